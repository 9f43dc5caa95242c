"""A DroneWrapper's getters: the paper's reads of one drone's newest values (no I/O, no waiting).

Each reads a holder of the drone client's :class:`~dronewrapper.client.inputs.Inputs`: the
newest value, :class:`~dronewrapper.errors.NoData` before the first. Positions in local ENU
metres, velocities in body FLU or local ENU m/s, angles in radians (ENU, yaw counter-clockwise
positive), images as BGR ``uint8`` arrays.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from dronewrapper import telemetry
from dronewrapper.client.inputs import Inputs
from dronewrapper.msgs.link import LinkStatus
from dronewrapper.msgs.mavros import LANDED_STATE_IN_AIR, LANDED_STATE_TAKEOFF, State


class Getters:
    """The paper's getters over one drone's :class:`~dronewrapper.client.inputs.Inputs` (see
    the module doc); a part a DroneWrapper owns."""

    def __init__(self, inputs: Inputs) -> None:
        self.inputs = inputs

    def get_state(self) -> State:
        """The newest autopilot State (connected, armed, mode, autopilot, failsafe ...)."""
        return self.inputs.need(self.inputs.state, "state")

    def get_position(self) -> np.ndarray:
        """``np.array([x, y, z])``: position in local ENU metres (origin: the take-off point)."""
        return telemetry.position_of(self.inputs.need(self.inputs.pose, "local position"))

    def get_velocity(self) -> np.ndarray:
        """``np.array([vx, vy, vz])``: velocity in body FLU m/s (forward, left, up)."""
        return telemetry.linear_of(self.inputs.need(self.inputs.velocity_body, "body velocity"))

    def get_velocity_local(self) -> np.ndarray:
        """``np.array([vx, vy, vz])``: velocity in local ENU m/s (east, north, up)."""
        msg = self.inputs.need(self.inputs.velocity_local, "local velocity")
        return telemetry.linear_of(msg)

    def get_yaw_rate(self) -> float:
        """Yaw rate in rad/s, counter-clockwise positive."""
        msg = self.inputs.need(self.inputs.velocity_body, "body velocity")
        return telemetry.yaw_rate_of(msg)

    def get_orientation(self) -> np.ndarray:
        """``np.array([roll, pitch, yaw])`` in radians, ENU (yaw 0 = east, CCW positive)."""
        return telemetry.orientation_of(self.inputs.need(self.inputs.pose, "local position"))

    def get_roll(self) -> float:
        """Roll angle in radians."""
        return float(self.get_orientation()[0])

    def get_pitch(self) -> float:
        """Pitch angle in radians."""
        return float(self.get_orientation()[1])

    def get_yaw(self) -> float:
        """Yaw angle in radians, ENU: 0 facing east, counter-clockwise positive."""
        return float(self.get_orientation()[2])

    def get_landed_state(self) -> int:
        """MAVROS landed state: 0 undefined, 1 on ground, 2 in air, 3 taking off, 4 landing."""
        return int(self.inputs.need(self.inputs.extended, "extended state").landed_state)

    def get_battery(self) -> float:
        """Battery charge as a fraction 0..1 (NaN if the aircraft does not report it)."""
        return float(self.inputs.need(self.inputs.battery, "battery state").percentage)

    def get_link(self) -> LinkStatus:
        """The autopilot link as the bridge last reported it (about once a second): its load
        (``load``, 1.0 = a serial line full), rates, frames lost, reconnects; ``describe()``
        says ``link 94 % full (serial 57600 baud: 5.4 / 1.8 kB/s down/up), 0 lost, ...``.
        NoData when the bridge reports none (the Tello's)."""
        return self.inputs.need(self.inputs.link, "link status")

    def get_global_position(self) -> np.ndarray:
        """``np.array([latitude, longitude, altitude])``: degrees, degrees, metres AMSL.

        Raises NoData when the aircraft has no GPS (nothing published).
        """
        return telemetry.global_of(self.inputs.need(self.inputs.global_, "global position (GPS)"))

    def is_flying(self) -> bool:
        """True if the landed state is in the air or taking off."""
        extended = self.inputs.extended.value
        return extended is not None and extended.landed_state in (
            LANDED_STATE_IN_AIR,
            LANDED_STATE_TAKEOFF,
        )

    def age(self, what: str) -> float:
        """Seconds since the newest value of a getter's stream arrived (inf before the first).

        ``what`` names a getter without ``get_``: ``position``, ``orientation``, ``velocity``,
        ``velocity_local``, ``yaw_rate``, ``landed_state``, ``battery``, ``global_position``,
        ``state``, ``frontal_image``, ``ventral_image``.
        """
        return self.inputs.age(what)

    def get_image(self, camera: str = "frontal", *, with_stamp: bool = False) -> Any:
        """The newest frame of ``camera`` as a BGR ``uint8`` array (height, width, 3).

        Args:
            camera: ``frontal`` or ``ventral``.
            with_stamp: return ``(image, stamp)``, the stamp being the capture time in seconds
                since the Unix epoch (for latency measurements).

        Raises:
            NoData: no frame received yet (no camera running, or the camera was not
                requested in ``cameras=``).
        """
        return self.inputs.image(camera, with_stamp=with_stamp)

    def decode_image(self, msg: Any) -> np.ndarray:
        """A camera message (raw or JPEG, as this object receives them) as a BGR array."""
        return self.inputs.decode_image(msg)

    def get_frontal_image(self) -> np.ndarray:
        """The newest frontal camera frame, BGR ``uint8`` (height, width, 3)."""
        return self.get_image("frontal")

    def get_ventral_image(self) -> np.ndarray:
        """The newest ventral (downward) camera frame, BGR ``uint8`` (height, width, 3)."""
        return self.get_image("ventral")
