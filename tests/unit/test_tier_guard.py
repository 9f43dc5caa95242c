"""The tiers' guard (tests/tier_guard.py) and the unit/service conftests that install it: a real
Zenoh session (zenoh.open, the runtime's Node) or a forbidden socket call fails the test with a
message naming the tier it belongs in, on the test's thread or any other; outside, all is as it
was. No session or packet is ever made: the guard fails before the real call."""

from __future__ import annotations

import contextlib
import importlib.util
import os
import re
import socket
import subprocess
import threading
from dataclasses import dataclass
from pathlib import Path

import pytest
import zenoh
from tier_guard import NETWORK, TRAFFIC, TierGuard, run_phase

from dronewrapper.runtime import Node, ZenohOptions
from support import Process

TESTS = Path(__file__).resolve().parents[1]
Failed = pytest.fail.Exception


@dataclass
class Item:
    """The one attribute of a pytest item the guard reads."""

    nodeid: str


def load_conftest(tier: str):
    """tests/<tier>/conftest.py as a module of its own (not the one pytest loaded)."""
    spec = importlib.util.spec_from_file_location(f"{tier}_conftest", TESTS / tier / "conftest.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_a_zenoh_session_fails_naming_the_tier_and_is_put_back_after():
    real_open = zenoh.open
    guard = TierGuard("service", sockets=NETWORK)
    with (
        guard.watching("tests/service/test_x.py::test_y") as seen,
        pytest.raises(Failed) as failure,
    ):
        zenoh.open(zenoh.Config())
    text = str(failure.value)
    assert text.startswith("tests/service/test_x.py::test_y opened a real Zenoh session")
    assert "tests/integration" in text and "fake bus" in text
    assert seen == [text]
    assert zenoh.open is real_open


def test_the_runtime_node_is_refused_before_any_session_opens():
    options = ZenohOptions(mode="client", connect=["tcp/127.0.0.1:9"], name="nobody")
    guard = TierGuard("unit", sockets=TRAFFIC)
    refused = pytest.raises(Failed, match="t::node opened a real Zenoh session")
    with guard.watching("t::node") as seen, refused:
        Node("nobody", options, handle_signals=False, open_timeout=0.0)
    assert len(seen) == 1 and "tests/unit is pure logic" in seen[0]


def test_service_tier_refuses_any_network_socket_but_not_a_local_pair():
    with TierGuard("service", sockets=NETWORK).watching("t::sock") as seen:
        with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as udp:
            with pytest.raises(Failed, match=r"used a network socket \(socket.bind"):
                udp.bind(("127.0.0.1", 0))
            with pytest.raises(Failed, match=r"socket\.sendto"):
                udp.sendto(b"x", ("127.0.0.1", 9))
        with pytest.raises(Failed, match=r"socket\.connect"):
            socket.create_connection(("127.0.0.1", 9), timeout=0.1)
        left, right = socket.socketpair()  # a local pipe is no network
        with left, right:
            left.sendall(b"ok")
            assert right.recv(2) == b"ok"
    assert len(seen) == 3
    assert "bind" not in socket.socket.__dict__  # the inherited method is back


def test_unit_tier_lets_a_port_be_probed_but_refuses_traffic():
    guard = TierGuard("unit", sockets=TRAFFIC)
    with guard.watching("t::probe"), socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as udp:
        udp.bind(("127.0.0.1", 0))  # the port allocator's probe
        with pytest.raises(Failed, match=r"socket\.sendto"):
            udp.sendto(b"x", udp.getsockname())


def test_a_process_is_refused_before_it_starts(tmp_path):
    log = tmp_path / "never.log"
    before = Process.__init__  # this test's own guard
    guard = TierGuard("service", sockets=NETWORK)
    with guard.watching("t::proc"), pytest.raises(Failed, match=r"started a process \(true x\)"):
        Process(["true", "x"], log)
    assert not log.exists()  # refused before its log was even opened
    assert Process.__init__ is before


@pytest.mark.parametrize(
    ("fixture", "what"),
    [("router", "asks for a real Zenoh router"), ("spawn", "asks to start processes")],
)
def test_the_router_and_spawn_fixtures_are_refused_naming_the_tier(request, fixture, what):
    with pytest.raises(Failed) as failure:
        request.getfixturevalue(fixture)  # this tier's conftest shadows the shared one
    text = str(failure.value)
    assert text.startswith(f"{request.node.nodeid} {what}")
    assert "belongs in tests/integration" in text
    assert hasattr(load_conftest("service"), fixture)  # the service tier shadows it too


def test_a_session_opened_on_another_thread_fails_the_phase():
    """A service's own thread opening a session: the thread swallows the failure, the phase
    still fails with the guard's message."""
    phase = run_phase(TierGuard("service", sockets=NETWORK), Item("t::thread"))
    next(phase)  # the phase runs from here

    def service_thread() -> None:
        with contextlib.suppress(BaseException):  # as a thread that logs and dies would
            zenoh.open(zenoh.Config())

    thread = threading.Thread(target=service_thread)
    thread.start()
    thread.join(5)
    with pytest.raises(Failed, match="t::thread opened a real Zenoh session"):
        phase.send(None)


def test_a_failure_the_violation_led_to_is_reported_as_the_violation():
    phase = run_phase(TierGuard("service", sockets=NETWORK), Item("t::led"))
    next(phase)
    with pytest.raises(Failed):
        zenoh.open(zenoh.Config())
    with pytest.raises(Failed, match="t::led opened a real Zenoh session"):
        phase.throw(AssertionError("timed out waiting for the bridge"))


@pytest.mark.parametrize(("tier", "sockets"), [("unit", TRAFFIC), ("service", NETWORK)])
@pytest.mark.parametrize("phase", ["runtest_setup", "runtest_call", "runtest_teardown"])
def test_each_tiers_conftest_guards_every_phase(tier, sockets, phase):
    conftest = load_conftest(tier)
    before = zenoh.open  # this test's own guard
    assert (conftest.GUARD.tier, conftest.GUARD.sockets) == (tier, sockets)
    hook = getattr(conftest, f"pytest_{phase}")
    args = (Item(f"tests/{tier}/test_x.py::test_y"),) + ((None,) if "teardown" in phase else ())
    wrapped = hook(*args)
    next(wrapped)
    with pytest.raises(Failed) as failure:
        zenoh.open(zenoh.Config())
    assert f"tests/{tier}/test_x.py::test_y opened a real Zenoh session" in str(failure.value)
    with pytest.raises(Failed):
        wrapped.throw(failure.value)
    assert zenoh.open is before


@pytest.mark.parametrize("tier", ["unit", "service"])
def test_each_tiers_conftest_fails_a_module_whose_import_opens_a_session(tier):
    """Collection (a test module's import-time code) is guarded too, even where the module
    swallows the failure."""
    hook = load_conftest(tier).pytest_make_collect_report(Item(f"tests/{tier}/test_x.py"))
    next(hook)
    with contextlib.suppress(Failed):
        zenoh.open(zenoh.Config())
    report = pytest.CollectReport(f"tests/{tier}/test_x.py", "passed", None, [])
    with pytest.raises(StopIteration) as done:
        hook.send(report)
    assert done.value.value is report and report.failed
    assert str(report.longrepr).startswith(f"tests/{tier}/test_x.py opened a real Zenoh session")


@pytest.mark.parametrize(
    ("start", "shown"),
    [
        (lambda: subprocess.run(["true", "run"], check=False), r"\(true run\)"),
        (lambda: subprocess.Popen(["true", "popen"]), r"\(true popen\)"),
        (lambda: subprocess.check_output("true shell", shell=True), r"\(true shell\)"),
        (lambda: os.system("true system"), r"\(os\.system true system\)"),
        (lambda: os.posix_spawn("/bin/true", ["true", "spawn"], {}), r"os\.posix_spawn true spawn"),
        (lambda: os.posix_spawnp("true", ["true", "spawnp"], {}), r"os\.posix_spawnp true spawnp"),
        (lambda: os.fork(), r"os\.fork"),
    ],
    ids=["run", "popen", "shell", "system", "posix_spawn", "posix_spawnp", "fork"],
)
@pytest.mark.parametrize(("tier", "sockets"), [("unit", TRAFFIC), ("service", NETWORK)])
def test_every_standard_way_to_start_a_process_is_refused(tier, sockets, start, shown):
    real = (subprocess.Popen.__init__, os.system, os.posix_spawn, os.fork)
    guard = TierGuard(tier, sockets=sockets)
    with guard.watching("t::spawn") as seen, pytest.raises(Failed, match=r"started a process"):
        start()
    assert len(seen) == 1 and re.search(shown, seen[0])
    assert (subprocess.Popen.__init__, os.system, os.posix_spawn, os.fork) == real


@pytest.mark.parametrize(("tier", "sockets"), [("unit", TRAFFIC), ("service", NETWORK)])
def test_sendmsg_on_a_network_socket_is_refused(tier, sockets):
    guard = TierGuard(tier, sockets=sockets)
    with (
        guard.watching("t::sendmsg") as seen,
        socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as udp,
        pytest.raises(Failed, match=r"socket\.sendmsg"),
    ):
        udp.sendmsg([b"x"], [], 0, ("127.0.0.1", 9))
    assert len(seen) == 1
