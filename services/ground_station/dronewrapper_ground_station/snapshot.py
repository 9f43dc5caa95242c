"""Telemetry as the page shows it: values with their age and a stale flag (pure).

Each section of a drone's snapshot is ``{"age": s, "stale": bool, ...fields}`` or None before
its first message. Frames and units as on the bus: local ENU metres, body FLU m/s, radians.
A value is stale when older than ``stale_after`` nominal periods of its topic (at least 1 s).
"""

from __future__ import annotations

import math
import time
from typing import Any

from dronewrapper import telemetry
from dronewrapper.envelope import Envelope
from dronewrapper.msgs.control import ControllerStatus
from dronewrapper.msgs.geometry import PoseStamped, TwistStamped
from dronewrapper.msgs.mavros import ExtendedState, State, StatusText
from dronewrapper.msgs.mission import HomePosition, WaypointList
from dronewrapper.msgs.refusal import Refusal
from dronewrapper.msgs.sensor import BatteryState, NavSatFix
from dronewrapper.msgs.vision import Detections

LANDED_STATES = {0: "undefined", 1: "on_ground", 2: "in_air", 3: "takeoff", 4: "landing"}
SEVERITIES = ("emergency", "alert", "critical", "error", "warning", "notice", "info", "debug")


def stale_limit(rate_hz: float, stale_after: float) -> float:
    """Seconds after which a value of a topic at ``rate_hz`` is stale (event topics: 1 s ×)."""
    period = 1.0 / rate_hz if rate_hz > 0 else 1.0
    return max(1.0, stale_after * period)


def section(fields: dict[str, Any] | None, age: float, limit: float) -> dict[str, Any] | None:
    """A snapshot section: ``fields`` plus ``age`` (s) and ``stale`` (age > ``limit``)."""
    if fields is None:
        return None
    return {**fields, "age": round(age, 3), "stale": age > limit}


def _named(msg: Any, *names: str) -> dict[str, Any]:
    """The fields ``names`` of ``msg``, as they are."""
    return {name: getattr(msg, name) for name in names}


def state_fields(msg: State) -> dict[str, Any]:
    return _named(
        msg, "connected", "armed", "guided", "mode", "autopilot", "failsafe", "system_status"
    )


def extended_fields(msg: ExtendedState) -> dict[str, Any]:
    return {"landed_state": LANDED_STATES.get(msg.landed_state, str(msg.landed_state))}


def pose_fields(msg: PoseStamped) -> dict[str, Any]:
    """Position (ENU m) and attitude (rad) of a pose."""
    x, y, z = (float(v) for v in telemetry.position_of(msg))
    roll, pitch, yaw = telemetry.euler_from_quaternion(msg.pose.orientation)
    return {"x": x, "y": y, "z": z, "roll": roll, "pitch": pitch, "yaw": yaw, "stamp": _stamp(msg)}


def twist_fields(msg: TwistStamped) -> dict[str, Any]:
    """Linear velocity (m/s, the message's frame) and yaw rate (rad/s)."""
    v = msg.twist.linear
    return {"vx": v.x, "vy": v.y, "vz": v.z, "yaw_rate": msg.twist.angular.z}


def battery_fields(msg: BatteryState) -> dict[str, Any]:
    return _named(msg, "percentage", "voltage")


def gps_fields(msg: NavSatFix) -> dict[str, Any]:
    return {
        "latitude": msg.latitude,
        "longitude": msg.longitude,
        "altitude": msg.altitude,
        "fix": msg.status.status,
    }


def _finite(value: float) -> float | None:
    return value if math.isfinite(value) else None


def home_fields(msg: HomePosition) -> dict[str, Any]:
    """Home: local ENU (m) and geodetic (deg; None without GPS)."""
    return {
        "x": msg.x,
        "y": msg.y,
        "z": msg.z,
        "latitude": _finite(msg.latitude),
        "longitude": _finite(msg.longitude),
    }


def mission_fields(msg: WaypointList) -> dict[str, Any]:
    """The mission's items (lat/lon deg, or ENU m from home for local items) and progress."""
    return {
        "current": msg.current_seq,
        "items": [
            {"frame": w.frame, "command": w.command, "x": w.x_lat, "y": w.y_long, "z": w.z_alt}
            for w in msg.waypoints
        ],
    }


def envelope_fields(msg: Envelope) -> dict[str, Any]:
    """The envelope (ENU m from home)."""
    return {
        "max_altitude": msg.max_altitude,
        "max_distance": msg.max_distance,
        "fence": [list(v) for v in msg.fence],
        "exclusions": [[list(v) for v in zone] for zone in msg.exclusions],
        "breach_action": msg.breach_action,
    }


def controller_fields(msg: ControllerStatus) -> dict[str, Any]:
    return _named(
        msg,
        *("mode", "state", "target_visible", "target_id", "detection_age"),
        *("error_x", "error_z", "error_yaw", "cmd_vx", "cmd_vz", "cmd_yaw_rate"),
    )


def detection_fields(msg: Detections) -> dict[str, Any]:
    """Boxes as fractions of the image (x, y of the top-left corner, w, h), best first."""
    width, height = max(1, msg.image_width), max(1, msg.image_height)
    boxes = []
    for det in msg.detections[:32]:
        box = det.bbox
        hyp = det.results[0].hypothesis if det.results else None
        boxes.append(
            {
                "x": (box.center.position.x - box.size_x / 2) / width,
                "y": (box.center.position.y - box.size_y / 2) / height,
                "w": box.size_x / width,
                "h": box.size_y / height,
                "label": hyp.class_id if hyp else "",
                "score": hyp.score if hyp else 0.0,
                "id": det.id,
                "target": bool(det.id) and det.id == msg.target_id,
            }
        )
    return {
        "camera": msg.header.frame_id,
        "stamp": msg.header.stamp,
        "detector": msg.detector,
        "boxes": boxes,
    }


def status_text_entry(msg: StatusText) -> dict[str, Any]:
    """A log line: the event's own stamp (s since the epoch) and its local ``time`` (HH:MM:SS),
    which the page shows, not when the page received it."""
    severity = SEVERITIES[msg.severity] if 0 <= msg.severity < len(SEVERITIES) else "info"
    stamp = msg.header.stamp
    shown = time.strftime("%H:%M:%S", time.localtime(stamp)) if math.isfinite(stamp) else "--:--:--"
    return {"stamp": stamp, "time": shown, "severity": severity, "text": msg.text}


def refusal_entry(refusal: Refusal) -> dict[str, Any]:
    """A refusal of the station's commands, as the page shows it beside its buttons: its rule
    (``kind``), ``limit``, ``count``, the bridge's stamp and local ``time``, and ``text``."""
    stamp = refusal.header.stamp
    shown = time.strftime("%H:%M:%S", time.localtime(stamp)) if math.isfinite(stamp) else "--:--:--"
    return {
        "stamp": stamp,
        "time": shown,
        "kind": refusal.kind,
        "limit": refusal.limit,
        "count": refusal.count,
        "text": refusal.text(),
    }


def _stamp(msg: Any) -> float:
    return float(msg.header.stamp)
