"""How high an autopilot's return to a rally point climbs, and the rally points refused for it
(pure). Heights are m above home, the envelope's frame.

A return flies to the closest of home and the rally points and climbs on its way there; the
envelope's ceiling binds that climb as it binds everything else. The autopilots differ:

- PX4 returns at the rally point's altitude plus its return altitude (``RTL_RETURN_ALT``: its
  RTL takes the point's altitude as the destination's ground): :func:`px4_peak`. A point is
  refused when that sum is above the ceiling.
- ArduCopter (``ModeRTL::compute_return_target``, 4.8) returns at the highest of the
  destination's altitude (a rally point's own, never below 0), ``RTL_ALT_M``, and the height
  it starts at plus ``RTL_CLIMB_MIN_M`` (at least 0.3 m), and never descends to get there;
  ``RTL_CONE_SLOPE`` and an altitude fence only lower it, and it then moves to
  ``RTL_ALT_FINAL_M`` over the destination: :func:`ardupilot_peak`. With
  ``RTL_ALT_TYPE`` 1 those heights are above the terrain, not home. The bridge keeps
  ``RTL_ALT_M`` and ``RTL_ALT_FINAL_M`` at most the return altitude (the ceiling less 1 m),
  ``RTL_CLIMB_MIN_M`` at 0 and ``RTL_ALT_TYPE`` at 0
  (:mod:`~dronewrapper_bridge_mavlink.autopilot_limits`), and a start above the ceiling is a
  breach already; what is left is the rally point's own altitude, so a point above the return
  altitude is refused: the same 1 m under the ceiling that a return to home keeps.
"""

from __future__ import annotations

from collections.abc import Sequence

from dronewrapper.envelope import Envelope
from dronewrapper.msgs.mission import Waypoint
from dronewrapper_bridge_mavlink.mission_frames import MissionFrameError, placed

ARDUPILOT_RTL_ALT_MIN_M = 0.3
"""ArduCopter's lowest return height (``RTL_ALT_MIN_M``, m above home)."""


def px4_peak(point_up: float, return_alt: float) -> float:
    """The height a PX4 return to a point ``point_up`` m above home climbs to (m)."""
    return point_up + return_alt


def ardupilot_peak(
    point_up: float, return_alt: float, start_up: float = 0.0, climb_min: float = 0.0
) -> float:
    """The height an ArduCopter return climbs to (m above home, ``RTL_ALT_TYPE`` 0): to a point
    ``point_up`` m up, with ``RTL_ALT_M`` ``return_alt``, from ``start_up`` m, with
    ``RTL_CLIMB_MIN_M`` ``climb_min`` (no cone, no altitude fence: they only lower it)."""
    lowest = max(ARDUPILOT_RTL_ALT_MIN_M, start_up + max(0.0, climb_min))
    return max(max(point_up, 0.0), return_alt, lowest, start_up)


def check(
    rally: Sequence[Waypoint],
    envelope: Envelope,
    home_geo: Sequence[float] | None,
    *,
    ardupilot: bool,
    return_alt: float,
) -> None:
    """Refuse the first rally point a return to it would climb too high from: on PX4 above
    the ceiling (``return_alt``: its ``RTL_RETURN_ALT``), on ArduCopter above ``return_alt``
    (the highest return altitude the bridge keeps under the ceiling).

    Raises:
        MissionFrameError: naming the rally point, the climb and the limit.
    """
    for seq, wp in enumerate(rally):
        up = (placed(wp, home_geo) or (0.0, 0.0, 0.0))[2]
        if ardupilot:
            peak = ardupilot_peak(up, return_alt)
            if peak > return_alt:
                raise MissionFrameError(
                    f"rally point {seq}: an ArduCopter return there flies at its {up:g} m "
                    f"above home (the higher of the point's altitude and the return altitude), "
                    f"above the {return_alt:g} m kept under the envelope's "
                    f"{envelope.max_altitude:g} m: lower the rally point"
                )
            continue
        peak = px4_peak(up, return_alt)
        if peak > envelope.max_altitude:
            raise MissionFrameError(
                f"rally point {seq}: a return there climbs to {peak:g} m above "
                f"home (its {up:g} m plus the return altitude of {return_alt:g} m), above "
                f"the envelope's {envelope.max_altitude:g} m: lower the rally point"
            )


__all__ = ["ARDUPILOT_RTL_ALT_MIN_M", "ardupilot_peak", "check", "px4_peak"]
