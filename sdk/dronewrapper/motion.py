"""A DroneWrapper's setpoints: position, velocity and mixed commands, streamed until changed.

Each ``set_cmd_*`` checks its arguments (finite numbers, yaw within a turn), builds the
PositionTarget (local ENU positions in metres, body FLU velocities in m/s, yaw in rad, yaw rate
in rad/s CCW positive), checks it against the bridge's envelope the wrapper holds (a target
outside it raises CommandRefused naming the limit, and nothing is sent) and hands it to the
drone client's setpoint stream, which publishes it at once and repeats it at the stream rate on
its own thread (:mod:`dronewrapper.client.stream`). What the bridge refuses later (the command
lease, a late setpoint, an envelope the wrapper did not hold yet) arrives on the wrapper's
``refusals``.
"""

from __future__ import annotations

import logging
from collections.abc import Callable

from dronewrapper import setpoints, telemetry
from dronewrapper.client import DroneClient
from dronewrapper.errors import NoData, NotConnected
from dronewrapper.msgs.mavros import (
    LANDED_STATE_ON_GROUND,
    MASK_MIXED,
    MASK_POSITION,
    PositionTarget,
)

log = logging.getLogger("dronewrapper")


class Motion:
    """The setpoint commands of one drone (see the module doc); a part a DroneWrapper owns.

    Args:
        client: the drone client (its inputs, clock and setpoint stream).
        check: ``check(target, what)`` raises CommandRefused for a target outside the
            envelope held (:meth:`dronewrapper.envelope_guard.EnvelopeGuard.check_setpoint`).
    """

    def __init__(self, client: DroneClient, check: Callable[[PositionTarget, str], None]) -> None:
        self.client = client
        self.ns = client.ns
        self.clock = client.clock
        self.inputs = client.inputs
        self._check_setpoint = check
        self._warned_grounded = False

    def set_cmd_pos(
        self,
        x: float = 0.0,
        y: float = 0.0,
        z: float | None = None,
        az: float | None = None,
        *,
        stamp: float | None = None,
    ) -> None:
        """Position control: fly to (x, y, z) local ENU metres facing yaw ``az`` (rad, ENU).

        Left out, ``z`` keeps the altitude (the one being commanded, else the current one) and
        ``az`` keeps the heading, so ``set_cmd_pos(1, 0)`` moves sideways instead of diving to
        the ground and turning east. Re-published at the stream rate until another command or
        :meth:`stop_commanding`. ``stamp`` (seconds since the Unix epoch) is carried in
        ``header.stamp`` (default now).

        Raises:
            InvalidArgument: an argument is not a finite number, or ``az`` is beyond a full turn
                (degrees by mistake); nothing is sent.
            NoData: ``z`` or ``az`` left out before any position arrived.
            CommandRefused: the point is outside the bridge's envelope (``limit`` names the
                envelope's field); nothing is sent.
        """
        stamp = setpoints.check_stamp(stamp, self.clock.time())
        z = self._kept_altitude("set_cmd_pos") if z is None else z
        az = self._kept_yaw("set_cmd_pos") if az is None else az
        target = setpoints.position_target(x, y, z, az, stamp=stamp)
        self._command(target, "set_cmd_pos")

    def set_cmd_vel(
        self,
        vx: float = 0.0,
        vy: float = 0.0,
        vz: float = 0.0,
        az: float = 0.0,
        *,
        stamp: float | None = None,
    ) -> None:
        """Velocity control: body FLU velocity (m/s) and yaw rate ``az`` (rad/s, CCW +).

        ``vx`` is forward, ``vy`` left, ``vz`` up on every aircraft. Re-published at the
        stream rate until changed: ``set_cmd_vel(az=1); sleep(5)`` spins for 5 s.

        Raises:
            InvalidArgument: an argument is not a finite number, or ``az`` is beyond a full turn
                per second (degrees by mistake); nothing is sent.
            CommandRefused: faster than the bridge's envelope allows (``limit`` names it).
        """
        stamp = setpoints.check_stamp(stamp, self.clock.time())
        target = setpoints.velocity_target(vx, vy, vz, az, stamp=stamp)
        self._command(target, "set_cmd_vel")

    def set_cmd_mix(
        self,
        vx: float = 0.0,
        vy: float = 0.0,
        z: float | None = None,
        az: float = 0.0,
        *,
        stamp: float | None = None,
    ) -> None:
        """Mixed control: body FLU vx, vy (m/s), altitude ``z`` (local ENU m), yaw rate (rad/s).

        Left out, ``z`` keeps the altitude (the one being commanded, else the current one).

        Raises:
            InvalidArgument: an argument is not a finite number (nothing is sent).
            NoData: ``z`` left out before any position arrived.
            CommandRefused: above or faster than the bridge's envelope allows (``limit``).
        """
        stamp = setpoints.check_stamp(stamp, self.clock.time())
        z = self._kept_altitude("set_cmd_mix") if z is None else z
        target = setpoints.mixed_target(vx, vy, z, az, stamp=stamp)
        self._command(target, "set_cmd_mix")

    def _kept_altitude(self, what: str) -> float:
        """The altitude a setpoint without ``z`` keeps: the commanded one, else the current."""
        commanded = self.client.target
        if commanded is not None and commanded.type_mask in (MASK_POSITION, MASK_MIXED):
            return float(commanded.required_position().z)
        pose = self.inputs.pose.value
        if pose is None:
            raise NoData(f"{what}: z left out, and no position yet to keep the altitude of")
        return float(pose.pose.position.z)

    def _kept_yaw(self, what: str) -> float:
        """The heading a position setpoint without ``az`` keeps: the commanded, else current."""
        commanded = self.client.target
        if commanded is not None and commanded.type_mask == MASK_POSITION:
            return float(commanded.yaw)
        pose = self.inputs.pose.value
        if pose is None:
            raise NoData(f"{what}: az left out, and no attitude yet to keep the heading of")
        return float(telemetry.orientation_of(pose)[2])

    def _warn_if_grounded(self, what: str) -> None:
        """Say once per landing that setpoints do nothing to a disarmed drone on the ground."""
        state, extended = self.inputs.state.value, self.inputs.extended.value
        grounded = (
            state is not None
            and not state.armed
            and extended is not None
            and extended.landed_state == LANDED_STATE_ON_GROUND
        )
        if grounded and not self._warned_grounded:
            self._warned_grounded = True
            log.warning(
                "%s: drone %r is disarmed on the ground, so nothing moves until takeoff()",
                what,
                self.ns,
            )
        elif not grounded:
            self._warned_grounded = False

    def _command(self, target: PositionTarget, what: str) -> None:
        """Stream ``target`` once it is inside the envelope held (CommandRefused if not),
        warning when the drone is disarmed on the ground."""
        self._check_setpoint(target, what)
        self._warn_if_grounded(what)
        if self.client.closed:
            raise NotConnected(f"DroneWrapper {self.ns!r} is closed")
        self.client.set(target)

    def stop_commanding(self) -> None:
        """Stop the setpoint stream. The bridge hovers after its ``setpoint_timeout``."""
        self.client.stop()
