"""The opening of a take-off on both PX4-capable bridges (MAVLink, PX4 over Zenoh), pure
(:func:`takeoff_start`): the request checked, the bridge's own answer when it cannot or need not
take off, the safety envelope's refusal, and the climb from where the aircraft is. What follows
(the modes, arming, the climb's watch) is each bridge's own. Positions local ENU m, yaw ENU rad,
time the core's (monotonic s).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import NamedTuple, Protocol

from dronewrapper.msgs import flight
from dronewrapper.runtime.errors import ServiceError
from dronewrapper_bridge_base.core_view import Clock
from dronewrapper_bridge_base.flight_request import failed, takeoff_heights, takeoff_request
from dronewrapper_bridge_base.guided_flight import Grounded

MAX_HEIGHT_M = 1000.0
"""The highest take-off these bridges fly (m above the take-off point)."""
MAX_TIMEOUT_S = 600.0
"""The longest a flight request on these bridges may ask to wait (s)."""


class Launching(Grounded, Clock, Protocol):
    """What :func:`takeoff_start` reads of a core besides the landed state and its time: where
    the aircraft is (local ENU m) and its yaw (ENU rad), None before a local position."""

    def pose(self) -> tuple[tuple[float, float, float], float] | None: ...


class Climb(NamedTuple):
    """A take-off's climb: from (``x``, ``y``, ``start_z``) up to ``target_z`` (local ENU m),
    facing ``yaw`` (ENU rad), ``height`` m as asked; reached within ``tolerance`` m by
    ``deadline`` (monotonic s), ``timeout`` s after the request."""

    x: float
    y: float
    yaw: float
    start_z: float
    target_z: float
    height: float
    tolerance: float
    deadline: float
    timeout: float


def takeoff_start(
    core: Launching,
    request: flight.TakeoffRequest,
    ready: Callable[[], flight.FlightResult | None],
    refuse: Callable[[float], object],
) -> Climb | flight.FlightResult:
    """The climb ``request`` asks for, or the answer it gets at once. A bad request is a
    ``ValueError``; then ``ready()`` is the bridge's own answer (not connected, already flying)
    or None; ``refuse(height)`` raises ServiceError naming the envelope's limit it breaks (a
    ``refused`` failure); with no local position there is no point to take off from."""
    height, timeout, tolerance = takeoff_request(
        request.height, request.timeout, request.tolerance, MAX_HEIGHT_M, MAX_TIMEOUT_S
    )
    answer = ready()
    if answer is not None:
        return answer
    try:
        refuse(height)
    except ServiceError as exc:
        return failed(flight.REFUSED, exc.message, "takeoff")
    pose = core.pose()
    if pose is None:
        return failed(flight.NO_POSITION, "no local position: no point to take off from")
    (x, y, z0), yaw = pose
    start_z, target_z = takeoff_heights(z0, core.ext.landed_state, height)
    deadline = core.now + timeout
    return Climb(x, y, yaw, start_z, target_z, height, tolerance, deadline, timeout)
