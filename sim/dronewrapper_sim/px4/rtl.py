"""PX4's return (AUTO.RTL) and landing descent, as its navigator flies them.

:class:`ReturnFlight` flies RTL: to the closest of home and the rally points (PX4's
RTL_TYPE 0, its default: a rally point within :data:`RALLY_MIN_FROM_HOME_M` of home is
ignored, one is chosen when 2 m closer than home), climbing first to RTL_RETURN_ALT above the
destination, then descending to RTL_DESCEND_ALT, waiting RTL_LAND_DELAY s and landing; within
RTL_MIN_DIST of the destination it lands at once. The ground at a rally point is at home's
height (a flat world; the rally point's altitude is not flown). :func:`land_target` is
AUTO.LAND's descent with PX4's speed schedule (MPC_LAND_ALT1/ALT2).

Pure: time is the caller's (s), positions local ENU m; each step returns the status text PX4
prints, if any, for the commander to send.
"""

from __future__ import annotations

import math

from dronewrapper_sim.dynamics import QuadState
from dronewrapper_sim.px4.flight_control import NAN, Limits, Target
from dronewrapper_sim.px4.params import ParamStore as Params

RALLY_MIN_FROM_HOME_M = 10.0  # PX4's MAX_DIST_FROM_HOME_FOR_LAND_APPROACHES
LAND_TEXT = "RTL: land at destination"

Point = tuple[float, float, float]


def auto_limits(p: Params) -> Limits:
    """The speed limits of PX4's auto modes (m/s, rad/s)."""
    return {
        "max_xy": p["MPC_XY_CRUISE"],
        "max_up": p["MPC_Z_V_AUTO_UP"],
        "max_down": p["MPC_Z_V_AUTO_DN"],
        "max_yaw_rate": math.radians(p["MPC_YAWRAUTO_MAX"]),
    }


def land_speed(p: Params, height: float) -> float:
    """PX4's descent speed (m/s) at ``height`` m above the ground: MPC_Z_V_AUTO_DN above
    MPC_LAND_ALT1, MPC_LAND_SPEED below MPC_LAND_ALT2, linear between."""
    alt1, alt2 = p["MPC_LAND_ALT1"], p["MPC_LAND_ALT2"]
    fast, slow = p["MPC_Z_V_AUTO_DN"], p["MPC_LAND_SPEED"]
    if height >= alt1:
        return fast
    if height <= alt2 or alt1 <= alt2:
        return slow
    return slow + (fast - slow) * (height - alt2) / (alt1 - alt2)


def land_target(p: Params, ground_z: float, x: float, y: float, yaw: float, z: float) -> Target:
    """Descend over (x, y) at PX4's speed for the height ``z - ground_z`` (m)."""
    speed = land_speed(p, z - ground_z)
    return Target(
        position=(x, y, NAN),
        velocity=(0.0, 0.0, -speed),
        yaw=yaw,
        max_xy=p["MPC_XY_CRUISE"],
        max_down=max(speed, p["MPC_Z_V_AUTO_DN"]),
        max_yaw_rate=math.radians(p["MPC_YAWRAUTO_MAX"]),
    )


def destination(home: Point, rally: list[tuple[float, float]], state: QuadState) -> Point:
    """The closest of home and the rally points (module docstring), local ENU m."""
    hx, hy, hz = home
    best, best_dist = home, math.hypot(state.x - hx, state.y - hy)
    for x, y in rally:
        dist = math.hypot(state.x - x, state.y - y)
        if math.hypot(x - hx, y - hy) > RALLY_MIN_FROM_HOME_M and dist + 2.0 < best_dist:
            best, best_dist = (x, y, hz), dist
    return best


class ReturnFlight:
    """One RTL: its destination and phase (``climb``, ``return``, ``descend``, ``land``,
    ``done``)."""

    def __init__(self, home: Point) -> None:
        self.phase = ""
        self.z = 0.0  # the return altitude, local ENU m
        self.wait_since = 0.0
        self.dest = home

    def start(
        self, p: Params, state: QuadState, landed: bool, home: Point, rally: list
    ) -> str | None:
        """Begin a return from ``state``; the text PX4 prints, if any."""
        self.dest = destination(home, rally, state)
        hx, hy, hz = self.dest
        if landed:
            self.phase = "done"
            return None
        if math.hypot(state.x - hx, state.y - hy) <= p["RTL_MIN_DIST"]:
            self.phase = "land"
            return LAND_TEXT
        self.z = max(state.z, hz + p["RTL_RETURN_ALT"])
        self.phase = "climb"
        return f"RTL: start return at {self.z - hz:.0f} m above destination"

    def target(
        self, p: Params, state: QuadState, now: float, hold: tuple[float, float, float, float]
    ) -> tuple[Target, str | None]:
        """The target now (``hold``: where the mode started, x y z yaw) and the text PX4
        prints on this step, if any."""
        hx, hy, hz = self.dest
        x0, y0, _, yaw0 = hold
        limits = auto_limits(p)
        text = None
        if self.phase == "climb":
            if state.z < self.z - 0.5:
                return Target(position=(x0, y0, self.z), yaw=yaw0, **limits), None
            self.phase = "return"
        if self.phase == "return":
            dist = math.hypot(hx - state.x, hy - state.y)
            if dist >= p["NAV_ACC_RAD"]:
                heading = math.atan2(hy - state.y, hx - state.x) if dist > 3.0 else state.yaw
                return Target(position=(hx, hy, self.z), yaw=heading, **limits), None
            self.phase = "descend"
            self.wait_since = now
        if self.phase == "descend":
            descend_z = hz + p["RTL_DESCEND_ALT"]
            if state.z > descend_z + 0.5:
                self.wait_since = now
                return Target(position=(hx, hy, descend_z), yaw=state.yaw, **limits), None
            if now - self.wait_since < p["RTL_LAND_DELAY"]:
                return Target(position=(hx, hy, descend_z), yaw=state.yaw, **limits), None
            self.phase = "land"
            text = LAND_TEXT
        if self.phase == "land":
            return land_target(p, hz, hx, hy, yaw0, state.z), text
        return Target(idle=True), text
