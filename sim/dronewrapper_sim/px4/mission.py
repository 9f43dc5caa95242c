"""PX4's mission side: the MAVLink mission protocol (autopilot end), AUTO.MISSION, the geofence.

:class:`MissionStore` answers the protocol as PX4 does: an upload (MISSION_COUNT) is asked
item by item with MISSION_REQUEST_INT and ended by MISSION_ACK; an item PX4 would not take
(an unsupported command or frame) ends it with the matching MAV_MISSION_RESULT; a download
(MISSION_REQUEST_LIST) is answered with MISSION_COUNT and each item asked; MISSION_CLEAR_ALL
empties a list. Missions, fences (MAV_MISSION_TYPE_FENCE) and rally points are separate lists.
An upload not finished within :data:`UPLOAD_TIMEOUT_S` is dropped (PX4's is 5 s), an item
asked again is answered again, and an item not sent within :data:`RETRY_S` of its request is
asked again (PX4's ``MAVLINK_MISSION_RETRY_TIMEOUT_DEFAULT``: a lost request does not stall
the upload).

:class:`MissionRunner` flies the mission in AUTO.MISSION: NAV_TAKEOFF climbs, NAV_WAYPOINT
flies to the item (acceptance radius param2, else NAV_ACC_RAD; hold param1 s), NAV_LAND
lands there, NAV_RETURN_TO_LAUNCH returns; each item reached is MISSION_ITEM_REACHED, and the
item being flown is MISSION_CURRENT; a new mission is flown from the item its upload marks
current (MAVLink's ``current``), else from the last mission's current item, as PX4 does. After
the last item the vehicle holds (AUTO.LOITER).
Altitudes: GLOBAL_RELATIVE_ALT items are m above home, GLOBAL items m AMSL (the local origin
lies at ``origin_amsl``). DO_CHANGE_SPEED (param1 0 or 1: horizontal; param2 m/s, capped at
MPC_XY_VEL_MAX; -2 or 0: back to MPC_XY_CRUISE; -1: unchanged) sets the speed of the legs
after it. The camera, gimbal, region-of-interest and gripper items PX4 takes
(:data:`NO_OP_COMMANDS`) are taken and skipped, each with an informational STATUSTEXT: this
vehicle carries no camera, gimbal or gripper. SPLINE_WAYPOINT is refused, as PX4 refuses it.

The uploaded fence's breach check is :mod:`dronewrapper_sim.px4.geofence`.

Pure: time is the caller's (s), positions local ENU m.

Size: the mission protocol and the runner share the store's lists and PX4's tables of what a
mission may hold.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

from pymavlink.dialects.v20 import common as mavlink
from pymavlink.dialects.v20.common import MAVLink_message as Message

from dronewrapper_sim.px4.flight_control import Limits, Target

if TYPE_CHECKING:
    from dronewrapper_sim.dynamics import QuadState
    from dronewrapper_sim.px4.params import ParamStore

MISSION = mavlink.MAV_MISSION_TYPE_MISSION
FENCE = mavlink.MAV_MISSION_TYPE_FENCE
RALLY = mavlink.MAV_MISSION_TYPE_RALLY
UPLOAD_TIMEOUT_S = 5.0
RETRY_S = 0.25
MAX_ITEMS = 500
NO_OP_COMMANDS = {  # taken as PX4 takes them, and skipped: no camera, gimbal or gripper
    mavlink.MAV_CMD_DO_SET_ROI,
    mavlink.MAV_CMD_DO_SET_ROI_LOCATION,
    mavlink.MAV_CMD_DO_SET_ROI_WPNEXT_OFFSET,
    mavlink.MAV_CMD_DO_SET_ROI_NONE,
    mavlink.MAV_CMD_DO_DIGICAM_CONTROL,
    mavlink.MAV_CMD_DO_MOUNT_CONFIGURE,
    mavlink.MAV_CMD_DO_MOUNT_CONTROL,
    mavlink.MAV_CMD_DO_SET_CAM_TRIGG_DIST,
    mavlink.MAV_CMD_DO_SET_CAM_TRIGG_INTERVAL,
    mavlink.MAV_CMD_DO_TRIGGER_CONTROL,
    mavlink.MAV_CMD_DO_GIMBAL_MANAGER_PITCHYAW,
    mavlink.MAV_CMD_DO_GIMBAL_MANAGER_CONFIGURE,
    mavlink.MAV_CMD_DO_GRIPPER,
    mavlink.MAV_CMD_IMAGE_START_CAPTURE,
    mavlink.MAV_CMD_IMAGE_STOP_CAPTURE,
    mavlink.MAV_CMD_VIDEO_START_CAPTURE,
    mavlink.MAV_CMD_VIDEO_STOP_CAPTURE,
    mavlink.MAV_CMD_SET_CAMERA_MODE,
    mavlink.MAV_CMD_SET_CAMERA_ZOOM,
    mavlink.MAV_CMD_SET_CAMERA_FOCUS,
}
NAV_COMMANDS = {
    MISSION: {
        mavlink.MAV_CMD_NAV_WAYPOINT,
        mavlink.MAV_CMD_NAV_TAKEOFF,
        mavlink.MAV_CMD_NAV_LAND,
        mavlink.MAV_CMD_NAV_RETURN_TO_LAUNCH,
        mavlink.MAV_CMD_NAV_LOITER_TIME,
        mavlink.MAV_CMD_DO_CHANGE_SPEED,
        *NO_OP_COMMANDS,
    },
    FENCE: {
        mavlink.MAV_CMD_NAV_FENCE_POLYGON_VERTEX_INCLUSION,
        mavlink.MAV_CMD_NAV_FENCE_POLYGON_VERTEX_EXCLUSION,
        mavlink.MAV_CMD_NAV_FENCE_CIRCLE_INCLUSION,
        mavlink.MAV_CMD_NAV_FENCE_CIRCLE_EXCLUSION,
        mavlink.MAV_CMD_NAV_FENCE_RETURN_POINT,
    },
    RALLY: {mavlink.MAV_CMD_NAV_RALLY_POINT},
}
FRAMES = {
    mavlink.MAV_FRAME_GLOBAL,
    mavlink.MAV_FRAME_GLOBAL_RELATIVE_ALT,
    mavlink.MAV_FRAME_GLOBAL_INT,
    mavlink.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT,
    mavlink.MAV_FRAME_MISSION,
}


@dataclass
class Upload:
    """An upload in progress: the items so far and when the last one came."""

    mission_type: int
    count: int
    items: list[Message] = field(default_factory=list)
    last_at: float = 0.0
    link: str = ""  # the link the upload came on (its requests go back there)
    request: Message | None = None  # the last request sent, and when
    asked_at: float = 0.0


class MissionStore:
    """The lists the autopilot holds and the protocol that fills them (see module docstring)."""

    def __init__(self, sysid: int) -> None:
        self.sysid = sysid
        self.lists: dict[int, list[Message]] = {MISSION: [], FENCE: [], RALLY: []}
        self.current = 0
        self.version = 0  # changes with every new mission list
        self.fence_version = 0
        self._upload: Upload | None = None

    def _ack(self, msg: Message, result: int, mission_type: int) -> Message:
        return mavlink.MAVLink_mission_ack_message(
            msg.get_srcSystem(), msg.get_srcComponent(), result, mission_type
        )

    def _request(self, msg: Message, seq: int, mission_type: int) -> Message:
        return mavlink.MAVLink_mission_request_int_message(
            msg.get_srcSystem(), msg.get_srcComponent(), seq, mission_type
        )

    def handle(self, msg: Message, now: float, link: str = "") -> list[Message]:
        """The replies to one mission-protocol message (addressed to this vehicle) that came
        on ``link``."""
        replies = self._handle(msg, now)
        upload = self._upload
        if upload is not None:
            for reply in replies:
                if reply.get_type() == "MISSION_REQUEST_INT":
                    upload.link, upload.request, upload.asked_at = link, reply, now
        return replies

    def retry(self, now: float, link: str) -> list[Message]:
        """The request of a running upload on ``link`` again, once :data:`RETRY_S` has passed
        since it was sent without its item coming."""
        upload = self._upload
        if upload is None or upload.link != link or upload.request is None:
            return []
        if now - upload.last_at > UPLOAD_TIMEOUT_S:
            self._upload = None
            return []
        if now - upload.asked_at < RETRY_S:
            return []
        upload.asked_at = now
        return [upload.request]

    def _handle(self, msg: Message, now: float) -> list[Message]:
        if getattr(msg, "target_system", 0) not in (0, self.sysid):
            return []
        kind = msg.get_type()
        mission_type = getattr(msg, "mission_type", MISSION)
        if mission_type not in self.lists:
            return [self._ack(msg, mavlink.MAV_MISSION_UNSUPPORTED, mission_type)]
        upload = self._upload
        if upload is not None and now - upload.last_at > UPLOAD_TIMEOUT_S:
            self._upload = upload = None
        if kind == "MISSION_COUNT":
            if msg.count > MAX_ITEMS:
                return [self._ack(msg, mavlink.MAV_MISSION_NO_SPACE, mission_type)]
            if msg.count == 0:
                self._store(mission_type, [])
                return [self._ack(msg, mavlink.MAV_MISSION_ACCEPTED, mission_type)]
            self._upload = Upload(mission_type, msg.count, last_at=now)
            return [self._request(msg, 0, mission_type)]
        if kind in ("MISSION_ITEM_INT", "MISSION_ITEM"):
            return self._on_item(msg, now, upload)
        if kind == "MISSION_REQUEST_LIST":
            count = len(self.lists[mission_type])
            return [
                mavlink.MAVLink_mission_count_message(
                    msg.get_srcSystem(), msg.get_srcComponent(), count, mission_type
                )
            ]
        if kind in ("MISSION_REQUEST_INT", "MISSION_REQUEST"):
            items = self.lists[mission_type]
            if not 0 <= msg.seq < len(items):
                return [self._ack(msg, mavlink.MAV_MISSION_INVALID_SEQUENCE, mission_type)]
            return [self._item_to(msg, items[msg.seq])]
        if kind == "MISSION_CLEAR_ALL":
            self._store(mission_type, [])
            return [self._ack(msg, mavlink.MAV_MISSION_ACCEPTED, mission_type)]
        if kind == "MISSION_SET_CURRENT":
            self.set_current(int(msg.seq))
            return [self.current_message()]
        return []

    def _on_item(self, msg: Message, now: float, upload: Upload | None) -> list[Message]:
        mission_type = getattr(msg, "mission_type", MISSION)
        if upload is None or upload.mission_type != mission_type:
            return []
        expected = len(upload.items)
        if msg.seq < expected:
            return []  # a duplicate: already taken
        if msg.seq > expected:
            return [self._request(msg, expected, mission_type)]
        if msg.command not in NAV_COMMANDS[mission_type]:
            self._upload = None
            return [self._ack(msg, mavlink.MAV_MISSION_UNSUPPORTED, mission_type)]
        if msg.frame not in FRAMES:
            self._upload = None
            return [self._ack(msg, mavlink.MAV_MISSION_UNSUPPORTED_FRAME, mission_type)]
        upload.items.append(msg)
        upload.last_at = now
        if len(upload.items) < upload.count:
            return [self._request(msg, len(upload.items), mission_type)]
        self._store(mission_type, upload.items)
        self._upload = None
        return [self._ack(msg, mavlink.MAV_MISSION_ACCEPTED, mission_type)]

    def _store(self, mission_type: int, items: list[Message]) -> None:
        self.lists[mission_type] = list(items)
        if mission_type == MISSION:  # as PX4: the item marked current, else the last current
            marked = [item.seq for item in items if getattr(item, "current", 0)]
            self.current = marked[0] if marked else max(0, min(self.current, len(items) - 1))
            self.version += 1
        elif mission_type == FENCE:
            self.fence_version += 1

    def _item_to(self, request: Message, item: Message) -> Message:
        return mavlink.MAVLink_mission_item_int_message(
            request.get_srcSystem(),
            request.get_srcComponent(),
            item.seq,
            item.frame,
            item.command,
            int(item.seq == self.current),
            item.autocontinue,
            item.param1,
            item.param2,
            item.param3,
            item.param4,
            item.x,
            item.y,
            item.z,
            item.mission_type,
        )

    @property
    def mission(self) -> list[Message]:
        return self.lists[MISSION]

    def set_current(self, seq: int) -> bool:
        """Fly item ``seq`` next; False when there is no such item."""
        if not 0 <= seq < len(self.mission):
            return False
        self.current = seq
        return True

    def current_message(self) -> Message:
        return mavlink.MAVLink_mission_current_message(self.current, len(self.mission))


@dataclass
class Leg:
    """What the runner asks of the commander now: a position to fly to (local ENU m; NaN
    z: keep the altitude), or a mode to switch to."""

    position: tuple[float, float, float] | None = None
    mode: str = ""  # "loiter", "land", "rtl"
    land_at: tuple[float, float] | None = None
    speed: float | None = None  # m/s horizontal set by DO_CHANGE_SPEED; None: MPC_XY_CRUISE


class MissionRunner:
    """Flies the store's mission item by item (see module docstring)."""

    def __init__(
        self,
        store: MissionStore,
        to_local: Callable[[float, float], tuple[float, float]],
        home: Callable[[], tuple[float, float, float]],
        acceptance_radius: Callable[[], float],
        *,
        origin_amsl: float = 0.0,
        max_speed: Callable[[], float] = lambda: math.inf,
    ) -> None:
        self.store = store
        self.to_local = to_local
        self.home = home
        self.acceptance_radius = acceptance_radius
        self.origin_amsl = origin_amsl  # m AMSL of local z = 0
        self.max_speed = max_speed  # m/s: the cap on a DO_CHANGE_SPEED (MPC_XY_VEL_MAX)
        self.speed: float | None = None  # m/s from the last DO_CHANGE_SPEED; None: default
        self.events: list[Message] = []  # MISSION_ITEM_REACHED / MISSION_CURRENT to send
        self.notes: list[str] = []  # informational texts for the commander to say
        self._arrived_at: float | None = None
        self._announced = -1
        self._version = store.version

    def runnable(self) -> bool:
        return self.store.current < len(self.store.mission)

    def _target_of(self, item: Message, z_now: float) -> tuple[float, float, float]:
        hx, hy, hz = self.home()
        if item.x == 0 and item.y == 0:
            east, north = hx, hy
        else:
            east, north = self.to_local(item.x / 1e7, item.y / 1e7)
        relative = item.frame in (
            mavlink.MAV_FRAME_GLOBAL_RELATIVE_ALT,
            mavlink.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT,
        )
        z = hz + item.z if relative else item.z - self.origin_amsl
        return (east, north, z if math.isfinite(z) else z_now)

    def step(self, now: float, position: tuple[float, float, float]) -> Leg:
        """The leg to fly now, advancing past reached items."""
        store = self.store
        if store.version != self._version:  # a new mission: start afresh
            self._version, self._announced, self._arrived_at = store.version, -1, None
            self.speed = None
        while store.current < len(store.mission):
            if self._announced != store.current:
                self._announced = store.current
                self.events.append(store.current_message())
            item = store.mission[store.current]
            if item.command == mavlink.MAV_CMD_NAV_RETURN_TO_LAUNCH:
                self._reached(store.current)
                return Leg(mode="rtl", speed=self.speed)
            if item.command == mavlink.MAV_CMD_DO_CHANGE_SPEED:
                self._change_speed(item)
                self._advance()
                continue
            if item.command in NO_OP_COMMANDS:
                self._note(store.current, item.command)
                self._advance()
                continue
            target = self._target_of(item, position[2])
            if item.command == mavlink.MAV_CMD_NAV_TAKEOFF:
                target = (position[0], position[1], target[2])
            if item.command == mavlink.MAV_CMD_NAV_LAND:
                self._reached(store.current)
                return Leg(mode="land", land_at=(target[0], target[1]))
            radius = item.param2 if item.param2 > 0 else self.acceptance_radius()
            distance = math.dist(position, target)
            if distance > radius:
                self._arrived_at = None
                return Leg(position=target, speed=self.speed)
            if self._arrived_at is None:
                self._arrived_at = now
            hold = item.param1 if item.command != mavlink.MAV_CMD_NAV_TAKEOFF else 0.0
            if now - self._arrived_at < hold:
                return Leg(position=target, speed=self.speed)
            self._reached(store.current)
            self._advance()
        return Leg(mode="loiter")

    def _change_speed(self, item: Message) -> None:
        """DO_CHANGE_SPEED: param1 speed type (0 air, 1 ground: horizontal; 2, 3: vertical,
        not flown differently here), param2 m/s (-1 unchanged; -2 or 0: the default)."""
        if int(item.param1) not in (0, 1):
            return
        speed = item.param2
        if speed == -1:
            return
        self.speed = min(speed, self.max_speed()) if speed > 0 else None

    def _note(self, seq: int, command: int) -> None:
        entry = mavlink.enums["MAV_CMD"].get(command)
        name = entry.name.removeprefix("MAV_CMD_") if entry is not None else str(command)
        self.notes.append(f"Mission item {seq}: {name} skipped (no camera, gimbal or gripper)")

    def _reached(self, seq: int) -> None:
        self.events.append(mavlink.MAVLink_mission_item_reached_message(seq))

    def _advance(self) -> None:
        self.store.current += 1
        self._arrived_at = None

    def drain(self) -> list[Message]:
        out, self.events = self.events, []
        return out


# ---------------------------------------------------------------- the target of a leg


Hold = tuple[float, float, float, float]  # x, y, z (local ENU m), yaw (rad)


def leg_target(leg: Leg, p: ParamStore, hold: Hold, state: QuadState) -> tuple[Target, Hold]:
    """AUTO.MISSION's target for ``leg`` and the hold point after it: a leg's position is
    flown facing it (the heading kept within 3 m of it); the end of the mission holds at
    ``hold``, or lands where the leg says (``land_at``)."""
    limits: Limits = {
        "max_xy": p["MPC_XY_CRUISE"] if leg.speed is None else leg.speed,
        "max_up": p["MPC_Z_V_AUTO_UP"],
        "max_down": p["MPC_Z_V_AUTO_DN"],
        "max_yaw_rate": math.radians(p["MPC_YAWRAUTO_MAX"]),
    }
    if leg.position is not None:
        x, y, z = leg.position
        far = math.hypot(x - state.x, y - state.y) > 3.0
        yaw = math.atan2(y - state.y, x - state.x) if far else hold[3]
        return Target(position=(x, y, z), yaw=yaw, **limits), (*hold[:3], yaw)
    if leg.land_at is not None:
        hold = (leg.land_at[0], leg.land_at[1], state.z, state.yaw)
    return Target(position=hold[:3], yaw=hold[3], **limits), hold
