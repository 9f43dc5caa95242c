"""The node side of a pure core: inputs fed under one lock with the time, effects executed
after it, and a service call waiting on its operation until it ends or the node stops."""

from __future__ import annotations

import logging
import threading

import pytest

from dronewrapper.runtime.core_driver import CoreDriver, PureCore
from dronewrapper.runtime.errors import ServiceError
from dronewrapper.runtime.operation import Steps


class EchoCore(PureCore):
    """Answers an operation when told; queues every input in its outbox (a list)."""

    def __init__(self) -> None:
        super().__init__(0.0, list, logging.getLogger("test"))
        self.answer: str | None = None

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
    drivers.append(CoreDriver(core, execute, threading.Event(), clock=lambda: 5.0, wall=lambda: 9))
    assert drivers[0].feed(core.on_input, "hello") == "fed"
    assert executed == [([("hello", 5.0, 9)], True)]


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
