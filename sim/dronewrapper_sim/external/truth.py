"""The truth an autopilot's own simulation sends, decoded from MAVLink into one form.

PX4 SIH sends ``HIL_STATE_QUATERNION`` (115) to UDP 19410; ArduCopter SITL sends ``SIM_STATE``
(108) on a MAVLink link when asked. Both carry the vehicle's true attitude (quaternion w x y z,
body FRD -> NED), body rates (FRD, rad/s), WGS84 position and NED velocity. Pure: no I/O.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

HIL_STATE_QUATERNION = "HIL_STATE_QUATERNION"
SIM_STATE = "SIM_STATE"
TRUTH_MESSAGES = (HIL_STATE_QUATERNION, SIM_STATE)


@dataclass(frozen=True)
class GeoTruth:
    """One truth sample as an autopilot reports it.

    Attributes:
        time_s: the autopilot's own clock (s), or None when the message carries no time.
        lat_deg, lon_deg: WGS84 position (deg).
        alt_m: altitude above mean sea level (m).
        q_wxyz: attitude quaternion w, x, y, z (body FRD -> NED).
        vel_ned: velocity north, east, down (m/s).
        rates_frd: body angular rates about forward, right, down (rad/s).
    """

    time_s: float | None
    lat_deg: float
    lon_deg: float
    alt_m: float
    q_wxyz: tuple[float, float, float, float]
    vel_ned: tuple[float, float, float]
    rates_frd: tuple[float, float, float]

    def is_finite(self) -> bool:
        values = (self.lat_deg, self.lon_deg, self.alt_m, *self.q_wxyz, *self.vel_ned)
        return all(math.isfinite(v) for v in (*values, *self.rates_frd)) and any(self.q_wxyz)


def from_hil_state_quaternion(msg: Any) -> GeoTruth:
    """PX4 SIH's truth: lat/lon degE7, alt mm, velocity cm/s. PX4 SIH leaves ``time_usec`` at
    0 (measured on PX4 main of 2026-03-02), which reads as no time; another value is PX4's
    clock (s)."""
    q = tuple(float(c) for c in msg.attitude_quaternion)
    return GeoTruth(
        time_s=msg.time_usec * 1e-6 if msg.time_usec else None,
        lat_deg=msg.lat * 1e-7,
        lon_deg=msg.lon * 1e-7,
        alt_m=msg.alt * 1e-3,
        q_wxyz=(q[0], q[1], q[2], q[3]),
        vel_ned=(msg.vx * 0.01, msg.vy * 0.01, msg.vz * 0.01),
        rates_frd=(float(msg.rollspeed), float(msg.pitchspeed), float(msg.yawspeed)),
    )


def from_sim_state(msg: Any) -> GeoTruth:
    """ArduPilot SITL's truth. It carries no time. Its position is read from ``lat_int`` /
    ``lon_int`` (degE7): ArduPilot fills the float ``lat``/``lon`` with degE7 too, which a
    float32 holds only to about a metre."""
    lat_int = getattr(msg, "lat_int", 0)
    lon_int = getattr(msg, "lon_int", 0)
    if lat_int or lon_int:
        lat, lon = lat_int * 1e-7, lon_int * 1e-7
    else:  # a sender without the extension: the standard's float degrees
        lat, lon = float(msg.lat), float(msg.lon)
    return GeoTruth(
        time_s=None,
        lat_deg=lat,
        lon_deg=lon,
        alt_m=float(msg.alt),
        q_wxyz=(float(msg.q1), float(msg.q2), float(msg.q3), float(msg.q4)),
        vel_ned=(float(msg.vn), float(msg.ve), float(msg.vd)),
        rates_frd=(float(msg.xgyro), float(msg.ygyro), float(msg.zgyro)),
    )


def decode(msg: Any) -> GeoTruth | None:
    """The truth in ``msg``, or None if it is not a truth message (or not finite)."""
    kind = msg.get_type()
    if kind == HIL_STATE_QUATERNION:
        truth = from_hil_state_quaternion(msg)
    elif kind == SIM_STATE:
        truth = from_sim_state(msg)
    else:
        return None
    return truth if truth.is_finite() else None
