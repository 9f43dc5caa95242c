"""Waiting for real firmware to be ready to fly: arming allowed in its guided mode."""

from __future__ import annotations

import time

from dronewrapper import CommandRefused, DroneWrapper

READY_TIMEOUT_S = 180.0  # GNSS fix and the estimator's checks (ArduCopter: ~40 s)
GUIDED = {"px4": "OFFBOARD", "ardupilot": "GUIDED"}


def wait_ready(drone: DroneWrapper, kind: str) -> float:
    """Until the autopilot (``px4`` or ``ardupilot``) lets us arm in its guided mode: arm,
    disarm; returns the seconds it took (AssertionError after :data:`READY_TIMEOUT_S`)."""
    started = time.monotonic()
    last = ""
    while time.monotonic() - started < READY_TIMEOUT_S:
        try:
            drone.set_mode(GUIDED[kind])
            drone.arm()
            drone.disarm()
            return time.monotonic() - started
        except CommandRefused as exc:
            last = str(exc)
        time.sleep(2.0)
    raise AssertionError(f"{kind} not ready within {READY_TIMEOUT_S:g} s: {last}")
