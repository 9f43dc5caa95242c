"""The Tello's state datagram (10 Hz to the client's port 8890): format and parse.

Field order and format of the real drone (SDK 2.0, mission pads off)::

    mid:-1;x:-100;y:-100;z:-100;mpry:-1,-1,-1;pitch:0;roll:0;yaw:0;vgx:0;vgy:0;vgz:0;
    templ:66;temph:68;tof:10;h:0;bat:87;baro:100.26;time:0;agx:7.00;agy:0.00;agz:-997.00;\\r\\n

(one line). Units and signs, the real drone's:

- ``pitch``, ``roll``, ``yaw``: degrees (integers). Pitch > 0 nose up, roll > 0 right side
  down, yaw > 0 clockwise seen from above, measured from the heading at power-on, -180..180.
- ``vgx``, ``vgy``, ``vgz``: velocity in dm/s (integers) in the frame of the power-on heading:
  x forward, y right, z down (so climbing gives vgz < 0).
- ``templ``, ``temph``: lowest and highest board temperature, deg C.
- ``tof``: downward range finder, cm (10 on the ground; 6553 out of range).
- ``h``: height above the take-off point, cm. ``bat``: charge, %. ``baro``: barometric
  altitude, m (2 decimals). ``time``: motors-on time, s.
- ``agx``, ``agy``, ``agz``: accelerometer (specific force) in the body frame x forward,
  y right, z down, in 0.001 g (2 decimals): about ``agz:-1000.00`` at rest.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Protocol

from dronewrapper_sim.dynamics import GRAVITY, QuadState
from dronewrapper_sim.frames import wrap_pi

if TYPE_CHECKING:
    from dronewrapper_sim.tello.flight import TelloFlight

MISSION_PAD_FIELDS = "mid:-1;x:-100;y:-100;z:-100;mpry:-1,-1,-1;"
"""What a Tello sends with no mission pad in view (and what a non-EDU Tello always sends)."""

FIELD_ORDER = (
    *("mid", "x", "y", "z", "mpry", "pitch", "roll", "yaw", "vgx", "vgy", "vgz"),
    *("templ", "temph", "tof", "h", "bat", "baro", "time", "agx", "agy", "agz"),
)
"""The fields of the state datagram, in the real drone's order."""
FLOAT_FIELDS = frozenset(("baro", "agx", "agy", "agz"))
INT_FIELDS = frozenset(FIELD_ORDER) - FLOAT_FIELDS - {"mpry"}


def attitude_deg(flight: TelloFlight) -> tuple[int, int, int]:
    """(pitch, roll, yaw) of ``flight`` in whole degrees, the Tello's signs (see module doc)."""
    s = flight.state
    pitch = -math.degrees(s.pitch)  # FLU pitch > 0 is nose down
    roll = math.degrees(s.roll)  # FLU and FRD roll agree
    yaw = -math.degrees(wrap_pi(s.yaw - flight.origin_yaw))
    return round(pitch), round(roll), round(yaw)


def velocity_dm_s(flight: TelloFlight) -> tuple[int, int, int]:
    """(vgx, vgy, vgz) in dm/s: forward, right, down of the power-on heading."""
    s = flight.state
    c, sn = math.cos(flight.origin_yaw), math.sin(flight.origin_yaw)
    forward = c * s.vx + sn * s.vy
    left = -sn * s.vx + c * s.vy
    return round(forward * 10.0), round(-left * 10.0), round(-s.vz * 10.0)


def acceleration_mg(s: QuadState) -> tuple[float, float, float]:
    """Specific force (acceleration minus gravity) in the body frame FRD, 0.001 g."""
    f = (s.ax, s.ay, s.az + GRAVITY)  # ENU
    cr, sr = math.cos(s.roll), math.sin(s.roll)
    cp, sp = math.cos(s.pitch), math.sin(s.pitch)
    cy, sy = math.cos(s.yaw), math.sin(s.yaw)
    # rows of R (body FLU -> ENU, ZYX), used transposed: ENU -> FLU
    x_axis = (cy * cp, sy * cp, -sp)
    y_axis = (cy * sp * sr - sy * cr, sy * sp * sr + cy * cr, cp * sr)
    z_axis = (cy * sp * cr + sy * sr, sy * sp * cr - cy * sr, cp * cr)
    fwd = sum(a * b for a, b in zip(x_axis, f, strict=True))
    left = sum(a * b for a, b in zip(y_axis, f, strict=True))
    up = sum(a * b for a, b in zip(z_axis, f, strict=True))
    scale = 1000.0 / GRAVITY
    return fwd * scale, -left * scale, -up * scale


class StateSource(Protocol):
    """What a state datagram reads of a simulated Tello (its
    :class:`~dronewrapper_sim.tello.protocol.TelloProtocol`)."""

    flight: TelloFlight

    def temperatures(self) -> tuple[int, int]: ...
    def tof_cm(self) -> int: ...
    def height_cm(self) -> int: ...
    def baro_m(self) -> float: ...


def format_state(protocol: StateSource) -> str:
    """The state datagram of ``protocol``'s Tello now."""
    flight = protocol.flight
    pitch, roll, yaw = attitude_deg(flight)
    vgx, vgy, vgz = velocity_dm_s(flight)
    templ, temph = protocol.temperatures()
    agx, agy, agz = acceleration_mg(flight.state)
    return (
        f"{MISSION_PAD_FIELDS}pitch:{pitch};roll:{roll};yaw:{yaw};"
        f"vgx:{vgx};vgy:{vgy};vgz:{vgz};templ:{templ};temph:{temph};"
        f"tof:{protocol.tof_cm()};h:{protocol.height_cm()};bat:{flight.battery_percent};"
        f"baro:{protocol.baro_m():.2f};time:{int(flight.motor_time_s)};"
        f"agx:{agx + 0.0:.2f};agy:{agy + 0.0:.2f};agz:{agz + 0.0:.2f};\r\n"
    )


def parse_state(text: str) -> dict[str, int | float | str]:
    """The fields of a state datagram: integers and floats as above, ``mpry`` as text.

    Raises:
        ValueError: a field without ``:`` or a number that does not parse.
    """
    fields: dict[str, int | float | str] = {}
    for item in text.strip().split(";"):
        if not item:
            continue
        key, sep, value = item.partition(":")
        if not sep:
            raise ValueError(f"state field without ':': {item!r}")
        if key in INT_FIELDS:
            fields[key] = int(value)
        elif key in FLOAT_FIELDS:
            fields[key] = float(value)
        else:
            fields[key] = value
    return fields
