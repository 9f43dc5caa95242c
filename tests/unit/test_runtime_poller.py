"""The shared loop (dronewrapper.runtime.poller): many members' deadlines and sockets on one
thread, in virtual time, sockets stood in for by descriptors a fake readiness marks readable."""

from __future__ import annotations

import math
import threading
from collections.abc import Sequence

from dronewrapper.runtime.clock import VirtualClock
from dronewrapper.runtime.poller import NO_FILE, Poller


class Sockets:
    """Readiness on a virtual clock: a descriptor is readable once marked (``send``)."""

    def __init__(self, clock: VirtualClock) -> None:
        self.clock = clock
        self.waiting: set[int] = set()
        self.waits = 0

    def send(self, fd: int) -> None:
        self.waiting.add(fd)

    def wait(self, fds: Sequence[int], timeout: float) -> list[int]:
        ready = [fd for fd in fds if fd in self.waiting]
        if not ready and timeout > 0:
            self.waits += 1
            self.clock.sleep(timeout)
        return ready


class Sim:
    """Steps on a 50 Hz grid and 'sends' a datagram to its bridge's descriptor each step."""

    def __init__(self, sockets: Sockets, to_fd: int, clock: VirtualClock) -> None:
        self.sockets, self.to_fd, self.clock = sockets, to_fd, clock
        self.steps: list[float] = []
        self.threads: set[str] = set()
        self.fail_at: float | None = None

    def fileno(self) -> int:
        return NO_FILE

    def on_readable(self) -> None:
        raise AssertionError("no socket")

    def on_due(self, now: float) -> float:
        if self.fail_at is not None and now >= self.fail_at:
            raise RuntimeError("a sim's step failed")
        self.steps.append(now)
        self.threads.add(threading.current_thread().name)
        self.sockets.send(self.to_fd)
        return 0.02 * (math.floor(round(now / 0.02, 6)) + 1)


class Bridge:
    """Reads its descriptor when readable; notes the time of each read."""

    def __init__(self, sockets: Sockets, fd: int, clock: VirtualClock) -> None:
        self.sockets, self.fd, self.clock = sockets, fd, clock
        self.reads: list[float] = []
        self.reopen_in: float | None = None
        self.dues: list[float] = []

    def fileno(self) -> int:
        return self.fd

    def on_readable(self) -> float | None:
        self.sockets.waiting.discard(self.fd)
        self.reads.append(self.clock.monotonic())
        return None if self.reopen_in is None else self.clock.monotonic() + self.reopen_in

    def on_due(self, now: float) -> float:
        self.dues.append(now)
        return math.inf


def fleet(n: int) -> tuple[VirtualClock, Sockets, Poller, list[Sim], list[Bridge]]:
    clock = VirtualClock(monotonic=1000.0)
    sockets = Sockets(clock)
    poller = Poller(clock=clock, readiness=sockets)
    sims = [Sim(sockets, 100 + i, clock) for i in range(n)]
    bridges = [Bridge(sockets, 100 + i, clock) for i in range(n)]
    return clock, sockets, poller, sims, bridges


def test_members_step_together_and_their_datagrams_are_read_in_the_same_round():
    clock, sockets, poller, sims, bridges = fleet(3)
    stop = threading.Event()
    for sim, bridge in zip(sims, bridges, strict=True):
        poller.add(sim, stop, lambda exc: None, due=1000.02)
        poller.add(bridge, stop, lambda exc: None, due=math.inf)
    clock.run_for(1.001)
    for sim, bridge in zip(sims, bridges, strict=True):
        assert len(sim.steps) == 50  # 50 Hz, every sim on the same instants
        assert sim.steps == sims[0].steps
        assert bridge.reads == sim.steps  # read at once, no later wake-up
    assert {name for sim in sims for name in sim.threads} == {"poller"}
    assert sockets.waits <= 51  # one wait a period for all six members
    assert poller.errors == 0
    stop.set()


def test_a_failing_member_leaves_alone_and_the_others_go_on():
    clock, _sockets, poller, sims, bridges = fleet(2)
    stops = [threading.Event(), threading.Event()]
    failures: list[list[BaseException]] = [[], []]
    for i in range(2):
        poller.add(sims[i], stops[i], failures[i].append, due=1000.02)
        poller.add(bridges[i], stops[i], failures[i].append, due=math.inf)
    sims[0].fail_at = 1000.2
    clock.run_for(1.001)
    assert [type(f) for f in failures[0]] == [RuntimeError] and failures[1] == []
    assert stops[0].is_set() and not stops[1].is_set()
    assert max(sims[0].steps) < 1000.2 and len(sims[1].steps) == 50
    assert max(bridges[0].reads) < 1000.2 and len(bridges[1].reads) == 50
    assert poller.errors == 1
    assert poller.entries == 2  # the failed member's sim and bridge both left
    stops[1].set()


def test_a_member_leaves_when_stopped_and_the_thread_ends_with_the_last():
    clock, _sockets, poller, sims, _bridges = fleet(2)
    first, second = threading.Event(), threading.Event()
    poller.add(sims[0], first, lambda exc: None, due=1000.02)
    poller.add(sims[1], second, lambda exc: None, due=1000.02)
    clock.run_for(0.501)
    first.set()
    clock.run_for(0.5)
    assert len(sims[0].steps) == 25 and len(sims[1].steps) == 50
    second.set()
    clock.run_for(0.2)
    assert poller.entries == 0
    again = threading.Event()
    poller.add(sims[0], again, lambda exc: None)  # due at once; a new thread
    clock.run_for(0.101)
    assert len(sims[0].steps) == 25 + 6
    again.set()


def test_a_read_may_set_a_deadline_as_a_link_to_reopen_does():
    clock, sockets, poller, _sims, bridges = fleet(1)
    stop = threading.Event()
    bridge = bridges[0]
    bridge.reopen_in = 1.0
    poller.add(bridge, stop, lambda exc: None, due=math.inf)
    clock.run_for(0.1)
    sockets.send(bridge.fd)
    clock.run_for(0.05)
    assert len(bridge.reads) == 1
    clock.run_for(1.0)
    assert bridge.dues == [bridge.reads[0] + 1.0]
    stop.set()
