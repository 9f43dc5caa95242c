"""The test tiers' rule, enforced: unit and service tests open no real Zenoh session, no
network socket and start no process.

- ``tests/unit``: pure logic, milliseconds.
- ``tests/service``: one process's logic on the fake bus (``dronewrapper.runtime.fake``
  FakeBus/FakeNode), in injected time.
- ``tests/integration``: real processes and sessions on a loopback router, real sockets.

A tier's ``conftest.py`` wraps each test's setup, call and teardown, and the import of each test
module, in :meth:`TierGuard.watching`:
while it runs, ``zenoh.open`` (which the runtime's ``Node``, the SDK and the test router all go
through), starting a process (the tests' ``support.Process``, the ``spawn`` fixture's, and
every way the standard library starts one: ``subprocess.Popen``, which ``subprocess.run`` and
asyncio's subprocesses go through, ``os.system``, ``os.posix_spawn``/``posix_spawnp``,
``os.fork``) and the tier's forbidden calls on an IPv4/IPv6 socket (service: any; unit: those
that talk, ``connect``/``sendto``/``sendmsg``, as binding a loopback port to probe it is the
port allocator's logic) fail the test with a message naming the tier it belongs in. A violation
on another thread (a service's own thread opening a session) is remembered and fails the test at
the end of that phase. The tier's conftest also shadows the ``router`` and ``spawn`` fixtures
with ones that fail at once (:func:`refusing`).
"""

from __future__ import annotations

import contextlib
import os
import socket
import subprocess
import threading
from collections.abc import Iterator
from typing import Any

import pytest
import zenoh

import support

_WHERE = (
    "a wiring test (real router, session, socket, process) belongs in tests/integration; "
    "a logic test runs on the fake bus (dronewrapper.runtime.fake FakeBus/FakeNode, injected "
    "time) or on a pure core (tests/unit/bridge_core_rig.py)"
)
DEFINITIONS = {
    "unit": "tests/unit is pure logic (no session, no network, no process)",
    "service": (
        "tests/service is one process's logic on the fake bus (no session, no network, no process)"
    ),
}
_INET = (socket.AF_INET, socket.AF_INET6)
NETWORK = ("bind", "connect", "connect_ex", "sendto", "sendmsg")  # any use of a network socket
TRAFFIC = ("connect", "connect_ex", "sendto", "sendmsg")  # talking (binding to probe is not)
SPAWNERS = ("system", "posix_spawn", "posix_spawnp", "fork")  # ``os`` functions that start one


class TierGuard:
    """What a tier forbids (a real Zenoh session, and the network socket calls ``sockets``
    names) and the violations seen while :meth:`watching`."""

    def __init__(self, tier: str, *, sockets: tuple[str, ...]) -> None:
        self.tier = tier
        self.sockets = sockets
        self._lock = threading.Lock()

    def message(self, where: str, what: str) -> str:
        return f"{where} {what}: {DEFINITIONS[self.tier]}; {_WHERE}"

    @contextlib.contextmanager
    def watching(self, where: str) -> Iterator[list[str]]:
        """Forbid, while inside, what the tier forbids; yields the violations seen (a test
        may have caught the failure on its own thread, or it happened on another thread)."""
        seen: list[str] = []

        def forbid(what: str) -> None:
            text = self.message(where, what)
            with self._lock:
                seen.append(text)
            pytest.fail(text, pytrace=False)

        def no_session(*_args: Any, **_kwargs: Any) -> None:
            forbid("opened a real Zenoh session (zenoh.open)")

        def no_process(_process: Any, argv: Any, *_args: Any, **_kwargs: Any) -> None:
            shown = argv if isinstance(argv, str | bytes) else " ".join(map(str, argv))
            forbid(f"started a process ({shown})")

        with contextlib.ExitStack() as undo:
            undo.callback(setattr, zenoh, "open", zenoh.open)
            zenoh.open = no_session
            undo.callback(setattr, support.Process, "__init__", support.Process.__init__)
            support.Process.__init__ = no_process
            undo.callback(setattr, subprocess.Popen, "__init__", subprocess.Popen.__init__)
            subprocess.Popen.__init__ = no_process
            for name in SPAWNERS:
                if hasattr(os, name):
                    undo.callback(setattr, os, name, getattr(os, name))
                    setattr(os, name, _spawn_guarded(name, forbid))
            for name in self.sockets:
                undo.callback(_restore, name, socket.socket.__dict__.get(name))
                setattr(socket.socket, name, _network_guarded(name, forbid))
            yield seen


def _restore(name: str, own: Any) -> None:
    """Put back ``socket.socket``'s own attribute ``name``, or the inherited one."""
    if own is None:
        delattr(socket.socket, name)
    else:
        setattr(socket.socket, name, own)


def _spawn_guarded(name: str, forbid) -> Any:
    def guarded(*args: Any, **_kwargs: Any) -> None:
        shown = " ".join(map(str, args[1] if name.startswith("posix_spawn") else args))
        forbid(f"started a process (os.{name} {shown})".replace(" )", ")"))

    return guarded


def _network_guarded(name: str, forbid) -> Any:
    real = getattr(socket.socket, name)

    def guarded(sock: socket.socket, *args: Any, **kwargs: Any) -> Any:
        if sock.family in _INET:
            forbid(f"used a network socket (socket.{name} {args[-1] if args else ''})")
        return real(sock, *args, **kwargs)

    return guarded


def run_phase(guard: TierGuard, item: pytest.Item) -> Iterator[None]:
    """The body of a ``pytest_runtest_{setup,call,teardown}`` wrapper hook: the phase runs
    guarded; a violation it swallowed or saw on another thread fails it afterwards."""
    with guard.watching(item.nodeid) as seen:
        try:
            result = yield
        except (Exception, pytest.fail.Exception) as exc:
            if not seen or str(exc) in seen:
                raise
            pytest.fail(seen[0], pytrace=False)  # what it led to is chained below
    if seen:
        pytest.fail(seen[0], pytrace=False)
    return result


def collect(guard: TierGuard, collector: pytest.Collector) -> Iterator[pytest.CollectReport]:
    """The body of a ``pytest_make_collect_report`` wrapper hook: a test module's import-time
    code runs guarded; a violation it swallowed fails its collection."""
    with guard.watching(collector.nodeid) as seen:
        report = yield
    if seen and report.passed:
        report.outcome, report.longrepr = "failed", seen[0]
    return report


def refusing(guard: TierGuard, name: str, what: str) -> Any:
    """A fixture called ``name`` that fails the test asking for it, saying ``what`` it wanted
    and where such a test belongs (a tier's conftest shadows ``router``/``spawn`` with it)."""

    @pytest.fixture(name=name)
    def refused(request: pytest.FixtureRequest) -> None:
        pytest.fail(guard.message(request.node.nodeid, what), pytrace=False)

    return refused


def conftest_hooks(guard: TierGuard) -> dict[str, Any]:
    """Everything a tier's conftest declares, by name: the guarded phases and collection, and
    the ``router`` / ``spawn`` fixtures refused (``globals().update(conftest_hooks(GUARD))``)."""

    @pytest.hookimpl(wrapper=True)
    def pytest_runtest_setup(item):
        return (yield from run_phase(guard, item))

    @pytest.hookimpl(wrapper=True)
    def pytest_runtest_call(item):
        return (yield from run_phase(guard, item))

    @pytest.hookimpl(wrapper=True)
    def pytest_runtest_teardown(item, nextitem):
        return (yield from run_phase(guard, item))

    @pytest.hookimpl(wrapper=True)
    def pytest_make_collect_report(collector):
        return (yield from collect(guard, collector))

    return {
        "router": refusing(guard, "router", "asks for a real Zenoh router (the router fixture)"),
        "spawn": refusing(guard, "spawn", "asks to start processes (the spawn fixture)"),
        "pytest_runtest_setup": pytest_runtest_setup,
        "pytest_runtest_call": pytest_runtest_call,
        "pytest_runtest_teardown": pytest_runtest_teardown,
        "pytest_make_collect_report": pytest_make_collect_report,
    }
