"""What every bridge core shares: inputs fed under one lock with the time, effects executed
after it, a service call waiting on its operation until it ends or the node stops, and the
commander lease applied in the core (holder only, take-over, lapse, off)."""

from __future__ import annotations

import itertools
import logging
import threading

import pytest

from dronewrapper.msgs.lease import LeaseRequest
from dronewrapper.runtime.clock import VirtualClock
from dronewrapper.runtime.errors import ServiceError
from dronewrapper_bridge_base.core_driver import CoreDriver, PureCore
from dronewrapper_bridge_base.operation import Steps


class Outbox(list):
    """EchoCore's outbox: the inputs in order, and the samples published (``samples``)."""

    def __init__(self) -> None:
        super().__init__()
        self.samples: list = []


class EchoCore(PureCore):
    """Answers an operation when told; queues every input in its outbox (a list), and the
    commander shown on each State it publishes."""

    def __init__(self, lease_ttl_s: float | None = None) -> None:
        super().__init__(0.0, Outbox, logging.getLogger("test"), lease_ttl_s=lease_ttl_s)
        self.answer: str | None = None
        self.states: list[str] = []

    def publish_state(self, *, force: bool = False) -> None:
        self.states.append(self.commander)

    def on_answer(self, text: str, now: float, stamp: float) -> None:
        """An input that ends the waiting operation at once (as a bridge's replies do)."""
        self.on_input(text, now, stamp)
        self.advance(now, stamp)

    def on_setpoint(self, commander: str, now: float, stamp: float) -> bool:
        self._at(now, stamp)
        return self.admit_setpoint(commander)

    def on_input(self, text: str, now: float, stamp: float) -> str:
        self.out.append((text, now, stamp))
        self.answer = text
        return "fed"


def wait_for_answer(core: EchoCore) -> Steps:
    while core.answer is None:
        yield core.now + 10.0  # woken by inputs, not by time
    return core.answer


def lock_is_free(cond: threading.Condition) -> bool:
    """Whether another thread could take ``cond``'s lock now (it is reentrant for ours)."""
    free: list[bool] = []

    def probe() -> None:
        got = cond.acquire(blocking=False)
        free.append(got)
        if got:
            cond.release()

    thread = threading.Thread(target=probe)
    thread.start()
    thread.join()
    return free[0]


def test_inputs_get_the_time_and_effects_run_outside_the_lock():
    executed: list = []
    drivers: list[CoreDriver] = []

    def execute(out: list) -> None:
        executed.append((out, lock_is_free(drivers[0].cond)))

    core = EchoCore()
    clock = VirtualClock(monotonic=5.0, time=9.0)
    drivers.append(CoreDriver(core, execute, threading.Event(), clock=clock))
    assert drivers[0].feed(core.on_input, "hello") == "fed"
    assert executed == [([("hello", 5.0, 9.0)], True)]


def test_a_call_waits_on_the_drivers_clock():
    """An operation that ends by time (a timeout) ends in the clock's time: on a virtual
    clock the caller's wait moves it, and the core is fed each moment it was resumed at."""
    core = EchoCore()
    clock = VirtualClock(monotonic=100.0, time=1_700_000_000.0)
    driver = CoreDriver(core, lambda out: None, threading.Event(), clock=clock)
    resumed: list[float] = []

    def time_out() -> Steps:
        deadline = core.now + 2.0
        while core.now < deadline:
            resumed.append(core.now)
            yield deadline
        return core.now, core.stamp

    ended, stamp = driver.call(time_out())  # waits of 1 ms at least, as in real time
    assert 102.0 <= ended == clock.monotonic() < 102.002
    assert stamp == clock.time()
    assert resumed[0] == 100.0 and resumed == sorted(resumed) and resumed[-1] < 102.0
    assert all(b - a <= 0.05 + 1e-9 for a, b in itertools.pairwise(resumed))


def test_a_call_returns_when_another_threads_input_ends_its_operation():
    core = EchoCore()
    driver = CoreDriver(core, lambda out: None, threading.Event())
    started = threading.Event()

    def operation() -> Steps:
        started.set()  # the call runs its operation: the input may come now
        return (yield from wait_for_answer(core))

    feeder = threading.Thread(
        target=lambda: started.wait(10) and driver.feed(core.on_input, "ok"), daemon=True
    )
    feeder.start()
    assert driver.call(operation()) == "ok"
    feeder.join(10)
    assert core.operations.finished == 1 and len(core.operations) == 0


def test_a_reply_never_overtakes_the_effects_of_the_input_that_ended_it():
    """The State that shows a landing is published before the landing's reply goes out."""
    core = EchoCore()
    executing, release, order = threading.Event(), threading.Event(), []

    def execute(out: list) -> None:
        if out:  # the input's effects: slow to publish
            executing.set()
            release.wait(5.0)
            order.append("effects")

    driver = CoreDriver(core, execute, threading.Event())
    feeder = threading.Thread(target=driver.feed, args=(core.on_answer, "ok"))
    caller = threading.Thread(target=lambda: order.append(driver.call(wait_for_answer(core))))
    caller.start()
    feeder.start()
    assert executing.wait(5.0)
    caller.join(0.2)  # the operation has ended; its reply must wait for the effects
    release.set()
    feeder.join(5.0)
    caller.join(5.0)
    assert order == ["effects", "ok"]


def test_a_call_is_cancelled_when_the_node_stops():
    core = EchoCore()
    stop = threading.Event()
    stop.set()
    driver = CoreDriver(core, lambda out: None, stop)
    with pytest.raises(ServiceError, match="stopping"):
        driver.call(wait_for_answer(core))
    assert len(core.operations) == 0


def test_a_bad_request_fails_at_once_and_a_background_failure_is_logged(caplog):
    core = EchoCore()

    def refuse() -> Steps:
        raise ValueError("altitude must be > 0")
        yield 0.0

    op = core.operations.start(refuse())
    assert op.done and isinstance(op.error, ValueError)
    with caplog.at_level(logging.ERROR, logger="test"):
        core.operations.start(refuse(), background=True)
    assert "refuse failed: altitude must be > 0" in caplog.text


def command(core: EchoCore, commander: str, now: float, what: str = "arming"):
    """A command request from ``commander`` at ``now``: its operation (done at once)."""

    def steps() -> Steps:
        return "ran"
        yield 0.0

    return core.request(steps(), commander, what, now, now)


def test_the_lease_off_obeys_everyone():
    core = EchoCore()
    assert core.on_setpoint("alice", 1.0, 1.0) and core.on_setpoint("bob", 1.0, 1.0)
    assert command(core, "bob", 2.0).result() == "ran"
    assert core.on_lease_request(LeaseRequest(action="take"), "bob", 3.0, 3.0).granted
    assert core.commander == "" and core.states == []


def test_the_lease_obeys_its_holder_until_taken_over_or_lapsed():
    core = EchoCore(lease_ttl_s=10.0)
    assert core.on_setpoint("alice", 100.0, 0.0)
    assert core.states == ["alice"]  # State shows the new holder at once
    assert not core.on_setpoint("carol", 101.0, 0.0)
    refused = command(core, "carol", 101.0)
    with pytest.raises(ServiceError, match="'alice' holds the command lease") as error:
        refused.result()
    assert error.value.code == "lease" and refused.name == "_refused"
    assert command(core, "carol", 101.0, what="").result() == "ran"  # a read is never refused
    assert not core.on_lease_request(LeaseRequest(action="take"), "carol", 102.0, 0.0).granted
    reply = core.on_lease_request(LeaseRequest(action="take_over"), "carol", 102.0, 0.0)
    assert (reply.granted, reply.holder, reply.previous) == (True, "carol", "alice")
    assert core.states == ["alice", "carol"]
    assert (core.lease.refused_setpoints, core.lease.refused_commands) == (1, 1)
    assert not core.on_setpoint("alice", 103.0, 0.0)
    core._at(112.0, 0.0)  # carol silent for the ttl: the lease lapses
    core.show_commander()
    assert core.states[-1] == ""
    assert core.on_setpoint("alice", 112.0, 0.0) and core.commander == "alice"
    with pytest.raises(ValueError, match="action"):
        core.on_lease_request(LeaseRequest(action="steal"), "alice", 113.0, 0.0)
    assert core.on_lease_request(LeaseRequest(action="release"), "alice", 113.0, 0.0).granted
    assert core.commander == ""


def test_commands_without_a_name_are_one_anonymous_commander():
    core = EchoCore(lease_ttl_s=10.0)
    assert core.on_setpoint("", 1.0, 0.0)  # e.g. the on-board controller (no attachment)
    assert core.commander == "anonymous"
    assert not core.on_setpoint("alice", 2.0, 0.0)
