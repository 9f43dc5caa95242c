"""bridge_base.guided_flight's mode command and failsafe request, shared by both PX4-capable
bridges: the failsafe hears of the mode before the command goes out; the core takes note of the
mode only once the command is accepted."""

from __future__ import annotations

import logging

import pytest

from dronewrapper_bridge_base.guided_flight import ACCEPTED, failsafe_request, mode_command

DENIED = 2  # MAV_RESULT_DENIED


class Core:
    """A core as :func:`mode_command` sees it, keeping the order of what it is told."""

    def __init__(self) -> None:
        self.now = 7.0
        self.events: list[tuple[str, str]] = []
        self.failsafe = self

    def on_mode_requested(self, mode: str, now: float) -> None:
        assert now == self.now
        self.events.append(("requested", mode))

    def mode_entered(self, mode: str) -> None:
        self.events.append(("entered", mode))


def sent(core: Core, result: int):
    core.events.append(("sent", ""))
    yield core.now + 0.5
    return result, f"result {result}"


def run(steps):
    try:
        while True:
            next(steps)
    except StopIteration as done:
        return done.value


def test_an_accepted_mode_command_is_requested_first_and_entered_after():
    core = Core()
    assert run(mode_command(core, "AUTO.LAND", sent(core, ACCEPTED))) == (ACCEPTED, "result 0")
    assert core.events == [("requested", "AUTO.LAND"), ("sent", ""), ("entered", "AUTO.LAND")]


def test_a_refused_mode_command_is_not_entered():
    core = Core()
    assert run(mode_command(core, "AUTO.RTL", sent(core, DENIED))) == (DENIED, "result 2")
    assert ("entered", "AUTO.RTL") not in core.events


@pytest.mark.parametrize(
    ("result", "level"), [(ACCEPTED, logging.WARNING), (DENIED, logging.ERROR)]
)
def test_a_failsafe_request_logs_its_outcome_and_returns_the_result(result, level, caplog):
    core, log = Core(), logging.getLogger("test_guided_mode_command")
    with caplog.at_level(logging.WARNING, logger=log.name):
        steps = failsafe_request(core, "land", "AUTO.LAND", sent(core, result), "PX4", log)
        assert run(steps) == result
    assert [r.levelno for r in caplog.records] == [level]
    assert (("entered", "AUTO.LAND") in core.events) == (result == ACCEPTED)
