"""Fuzz the controller's input: any Detections message, however broken, is either dropped by
the gate (counted, naming the field) or steered on, and a step never raises; every command is
finite and within the configured limits. (One ``header.stamp = inf`` used to kill it.)"""

from __future__ import annotations

import math

import pytest
from fuzz_inputs import detections
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from dronewrapper.msgs.vision import Detections
from dronewrapper_controller.config import ServoConfig
from dronewrapper_controller.inputs import DetectionsGate
from dronewrapper_controller.loop import ControlLoop

pytestmark = pytest.mark.fuzz

FUZZ = settings(
    max_examples=150,
    deadline=None,
    derandomize=True,
    database=None,
    suppress_health_check=[HealthCheck.too_slow],
)


@pytest.mark.parametrize("mode", ["follow_color", "follow_person"])
def test_no_detections_message_breaks_the_control_step(mode):
    config = ServoConfig(mode=mode)
    loop = ControlLoop(config)
    accepted: list[Detections] = []
    problems: list[str] = []
    gate = DetectionsGate(accepted.append, lambda n, why: problems.append(why))
    clock = [0.0]

    @FUZZ
    @given(msgs=st.lists(detections(), min_size=1, max_size=4))
    def step(msgs: list[Detections]) -> None:
        for msg in msgs:
            gate(msg)
            clock[0] += 0.05
            newest = accepted[-1] if accepted else None
            cmd = loop.tick(clock[0], newest, 0.0 if newest is msg else 1.0)
            if cmd is None:
                continue
            for value, limit in (
                (cmd.vx, config_limit(config, "vx")),
                (cmd.vz, config_limit(config, "vz")),
                (cmd.yaw_rate, config_limit(config, "yaw_rate")),
            ):
                assert math.isfinite(value) and abs(value) <= limit + 1e-9, cmd

    step()
    assert problems, "the generator never produced a bad message"
    assert all(any(word in why for word in ("must", "within")) for why in problems)


def config_limit(config: ServoConfig, axis: str) -> float:
    """The output bound of ``axis``; the search turn may exceed the yaw PID's."""
    if axis == "vx":
        section = config.follow_color if config.mode == "follow_color" else config.follow_person
        return section.vx.out_limit
    limit = getattr(config, axis).out_limit
    return max(limit, config.search_yaw_rate) if axis == "yaw_rate" else limit
