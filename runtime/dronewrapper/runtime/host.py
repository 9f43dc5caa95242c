"""Many services in one process: several ``run(node, config)`` on one Zenoh session.

    python -m dronewrapper.runtime.host -m dronewrapper_sim ARGS... -- -m MODULE ARGS... ...

Each member (``-m MODULE ARGS``, members separated by ``--``) is what ``python -m MODULE ARGS``
would run: its ``main(argv)`` (the module's own, else its ``__main__``'s), which parses its
flags and config and calls its ``run(node, config)`` through
:func:`~dronewrapper.runtime.service.run_service`, on a thread of its own. The members start
one after another, each once the one before is ready (its liveliness token declared) or has
ended, or after :data:`START_WAIT_S`: two members building the same config types at once
(msgspec's first conversion of a type) can block each other. Every member gets a
Node of its own (its namespace, its name, its liveliness token, its service workers, its stop
event), all on one Zenoh session that the first member's flags open; a member whose router
flags differ is refused. A fleet graph runs its drones so with ``per_process``
(``compose/dronewrapper_compose/launcher.py``).

What one process for N drones shares, and what it does not:

- shared: the interpreter, the imported modules (pymavlink's message tables, NumPy, msgspec,
  Zenoh's runtime: tens of MB that N processes each hold), one session to the router, the GIL;
- each member's own: its node and token, its config, its threads, its failsafe and commander
  lease (they live in its bridge), its sockets;
- shared timers: a member that ticks at a fixed rate may join the host's one thread for that
  rate (:func:`shared_ticker`, :mod:`~dronewrapper.runtime.ticker`) instead of waking a
  thread of its own: the MAVLink bridges' 30 Hz tick, one wake-up for all N of them. A tick
  that takes long delays its siblings' ticks of that period;
- a shared loop: a member that waits on sockets and deadlines may add them to the host's one
  :class:`~dronewrapper.runtime.poller.Poller` thread (:func:`shared_poller`) instead of a
  thread of its own: the simulated Iris' physics loops and the MAVLink bridges' UDP receive,
  so the host wakes once for all N sims' steps and once for all N bridges' datagrams. A call
  that takes long delays its siblings' calls of that round; an exception out of one ends that
  member alone (as below);
- a member that raises (an exception out of its ``run``) ends alone: run_service logs it and
  closes its node, which withdraws its liveliness token and undeclares its publishers,
  subscribers and services; its bridge threads stop with its node's stop event, so its
  autopilot no longer gets setpoints and falls to its own offboard-loss failsafe (PX4's
  ``COM_OF_LOSS_T``, which the simulated Iris follows), as when a bridge process dies. Its
  siblings carry on, and the host runs until the last member ends;
- what still takes every member down: the process dying (a segfault in a C extension, the
  kernel's OOM killer, ``os._exit``, SIGKILL), a member holding the GIL in a loop, or one
  member's leak exhausting the memory they share.

SIGINT/SIGTERM stop every member (a second one exits at once). Exit status: 0 when every member
ended cleanly, 1 when one failed, 2 for bad arguments.
"""

from __future__ import annotations

import dataclasses
import importlib
import logging
import os
import signal
import sys
import threading
import time
from collections.abc import Callable, Sequence
from typing import Any

from dronewrapper.runtime.options import ZenohOptions
from dronewrapper.runtime.poller import Poller
from dronewrapper.runtime.ticker import Ticker

log = logging.getLogger("host")

SEPARATOR = "--"
"""Separates two members on the host's command line."""
START_WAIT_S = 30.0
"""The longest a member waits for the one started before it to be ready (s)."""

_local = threading.local()


class Member:
    """One service hosted in this process: its module, its argv, and once started its node."""

    def __init__(self, host: Host, module: str, argv: list[str]) -> None:
        self.host = host
        self.module = module
        self.argv = argv
        self.node: Any = None
        self.code: int | None = None
        self.thread = threading.Thread(target=self._run, name=f"host-{module}", daemon=True)

    @property
    def label(self) -> str:
        """``NAMESPACE/NAME`` once its node is open, else its module."""
        node = self.node
        return f"{node.ns}/{node.name}" if node is not None else self.module

    def _run(self) -> None:
        _local.member = self
        try:
            self.code = int(main_of(self.module)(self.argv) or 0)
        except SystemExit as exc:  # argparse's errors and --help
            self.code = exc.code if isinstance(exc.code, int) else 2
        except BaseException:
            log.exception("%s failed", self.label)
            self.code = 1
        finally:
            _local.member = None
        if self.code != 0 and not self.host.stopping.is_set():
            others = sum(m.thread.is_alive() and m is not self for m in self.host.members)
            log.error("%s ended with code %s; %d other(s) carry on", self.label, self.code, others)

    def started(self) -> bool:
        """Its node announced itself (ready), or it has ended."""
        return self.code is not None or (self.node is not None and self.node.announced)

    def attach(self, node: Any) -> None:
        """Its node is open (called by run_service); stopped at once if the host is stopping."""
        self.node = node
        if self.host.stopping.is_set():
            node.stop()


def current() -> Member | None:
    """The member the calling thread runs (its run_service's), or None outside a host."""
    return getattr(_local, "member", None)


def shared_ticker(rate_hz: float) -> Ticker | None:
    """The host's one :class:`~dronewrapper.runtime.ticker.Ticker` at ``rate_hz`` for the
    calling member to join, or None outside a host (the caller then ticks on its own)."""
    member = current()
    return None if member is None else member.host.ticker(rate_hz)


def shared_poller() -> Poller | None:
    """The host's one :class:`~dronewrapper.runtime.poller.Poller` (its members' sockets and
    deadlines on one thread) for the calling member to add to, or None outside a host."""
    member = current()
    return None if member is None else member.host.poller()


def main_of(module: str) -> Callable[[list[str]], int | None]:
    """The entry point ``python -m module`` runs: ``module.main``, else ``module.__main__.main``."""
    mod = importlib.import_module(module)
    entry = getattr(mod, "main", None)
    if entry is None:
        entry = importlib.import_module(f"{module}.__main__").main
    return entry


class Host:
    """The members of one process and the session they share."""

    def __init__(self, members: Sequence[tuple[str, list[str]]]) -> None:
        self.members = [Member(self, module, argv) for module, argv in members]
        self.stopping = threading.Event()
        self._lock = threading.Lock()
        self._session: Any = None
        self._session_key: tuple[str, tuple[str, ...]] | None = None
        self._tickers: dict[float, Ticker] = {}
        self._poller: Poller | None = None

    def ticker(self, rate_hz: float) -> Ticker:
        """The members' shared ticker at ``rate_hz`` (made on first use)."""
        with self._lock:
            ticker = self._tickers.get(rate_hz)
            if ticker is None:
                ticker = self._tickers[rate_hz] = Ticker(rate_hz, name=f"tick-{rate_hz:g}Hz")
            return ticker

    def poller(self) -> Poller:
        """The members' shared poller (made on first use)."""
        with self._lock:
            if self._poller is None:
                self._poller = Poller(name="host-loop")
            return self._poller

    def session_for(self, options: ZenohOptions) -> Any:
        """The shared session, opened with the first caller's router flags.

        Raises:
            ValueError: ``options`` name another mode or router than the session's.
        """
        from dronewrapper.runtime.session import open_session

        key = (options.mode, tuple(options.connect))
        with self._lock:
            if self._session is None:
                self._session = open_session(dataclasses.replace(options, name="host"))
                self._session_key = key
            elif key != self._session_key:
                raise ValueError(
                    f"a hosted service joins the process's session ({self._session_key}); "
                    f"its flags ask for {key}"
                )
            return self._session

    def start(self) -> None:
        """Start the members in order, each once the one before is ready or has ended."""
        for member in self.members:
            main_of(member.module)  # imported here, one at a time
        for member in self.members:
            if self.stopping.is_set():
                break
            member.thread.start()
            deadline = time.monotonic() + START_WAIT_S
            while not member.started() and time.monotonic() < deadline:
                self.stopping.wait(0.02)

    def stop(self) -> None:
        """Stop every member (each closes its own node)."""
        self.stopping.set()
        for member in self.members:
            if member.node is not None:
                member.node.stop()

    def join(self) -> None:
        """Wait until every started member has ended."""
        for member in self.members:
            while member.thread.is_alive():
                member.thread.join(0.5)

    def close(self) -> None:
        """After the members: close the shared session."""
        if self._session is not None:
            self._session.close()

    @property
    def exit_code(self) -> int:
        """0 when every started member ended cleanly, else 1."""
        codes = [m.code for m in self.members if m.thread.ident is not None]
        return 0 if all(code == 0 for code in codes) else 1


def split_members(argv: Sequence[str]) -> list[tuple[str, list[str]]]:
    """``-m A x y -- -m B z`` -> ``[("A", ["x", "y"]), ("B", ["z"])]``.

    Raises:
        ValueError: a member does not start with ``-m MODULE``.
    """
    members, current_part = [], []
    for arg in [*argv, SEPARATOR]:
        if arg != SEPARATOR:
            current_part.append(arg)
            continue
        if len(current_part) < 2 or current_part[0] != "-m":
            raise ValueError(f"each member is -m MODULE [ARGS...], got {current_part!r}")
        members.append((current_part[1], current_part[2:]))
        current_part = []
    return members


def main(argv: Sequence[str] | None = None) -> int:
    """``python -m dronewrapper.runtime.host -m MODULE ARGS [-- -m MODULE ARGS ...]``."""
    argv = list(sys.argv[1:] if argv is None else argv)
    try:
        members = split_members(argv)
    except ValueError as exc:
        print(f"host: {exc}", file=sys.stderr)
        return 2
    host = Host(members)

    def on_signal(signum: int, _frame: object) -> None:
        if host.stopping.is_set():
            log.warning("second %s: exiting now", signal.Signals(signum).name)
            logging.shutdown()
            os._exit(128 + signum)
        host.stop()

    for sig in (signal.SIGINT, signal.SIGTERM):
        signal.signal(sig, on_signal)
    host.start()
    host.join()
    host.close()
    return host.exit_code


if __name__ == "__main__":  # run_service looks for its member in the imported module
    from dronewrapper.runtime.host import main as host_main

    raise SystemExit(host_main())
