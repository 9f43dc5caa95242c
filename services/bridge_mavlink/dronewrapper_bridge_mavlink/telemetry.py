"""MAVLink telemetry -> DroneWrapper messages (MAVROS-equivalent), as pure conversions.

:class:`Telemetry` keeps the latest attitude, rates and fix so each incoming message can be
turned into the messages MAVROS would publish. Every method takes the pymavlink message and
the wall-clock receive time (``stamp``, float s since the epoch) and returns messages; nothing
here does I/O or reads a clock.

Frames: local ENU (``map``), body FLU (``base_link``); see :mod:`.frames`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

from pymavlink.dialects.v20.common import (
    MAV_AUTOPILOT_INVALID,
    MAV_MODE_FLAG_MANUAL_INPUT_ENABLED,
    MAV_MODE_FLAG_SAFETY_ARMED,
    MAV_TYPE_GCS,
)

from dronewrapper.msgs.geometry import PoseStamped, TwistStamped, Vector3
from dronewrapper.msgs.mavros import (
    LANDED_STATE_UNDEFINED,
    VTOL_STATE_UNDEFINED,
    ExtendedState,
    State,
    StatusText,
)
from dronewrapper.msgs.sensor import (
    COVARIANCE_TYPE_UNKNOWN,
    NAVSAT_STATUS_FIX,
    BatteryState,
    NavSatFix,
    NavSatStatus,
)
from dronewrapper.msgs.std import Header
from dronewrapper_bridge_base.frames import (
    Quat,
    attitude_ned_frd_to_enu_flu,
    frd_to_flu,
    ned_to_enu,
    quat_from_rpy,
    rotate,
    rpy_from_quat,
)
from dronewrapper_bridge_base.odometry import FRAME_BASE_LINK, Headers, odometry
from dronewrapper_bridge_mavlink.modes import autopilot_kind, is_guided, mode_name

UINT16_MAX = 65535
GPS_FIX_TYPE_3D = 3

FRAME_MAP = "map"


def is_autopilot_heartbeat(msg: Any) -> bool:
    """True for a HEARTBEAT sent by an autopilot (not a GCS, companion or other peer)."""
    return msg.autopilot != MAV_AUTOPILOT_INVALID and msg.type != MAV_TYPE_GCS


def state_from_heartbeat(msg: Any, stamp: float, *, failsafe: str = "") -> State:
    """An autopilot HEARTBEAT as State (mode name, armed, guided, autopilot kind)."""
    kind = autopilot_kind(msg.autopilot)
    mode = mode_name(kind, msg.custom_mode)
    return State(
        header=Header(stamp=stamp),
        connected=True,
        armed=bool(msg.base_mode & MAV_MODE_FLAG_SAFETY_ARMED),
        guided=is_guided(mode),
        manual_input=bool(msg.base_mode & MAV_MODE_FLAG_MANUAL_INPUT_ENABLED),
        mode=mode,
        system_status=int(msg.system_status),
        autopilot=kind,
        failsafe=failsafe,
    )


def extended_state(msg: Any, stamp: float) -> ExtendedState:
    """EXTENDED_SYS_STATE as ExtendedState (landed_state and vtol_state are MAVLink values)."""
    return ExtendedState(
        header=Header(stamp=stamp),
        vtol_state=int(getattr(msg, "vtol_state", VTOL_STATE_UNDEFINED)),
        landed_state=int(getattr(msg, "landed_state", LANDED_STATE_UNDEFINED)),
    )


def _fraction(remaining_percent: int) -> float:
    return float("nan") if remaining_percent < 0 else remaining_percent / 100.0


def battery_from_sys_status(msg: Any, stamp: float) -> BatteryState:
    """SYS_STATUS's battery fields as BatteryState (percentage 0..1, V, A; NaN if unknown)."""
    voltage = float("nan") if msg.voltage_battery in (UINT16_MAX, 0) else msg.voltage_battery / 1e3
    return _battery(msg, voltage, stamp)


def battery_from_battery_status(msg: Any, stamp: float) -> BatteryState:
    """BATTERY_STATUS as BatteryState (voltage = sum of the reported cells)."""
    cells = [v for v in msg.voltages if v != UINT16_MAX]
    return _battery(msg, sum(cells) / 1e3 if cells else float("nan"), stamp)


def _battery(msg: Any, voltage: float, stamp: float) -> BatteryState:
    """A BatteryState of ``voltage`` (V) and the current (cA -> A) and remaining charge (%)
    both battery messages carry under the same names (-1: unknown, NaN)."""
    current = float("nan") if msg.current_battery < 0 else msg.current_battery / 100.0
    return BatteryState(
        header=Header(stamp=stamp),
        voltage=voltage,
        current=current,
        percentage=_fraction(msg.battery_remaining),
    )


@dataclass
class Telemetry:
    """The latest attitude / fix, and the conversions that need them.

    Attributes:
        attitude: body FLU in local ENU (x, y, z, w), identity until the first attitude.
        rates_flu: body angular rates (rad/s, FLU).
        position_enu: last local position (m, ENU), None before the first.
        velocity_enu: last local velocity (m/s, ENU).
        gps_fix_type: GPS_RAW_INT.fix_type seen last, None if no GPS_RAW_INT yet.
        home_amsl: altitude of the home position above mean sea level (m), None if unknown.
    """

    attitude: Quat = (0.0, 0.0, 0.0, 1.0)
    rates_flu: tuple[float, float, float] = (0.0, 0.0, 0.0)
    position_enu: tuple[float, float, float] | None = None
    velocity_enu: tuple[float, float, float] = (0.0, 0.0, 0.0)
    gps_fix_type: int | None = None
    home_amsl: float | None = None
    amsl: float | None = None
    headers: Headers = field(default_factory=Headers)

    @property
    def yaw_enu(self) -> float:
        """Current heading (rad, ENU, CCW from east)."""
        return rpy_from_quat(self.attitude)[2]

    def on_attitude(self, msg: Any) -> None:
        """ATTITUDE (roll/pitch/yaw, rates; NED/FRD)."""
        q_ned = quat_from_rpy(msg.roll, msg.pitch, msg.yaw)
        self.attitude = attitude_ned_frd_to_enu_flu(q_ned)
        self.rates_flu = frd_to_flu((msg.rollspeed, msg.pitchspeed, msg.yawspeed))

    def on_attitude_quaternion(self, msg: Any) -> None:
        """ATTITUDE_QUATERNION (q1..q4 = w, x, y, z; NED/FRD)."""
        q_ned = (msg.q2, msg.q3, msg.q4, msg.q1)  # MAVLink's (w, x, y, z) as (x, y, z, w)
        self.attitude = attitude_ned_frd_to_enu_flu(q_ned)
        self.rates_flu = frd_to_flu((msg.rollspeed, msg.pitchspeed, msg.yawspeed))

    def on_local_position(
        self, msg: Any, stamp: float
    ) -> tuple[PoseStamped, TwistStamped, TwistStamped]:
        """LOCAL_POSITION_NED -> (pose ENU, velocity_local ENU, velocity_body FLU)."""
        position = ned_to_enu((msg.x, msg.y, msg.z))
        velocity = ned_to_enu((msg.vx, msg.vy, msg.vz))
        self.position_enu, self.velocity_enu = position, velocity
        rates = (Vector3.of(rotate(self.attitude, self.rates_flu)), Vector3.of(self.rates_flu))
        motion = (position, self.attitude, velocity)
        return odometry(self.headers, FRAME_MAP, stamp, motion, *rates)

    def on_gps_raw(self, msg: Any) -> None:
        """GPS_RAW_INT: remember the fix type (3 = 3D fix)."""
        self.gps_fix_type = int(msg.fix_type)

    def on_home_position(self, msg: Any) -> None:
        """HOME_POSITION: remember the home altitude (AMSL, m)."""
        self.home_amsl = msg.altitude / 1e3

    def on_global_position(self, msg: Any, stamp: float) -> NavSatFix | None:
        """GLOBAL_POSITION_INT -> NavSatFix, or None when there is no GPS fix to report."""
        self.amsl = msg.alt / 1e3
        if msg.lat == 0 and msg.lon == 0:
            return None
        if self.gps_fix_type is not None and self.gps_fix_type < GPS_FIX_TYPE_3D:
            return None
        if self.home_amsl is None:
            self.home_amsl = (msg.alt - msg.relative_alt) / 1e3
        return NavSatFix(
            header=self.headers(FRAME_BASE_LINK, stamp, "global"),
            status=NavSatStatus(status=NAVSAT_STATUS_FIX),
            latitude=msg.lat / 1e7,
            longitude=msg.lon / 1e7,
            altitude=msg.alt / 1e3,
            position_covariance_type=COVARIANCE_TYPE_UNKNOWN,
        )

    def takeoff_altitude_amsl(self, height: float) -> float:
        """AMSL altitude (m) of ``height`` m above the take-off point (NaN if unknown)."""
        if self.home_amsl is not None:
            return self.home_amsl + height
        return float("nan")


class StatusTextAssembler:
    """Joins STATUSTEXT chunks (MAVLink 2 ``id``/``chunk_seq``) into whole texts.

    A text with ``id`` 0 is complete in one message. A chunked text is complete when a chunk
    shorter than 50 characters arrives, or ``max_wait`` seconds after its last chunk (a chunk
    may be lost). Trailing whitespace and NULs are removed (PX4 ends most texts with a tab).
    """

    CHUNK = 50

    def __init__(self, max_wait: float = 0.5) -> None:
        self.max_wait = max_wait
        self._parts: dict[int, tuple[int, list[str], float]] = {}

    @staticmethod
    def _text(msg: Any) -> str:
        text = msg.text
        if isinstance(text, bytes | bytearray):
            text = bytes(text).decode("utf-8", "replace")
        return text.split("\x00", 1)[0]

    def add(self, msg: Any, stamp: float, now: float) -> list[StatusText]:
        """Feed one STATUSTEXT (``now`` monotonic s); returns the texts completed by it."""
        done = self.flush(now)
        text = self._text(msg)
        text_id = int(getattr(msg, "id", 0) or 0)
        complete = len(text) < self.CHUNK
        if text_id == 0:
            done.append(self._make(msg.severity, text, stamp))
            return done
        severity, parts, _ = self._parts.get(text_id, (msg.severity, [], now))
        parts.append(text)
        if complete:
            self._parts.pop(text_id, None)
            done.append(self._make(severity, "".join(parts), stamp))
        else:
            self._parts[text_id] = (severity, parts, now)
        return done

    def flush(self, now: float, *, stamp: float | None = None) -> list[StatusText]:
        """Texts whose last chunk is older than ``max_wait`` (emitted as they are)."""
        out = []
        for text_id, (severity, parts, last) in list(self._parts.items()):
            if now - last >= self.max_wait:
                del self._parts[text_id]
                out.append(self._make(severity, "".join(parts), stamp or 0.0))
        return out

    @staticmethod
    def _make(severity: int, text: str, stamp: float) -> StatusText:
        return StatusText(header=Header(stamp=stamp), severity=int(severity), text=text.rstrip())


# Fields that must be finite for a telemetry message to be used: a NaN or infinite pose would be
# published to every app, and held by the failsafe as a position target.
FINITE_FIELDS = {
    "LOCAL_POSITION_NED": ("x", "y", "z", "vx", "vy", "vz"),
    "ATTITUDE": ("roll", "pitch", "yaw", "rollspeed", "pitchspeed", "yawspeed"),
    "ATTITUDE_QUATERNION": ("q1", "q2", "q3", "q4", "rollspeed", "pitchspeed", "yawspeed"),
}


def non_finite_field(kind: str, msg: Any) -> str | None:
    """The first field of a pose/attitude message that is NaN or infinite, or None."""
    for name in FINITE_FIELDS.get(kind, ()):
        value = getattr(msg, name, 0.0)
        if not math.isfinite(value):
            return f"{kind}.{name} = {value!r}"
    return None
