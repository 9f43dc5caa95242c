"""What the flight operations of both PX4-capable bridges (MAVLink, PX4 over Zenoh) read and wait
on, over their :class:`~dronewrapper_bridge_base.guided_core.GuidedCore`: whether the aircraft
flies (:func:`flying`) or is down (:func:`landed`), and the end of a return (:func:`returned`).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from dronewrapper.msgs.flight import REFUSED, TOO_LATE, FlightResult
from dronewrapper.msgs.mavros import LANDED_STATE_ON_GROUND
from dronewrapper_bridge_base.flight_request import failed
from dronewrapper_bridge_base.operation import Steps

if TYPE_CHECKING:
    from dronewrapper_bridge_base.guided_core import GuidedCore


def flying(core: GuidedCore) -> bool:
    """Armed and in the air (per the landed state)."""
    return core.failsafe.airborne and core.failsafe.armed


def landed(core: GuidedCore) -> bool:
    """On the ground and disarmed."""
    state = core.heartbeat_state
    return core.ext.landed_state == LANDED_STATE_ON_GROUND and state is not None and not state.armed


def returned(
    core: GuidedCore, modes: tuple[str, str], deadline: float, timeout: float, who: str
) -> Steps:
    """Wait until a return started in ``modes[0]`` (``modes[1]``: the landing it ends in) is on
    the ground and disarmed, by ``deadline`` (monotonic s; ``timeout`` s as asked); refused when
    ``who`` (the autopilot) leaves both modes while armed."""
    while not landed(core):
        hb = core.heartbeat_state
        if hb is not None and hb.armed and hb.mode not in modes:
            return failed(REFUSED, f"{who} left {modes[0]} for {hb.mode}", "return")
        if core.now >= deadline:
            return failed(TOO_LATE, f"not on the ground and disarmed after {timeout:g} s")
        yield deadline
    core.unattended.clear()
    return FlightResult(success=True, message="returned: on the ground and disarmed")
