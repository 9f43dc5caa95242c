"""The bus side of the station: the drones online, their telemetry, video and commands.

Everything goes through the station's runtime Node (a FakeNode on the fake bus in tests), one
drone client per drone on it (:class:`~dronewrapper.client.DroneClient`, under the DroneWrapper
whose verbs the commands call): the station shows its input holders (each telemetry key
subscribed once per drone), its texts and its refusals. Video (while someone watches) and the
simulator's topics are subscribed here. Nothing here spells a key: each is a registry topic.
"""

from __future__ import annotations

import logging
import threading
from collections.abc import Callable
from typing import Any, TypeVar

from dronewrapper import DroneWrapper
from dronewrapper.discovery import BRIDGE_PREFIX, services_by_namespace
from dronewrapper.errors import CommandRefused, NotConnected
from dronewrapper.msgs import registry
from dronewrapper.msgs.mavros import LANDED_STATE_ON_GROUND
from dronewrapper.msgs.registry import Topic
from dronewrapper.msgs.sensor import CompressedImage
from dronewrapper.msgs.simulation import VehicleReset
from dronewrapper.runtime.contract import NodeApi
from dronewrapper.runtime.errors import ServiceError, ServiceUnavailable
from dronewrapper.runtime.latest import Latest
from dronewrapper_ground_station import snapshot
from dronewrapper_ground_station.config import Config
from dronewrapper_ground_station.requests import VelocityCommand
from dronewrapper_ground_station.sim_objects import SimObjects
from dronewrapper_ground_station.teleop import DeadMan
from dronewrapper_ground_station.undeclare import undeclare

T = TypeVar("T")

log = logging.getLogger("station")

CAMERAS = registry.CAMERA_SHORT_NAMES

# (snapshot section, topic, message -> fields)
TELEMETRY: tuple[tuple[str, Topic[Any], Callable[[Any], dict[str, Any]]], ...] = (
    ("state", registry.STATE, snapshot.state_fields),
    ("landed", registry.EXTENDED_STATE, snapshot.extended_fields),
    ("pose", registry.LOCAL_POSE, snapshot.pose_fields),
    ("velocity", registry.VELOCITY_LOCAL, snapshot.twist_fields),
    ("velocity_body", registry.VELOCITY_BODY, snapshot.twist_fields),
    ("battery", registry.BATTERY, snapshot.battery_fields),
    ("gps", registry.GLOBAL_POSITION, snapshot.gps_fields),
    ("ground_truth", registry.SIM_GROUND_TRUTH, snapshot.pose_fields),
    ("controller", registry.CONTROLLER_STATUS, snapshot.controller_fields),
    ("detections", registry.DETECTIONS, snapshot.detection_fields),
    ("home", registry.HOME_POSITION, snapshot.home_fields),
    ("mission", registry.MISSION_WAYPOINTS, snapshot.mission_fields),
    ("envelope", registry.ENVELOPE, snapshot.envelope_fields),
)


class DroneLink:
    """One drone as the station sees it: telemetry holders, video slots, commands.

    Args:
        node: the station's node (shared by every drone); its clock times the ages, the
            dead-man and the blocking commands.
        ns: the drone's namespace.
        config: the station config.
    """

    def __init__(self, node: NodeApi, ns: str, config: Config) -> None:
        self.ns = ns
        self.config = config
        self.clock = node.clock
        self.services: list[str] = []
        self.online = True
        self._node = node
        self._subs: list[Any] = []
        self.drone = DroneWrapper(ns, node=node, cameras=(), wait=False)
        self.client = self.drone.client
        self._latest: dict[str, tuple[Latest[Any], float, Callable[[Any], dict[str, Any]]]] = {
            name: (self.client.inputs.latest(topic), topic.rate_hz, fields)
            for name, topic, fields in TELEMETRY
        }
        self.slots: dict[str, Latest[CompressedImage]] = {
            camera: Latest(name=f"{ns} {camera} video", clock=node.clock) for camera in CAMERAS
        }
        self._viewers = dict.fromkeys(CAMERAS, 0)
        self._video_subs: dict[str, Any] = {}
        self._video_lock = threading.Lock()
        self.deadman = DeadMan(config.teleop.timeout)
        self._command_lock = threading.Lock()
        self.last_command: dict[str, Any] | None = None

    def _subscribe(self, topic: Topic[T], callback: Callable[[T], None], **parts: str) -> Any:
        sub = self._node.subscribe(topic, callback, key=topic.key(self.ns, **parts))
        self._subs.append(sub)
        return sub

    # ---- telemetry

    def value(self, section: str) -> Any:
        """The newest message of a telemetry section, or None."""
        return self._latest[section][0].value

    def snapshot(self) -> dict[str, Any]:
        """Every telemetry section with ages and stale flags, the log and the command."""
        out: dict[str, Any] = {"ns": self.ns, "online": self.online, "services": self.services}
        for name, (holder, rate, fields) in self._latest.items():
            msg = holder.value
            out[name] = snapshot.section(
                None if msg is None else fields(msg),
                holder.age(),
                snapshot.stale_limit(rate, self.config.stale_after),
            )
        out["log"] = [snapshot.status_text_entry(m) for m in list(self.drone.status_texts)[-20:]]
        out["command"] = self.last_command
        out["refusals"] = [snapshot.refusal_entry(r) for r in self.drone.refusals[-5:]]
        out["teleop"] = self.deadman.active
        for camera, slot in self.slots.items():
            out[f"video_{camera}_age"] = None if slot.value is None else slot.age()
        return out

    def health(self) -> str:
        """``ok``, ``stale`` (telemetry stopped), ``no_autopilot`` or ``offline``."""
        if not self.online:
            return "offline"
        holder, rate, _ = self._latest["state"]
        state = holder.value
        if state is None or holder.age() > snapshot.stale_limit(rate, self.config.stale_after):
            return "stale"
        return "ok" if state.connected else "no_autopilot"

    # ---- video (subscribed only while someone watches; the sim encodes JPEG only then)

    def watch(self, camera: str) -> Latest[CompressedImage]:
        """Start receiving ``camera``'s JPEG frames (counted per viewer)."""
        key_name = CAMERAS[camera]
        slot = self.slots[camera]
        with self._video_lock:
            self._viewers[camera] += 1
            if camera not in self._video_subs:
                self._video_subs[camera] = self._subscribe(
                    registry.IMAGE_COMPRESSED, slot.update, camera=key_name
                )
        return slot

    def unwatch(self, camera: str) -> None:
        """Stop receiving ``camera`` when its last viewer left."""
        with self._video_lock:
            self._viewers[camera] = max(0, self._viewers[camera] - 1)
            if self._viewers[camera] == 0 and camera in self._video_subs:
                sub = self._video_subs.pop(camera)
                self._subs.remove(sub)
                sub.undeclare()

    # ---- commands (blocking: run them on a worker thread)

    def _note(self, what: str, **fields: Any) -> None:
        self.last_command = {"what": what, "at": self.clock.time(), **fields}

    def teleop(self, cmd: VelocityCommand, owner: object) -> None:
        """Velocity teleop, body FLU; must be renewed within the teleop timeout."""
        self.deadman.renew(self.clock(), owner)
        self.drone.set_cmd_vel(cmd.vx, cmd.vy, cmd.vz, cmd.yaw_rate)
        self._note("velocity", vx=cmd.vx, vy=cmd.vy, vz=cmd.vz, yaw_rate=cmd.yaw_rate)

    def release(self, owner: object | None = None) -> None:
        """The page let go of the sticks (or left): hold where the drone is."""
        if owner is not None and self.deadman.owner is not owner:
            return
        if self.deadman.release():
            self.hold()

    def check_deadman(self) -> None:
        """Hold if the velocity teleop was not renewed in time (called periodically)."""
        if self.deadman.expired(self.clock()):
            log.info("%s: teleop not renewed within %g s: holding", self.ns, self.deadman.timeout)
            self.hold()

    def hold(self) -> None:
        """Hold position where the drone is now (a position setpoint); on the ground, or
        outside the envelope (the bridge's breach action flies it), stop commanding."""
        with self._command_lock:
            self.deadman.release()
            pose = self.value("pose")
            landed = self.value("landed")
            on_ground = landed is not None and landed.landed_state == LANDED_STATE_ON_GROUND
            if pose is None or on_ground:
                self.drone.stop_commanding()
                self._note("stop")
                return
            f = snapshot.pose_fields(pose)
            try:
                self.drone.set_cmd_pos(f["x"], f["y"], f["z"], f["yaw"])
            except CommandRefused as exc:
                self.drone.stop_commanding()
                self._note("stop", refused=exc.reason)
                return
            self._note("hold", x=f["x"], y=f["y"], z=f["z"])

    def goto(self, x: float, y: float) -> None:
        """Fly to local ENU (x, y) at the current altitude and heading."""
        pose = self.value("pose")
        if pose is None:
            raise RuntimeError(f"{self.ns}: no position yet, cannot go to a point")
        with self._command_lock:
            self.deadman.release()
            f = snapshot.pose_fields(pose)
            self.drone.set_cmd_pos(x, y, f["z"], f["yaw"])
            self._note("goto", x=x, y=y, z=f["z"])

    def takeoff(self, height: float) -> None:
        self.deadman.release()
        self._note("takeoff", height=height)
        self.drone.takeoff(height, timeout=self.config.command_timeout)

    def land(self) -> None:
        self.deadman.release()
        self._note("land")
        self.drone.land(timeout=self.config.command_timeout)

    def upload_plan(self, plan: dict[str, Any]) -> None:
        """Upload a QGroundControl ``.plan`` document as the drone's mission."""
        self._note("upload_plan")
        self.drone.upload_mission(plan)

    def start_mission(self) -> None:
        self.deadman.release()
        self._note("start_mission")
        self.drone.start_mission()

    def pause_mission(self) -> None:
        self._note("pause_mission")
        self.drone.pause_mission()

    def return_to_launch(self) -> None:
        self.deadman.release()
        self._note("return_to_launch")
        self.drone.return_to_launch(timeout=self.config.command_timeout)

    def reset(self) -> None:
        """Put this simulated drone back at its start pose, landed (``{ns}/sim/world/reset``).

        Raises:
            NotConnected: no simulator answers for this drone (a real aircraft).
            CommandRefused: the simulator could not reset it.
        """
        self.deadman.release()
        self.drone.stop_commanding()
        self._note("reset")
        try:
            reply = self._node.call(
                registry.SIM_RESET, VehicleReset(), ns=self.ns, timeout=self.config.command_timeout
            )
        except ServiceUnavailable:
            raise NotConnected(f"{self.ns}: no simulator answers: a real aircraft?") from None
        except ServiceError as exc:
            raise CommandRefused("reset", exc.message) from None
        if not reply.success:
            raise CommandRefused("reset", reply.message)

    def arm(self) -> None:
        self.drone.arm()

    def disarm(self) -> None:
        self.drone.disarm()

    def set_mode(self, mode: str) -> None:
        self.drone.set_mode(mode)

    def close(self) -> None:
        self.drone.close()
        undeclare(self._subs)


class Fleet:
    """Every drone the station shows, found by their bridges' liveliness tokens.

    Args:
        node: the station's node (``linked()`` says whether its router is reachable).
        config: the station config (``namespaces`` fixes the list; empty: discover).
    """

    def __init__(self, node: NodeApi, config: Config) -> None:
        self.node = node
        self.config = config
        self.clock = node.clock
        self.router_linked = True
        self.links: dict[str, DroneLink] = {}
        self.objects = SimObjects(node)
        self._lock = threading.Lock()
        for ns in config.namespaces:
            self.links[ns] = self._link(ns)

    def _link(self, ns: str) -> DroneLink:
        return DroneLink(self.node, ns, self.config)

    def discover(self) -> None:
        """Whether the router is linked; list the processes alive now; add new drones, mark
        vanished ones offline."""
        linked = self.node.linked()
        if linked != self.router_linked:
            endpoint = self.router()["endpoint"]
            if linked:
                log.info("router reached at %s", endpoint)
            else:
                log.warning(
                    "no router reachable at %s: the page shows no drone until one runs there "
                    "(dronewrapper router, or dronewrapper up GRAPH), or give --connect",
                    endpoint,
                )
        self.router_linked = linked
        by_ns = services_by_namespace(self.node.alive_services("*"))
        for ns, names in by_ns.items():
            has_bridge = any(name.startswith(BRIDGE_PREFIX) for name in names)
            if ns not in self.links and has_bridge and not self.config.namespaces:
                log.info("drone online: %s (%s)", ns, ", ".join(names))
                with self._lock:
                    self.links[ns] = self._link(ns)
        for ns, link in self.links.items():
            link.services = by_ns.get(ns, [])
            link.online = any(name.startswith(BRIDGE_PREFIX) for name in link.services)

    def router(self) -> dict[str, Any]:
        """The station's link to its router: ``linked`` and the ``endpoint`` it connects to."""
        options = getattr(self.node, "options", None)
        endpoint = ", ".join(getattr(options, "connect", None) or []) or "the router"
        return {"linked": self.router_linked, "endpoint": endpoint}

    def get(self, ns: str) -> DroneLink:
        """The drone ``ns``. Raises KeyError if the station does not know it."""
        return self.links[ns]

    def summary(self) -> list[dict[str, Any]]:
        """The drones to pick from, each with its health and services."""
        return [
            {"ns": ns, "health": link.health(), "services": link.services}
            for ns, link in sorted(self.links.items())
        ]

    def land_all(self) -> dict[str, str]:
        """Land every drone online at once; ``{ns: "landed" or why not}``, each on its own
        thread so that one slow drone delays nobody else."""
        links = {ns: link for ns, link in list(self.links.items()) if link.online}
        outcomes: dict[str, str] = {}

        def land(ns: str, link: DroneLink) -> None:
            try:
                link.land()
                outcomes[ns] = "landed"
            except Exception as exc:
                outcomes[ns] = str(exc)

        threads = [threading.Thread(target=land, args=item, daemon=True) for item in links.items()]
        for thread in threads:
            thread.start()
        for thread in threads:
            thread.join()
        return dict(sorted(outcomes.items()))

    def check_deadmen(self) -> None:
        for link in list(self.links.values()):
            link.check_deadman()

    def release_owner(self, owner: object) -> None:
        """A page went away: every drone it was driving holds."""
        for link in list(self.links.values()):
            link.release(owner)

    def close(self) -> None:
        for link in self.links.values():
            link.close()
        self.objects.close()
