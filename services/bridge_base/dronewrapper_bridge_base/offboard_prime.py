"""Priming before OFFBOARD: PX4 leaves OFFBOARD at once unless setpoints already stream, so a
bridge streams for ``offboard_prime_s`` (the fresh setpoint, else a hold at the current pose)
before it asks for the mode. Shared by the bridges that fly PX4's OFFBOARD mode (over MAVLink
and over PX4's own Zenoh)."""

from __future__ import annotations

from collections.abc import Generator
from typing import Protocol

from dronewrapper.runtime.errors import ServiceError
from dronewrapper_bridge_base.core_view import Clock
from dronewrapper_bridge_base.guided_failsafe import Failsafe

PRIME_MARGIN_S = 2.0
"""How much longer than ``offboard_prime_s`` priming may take before it is refused."""


class _PrimeConfig(Protocol):
    offboard_prime_s: float  # s of streaming before OFFBOARD is asked for


class PrimingCore(Clock, Protocol):
    """What priming reads of a bridge's core besides its time."""

    @property
    def config(self) -> _PrimeConfig: ...
    @property
    def failsafe(self) -> Failsafe: ...
    def pose(self) -> tuple[tuple[float, float, float], float] | None: ...
    def streamed_for(self, now: float) -> float: ...


def prime(core: PrimingCore) -> Generator[float, None, None]:
    """Stream for > ``offboard_prime_s`` before OFFBOARD: the fresh setpoint, else a hold at
    the current pose (streamed by the core's tick). ServiceError when it cannot."""
    need = core.config.offboard_prime_s
    if core.streamed_for(core.now) >= need:
        return
    if core.pose() is None and core.failsafe.fresh_target(core.now) is None:
        raise ServiceError(
            "cannot enter OFFBOARD: no local position to hold and no setpoint stream", "refused"
        )
    core.failsafe.start_priming(core.now, need + PRIME_MARGIN_S)
    deadline = core.now + need + PRIME_MARGIN_S
    while core.streamed_for(core.now) < need:
        if core.now >= deadline:
            raise ServiceError("could not stream setpoints before OFFBOARD", "refused")
        yield deadline
