"""Take-off and landing, each one waiting operation, flown the Tello's way (pure).

- take-off: ``takeoff`` (the Tello's own, which ends hovering near 1 m), then ``up``/``down`` to
  the height asked (:func:`~dronewrapper_bridge_tello.operations.move_to_height`). Already
  flying: done at once, nothing sent.
- landing: ``land``, answered by the Tello once on the ground.

Each returns a :class:`~dronewrapper.msgs.flight.FlightResult` (a failure says which step and
why); a bad request is a ``ValueError``. Heights in metres above the take-off point, time the
core's (monotonic s): a step that ends after the request's ``timeout`` makes it too late.
"""

from __future__ import annotations

import math
from typing import Protocol

from dronewrapper.msgs import flight
from dronewrapper.msgs.mavros import LANDED_STATE_IN_AIR, LANDED_STATE_ON_GROUND, CommandTOL
from dronewrapper.runtime.errors import ServiceError
from dronewrapper_bridge_base.flight_request import checked, failed
from dronewrapper_bridge_base.operation import Steps
from dronewrapper_bridge_tello import missions
from dronewrapper_bridge_tello import operations as ops


class FlightPort(ops.OperationPort, Protocol):
    """What take-off and landing use of the core besides the operations they run
    (:class:`~.operations.OperationPort`): whether the Tello is connected."""

    connected: bool


MAX_HEIGHT_M = 30.0
MAX_TIMEOUT_S = 600.0


def height_now(core: FlightPort) -> float:
    return (core.telemetry.position_enu or (math.nan,) * 3)[2]


def takeoff_to(core: FlightPort, request: flight.TakeoffRequest) -> Steps:
    """Take off to ``request.height`` m above the take-off point (see module docstring)."""
    height = checked("height", request.height, 0.0, MAX_HEIGHT_M)
    deadline = core.now + checked("timeout", request.timeout, 0.0, MAX_TIMEOUT_S)
    if not core.connected:
        return failed(flight.NOT_READY, "the Tello is not connected (no state string)")
    if core.telemetry.landed.state == LANDED_STATE_IN_AIR:
        return flight.FlightResult(
            success=True,
            message=f"already flying (z={height_now(core):.2f} m): nothing done; a position "
            "setpoint changes the altitude",
        )
    try:  # above the safety envelope: refused, the limit named
        missions.refuse_takeoff(core.missions.envelope, height)
    except ServiceError as exc:
        return failed(flight.REFUSED, exc.message, "takeoff")
    reply = yield from ops.takeoff(core, CommandTOL.takeoff())
    if not reply.success:
        return failed(flight.REFUSED, reply.message, "takeoff", reply.result)
    result, message, move = yield from ops.move_to_height(core, height)
    if result != ops.MAV_RESULT_ACCEPTED:
        return failed(flight.REFUSED, message, move, result)
    z = yield from ops.settled_height(core)
    if core.now > deadline:
        return failed(flight.TOO_LATE, f"{message}, at {z:.2f} m only after {request.timeout:g} s")
    return flight.FlightResult(success=True, message=f"took off: {message}", height=z)


def land_here(core: FlightPort, request: flight.LandRequest) -> Steps:
    """``land`` here; done once the Tello says it is on the ground."""
    checked("timeout", request.timeout, 0.0, MAX_TIMEOUT_S)
    if not core.connected:
        return failed(flight.NOT_READY, "the Tello is not connected (no state string)")
    if core.telemetry.landed.state == LANDED_STATE_ON_GROUND:
        return flight.FlightResult(success=True, message="already on the ground")
    reply = yield from ops.land(core, CommandTOL.land())
    if not reply.success:
        return failed(flight.REFUSED, reply.message, "land", reply.result)
    return flight.FlightResult(success=True, message="on the ground, motors off")
