"""A small fake of the bridge built from the runtime, on a real Zenoh router: the one test copy.

It holds the bridge's keys like the real one (State, ExtendedState, pose, velocities, battery,
a frontal camera, status text; the ARMING, SET_MODE, TAKEOFF, LAND, PARAM_GET and PARAM_SET
services), records every request and setpoint, and flies a toy aircraft at 20 Hz: when armed,
the altitude moves 0.2 m a tick (4 m/s) toward the newest position setpoint in OFFBOARD
(velocity setpoints keep that goal) or a TAKEOFF command's altitude; a landing descends the
same way, then disarms. It lets the SDK, the controller and the ground station tests check
their side of the contract precisely (order of calls, keys, masks, rates, error messages) in a
fraction of a second per test.
"""

from __future__ import annotations

import math
import threading
import time
from typing import Any

import numpy as np

from dronewrapper.msgs import registry
from dronewrapper.msgs.geometry import Point, Pose, PoseStamped, Twist, TwistStamped, Vector3
from dronewrapper.msgs.mavros import (
    LANDED_STATE_IN_AIR,
    LANDED_STATE_ON_GROUND,
    MASK_POSITION,
    MASK_VELOCITY,
    MAV_RESULT_DENIED,
    CommandBool,
    CommandBoolResult,
    CommandTOL,
    CommandTOLResult,
    ExtendedState,
    ParamGet,
    ParamGetResult,
    ParamSet,
    ParamSetResult,
    ParamValue,
    PositionTarget,
    SetMode,
    SetModeResult,
    State,
    StatusText,
)
from dronewrapper.msgs.sensor import BatteryState, Image
from dronewrapper.msgs.std import Header
from dronewrapper.runtime import Ratekeeper
from support import client_node, wait_for

MODES = ("OFFBOARD", "POSCTL", "AUTO.LOITER", "AUTO.LAND", "GUIDED")
"""The modes this bridge knows; another is refused (result 4, ``unknown mode NAME``)."""
STEP_M = 0.2
"""Largest altitude change a tick (m; 4 m/s at 20 Hz)."""


class FakeBridge:
    """A PX4-like bridge in one thread: services, telemetry at 20 Hz, a toy climb/descent.

    ``flying``: start armed in OFFBOARD at ``position``'s altitude (2 m when that is 0).
    ``objects``: simulated object poses (name -> x, y, z in m, ENU) published each tick.
    """

    def __init__(
        self,
        endpoint: str,
        ns: str = "drone",
        *,
        connected: bool = True,
        autopilot: str = "px4",
        flying: bool = False,
        position: tuple[float, float, float] = (1.0, 0.0, 0.0),
        objects: dict[str, tuple[float, float, float]] | None = None,
        name: str = "bridge_fake",
    ) -> None:
        self.node = client_node(endpoint, name=name, namespace=ns, mode="client")
        self.connected = connected
        self.autopilot = autopilot
        self.x, self.y, self.z = position
        if flying and self.z == 0.0:
            self.z = 2.0
        self.armed = flying
        self.mode = "OFFBOARD" if flying else "POSCTL"
        self.climb_to: float | None = None  # a TAKEOFF command's altitude (ArduPilot, Tello)
        self.z_goal: float | None = None  # the newest position setpoint's altitude
        self.landing = False
        self.refuse_arming = ""
        self.calls: list[str] = []  # "arming True", "set_mode OFFBOARD", "takeoff 1", "land"
        self.requests: list[Any] = []  # every service request, as received
        self.land_requests: list[CommandTOL] = []
        self.params: dict[str, ParamValue] = {"MPC_XY_VEL_MAX": ParamValue(real=12.0)}
        self.setpoints: list[tuple[float, PositionTarget]] = []  # (monotonic arrival s, msg)
        self.z_at_first_velocity: float | None = None  # altitude when the first one arrived
        self.objects = dict(objects or {})
        self.silent: set[str] = set()  # keys of streams this bridge leaves out
        self.paused = False  # publish nothing (a stalled link)
        self.lock = threading.Lock()
        n = self.node
        self.pub_state = n.publisher(registry.STATE)
        self.pub_ext = n.publisher(registry.EXTENDED_STATE)
        self.pub_pose = n.publisher(registry.LOCAL_POSE)
        self.pub_vel = n.publisher(registry.VELOCITY_BODY)
        self.pub_vel_local = n.publisher(registry.VELOCITY_LOCAL)
        self.pub_battery = n.publisher(registry.BATTERY)
        self.pub_text = n.publisher(registry.STATUSTEXT)
        self.pub_image = n.publisher(registry.IMAGE_RAW, camera="cam_frontal")
        self.pub_objects = {
            name: n.publisher(registry.SIM_OBJECT_POSE, name=name) for name in self.objects
        }
        n.subscribe(registry.SETPOINT_RAW_LOCAL, self._on_setpoint)
        n.serve(registry.ARMING, self._arming)
        n.serve(registry.SET_MODE, self._set_mode)
        n.serve(registry.LAND, self._land)
        n.serve(registry.TAKEOFF, self._takeoff)
        n.serve(registry.PARAM_GET, self._param_get)
        n.serve(registry.PARAM_SET, self._param_set)
        n.announce()
        self.thread = threading.Thread(target=self._run, daemon=True)
        self.thread.start()

    @property
    def in_air(self) -> bool:
        return self.armed and self.z > 0.05

    @property
    def land_calls(self) -> int:
        return len(self.land_requests)

    # services
    def _arming(self, req: CommandBool) -> CommandBoolResult:
        self.requests.append(req)
        self.calls.append(f"arming {req.value}")
        if req.value and self.refuse_arming:
            self.pub_text.put(StatusText(text=self.refuse_arming, severity=2))
            return CommandBoolResult(
                success=False, result=MAV_RESULT_DENIED, message=self.refuse_arming
            )
        if not req.value and self.in_air:
            return CommandBoolResult(
                success=False, result=MAV_RESULT_DENIED, message="disarming denied in flight"
            )
        self.armed = req.value
        return CommandBoolResult(success=True, result=0)

    def _set_mode(self, req: SetMode) -> SetModeResult:
        self.requests.append(req)
        self.calls.append(f"set_mode {req.custom_mode}")
        if req.custom_mode not in MODES:
            return SetModeResult(
                mode_sent=False, result=4, message=f"unknown mode {req.custom_mode}"
            )
        # like the real bridge, give the stream a moment (it primes for > 1 s before asking, and
        # waits up to 3 s more for a stream); generous here for a busy machine
        deadline = time.monotonic() + 5.0
        while req.custom_mode == "OFFBOARD" and not self.setpoints and time.monotonic() < deadline:
            time.sleep(0.01)
        if req.custom_mode == "OFFBOARD" and not self.setpoints:
            return SetModeResult(mode_sent=False, result=4, message="no setpoint stream")
        self.mode = req.custom_mode
        return SetModeResult(mode_sent=True, result=0)

    def _takeoff(self, req: CommandTOL) -> CommandTOLResult:
        self.requests.append(req)
        self.calls.append(f"takeoff {req.altitude:g}")
        if self.autopilot == "tello":
            self.armed = True  # a Tello arms and lifts off on "takeoff"
        if not self.armed:
            return CommandTOLResult(success=False, result=4, message="not armed")
        self.climb_to = req.altitude
        return CommandTOLResult(success=True, result=0)

    def _land(self, req: CommandTOL) -> CommandTOLResult:
        self.requests.append(req)
        self.calls.append("land")
        self.land_requests.append(req)
        self.climb_to = None
        self.mode, self.landing = "AUTO.LAND", True
        return CommandTOLResult(success=True, result=0)

    def _param_get(self, req: ParamGet) -> ParamGetResult:
        self.requests.append(req)
        if req.param_id not in self.params:
            return ParamGetResult(success=False, message=f"no parameter {req.param_id}")
        return ParamGetResult(success=True, value=self.params[req.param_id])

    def _param_set(self, req: ParamSet) -> ParamSetResult:
        self.requests.append(req)
        self.params[req.param_id] = req.value
        return ParamSetResult(success=True, value=req.value)

    def _on_setpoint(self, msg: PositionTarget) -> None:
        with self.lock:
            self.setpoints.append((time.monotonic(), msg))
            if msg.type_mask == MASK_VELOCITY and self.z_at_first_velocity is None:
                self.z_at_first_velocity = self.z
            if msg.type_mask == MASK_POSITION:
                self.z_goal = msg.position.z

    # what the tests read
    def setpoints_since(self, t0: float) -> list[PositionTarget]:
        with self.lock:
            return [msg for t, msg in self.setpoints if t >= t0]

    def velocity_setpoints(self, since: float = 0.0) -> list[PositionTarget]:
        return [sp for sp in self.setpoints_since(since) if sp.type_mask == MASK_VELOCITY]

    def last_command(self) -> tuple[float, float, float] | None:
        """(vx, vz, yaw_rate) of the newest velocity setpoint, None before the first."""
        sps = self.velocity_setpoints()
        return (sps[-1].velocity.x, sps[-1].velocity.z, sps[-1].yaw_rate) if sps else None

    def wait_quiet(self, quiet: float = 0.5, timeout: float = 10.0) -> None:
        """Wait until no setpoint has arrived for ``quiet`` s (fails if the stream goes on).

        Setpoints already in flight when a stream stops still arrive meanwhile.
        """

        def silent_for() -> float:
            with self.lock:
                last = self.setpoints[-1][0] if self.setpoints else -math.inf
            return time.monotonic() - last

        wait_for(lambda: silent_for() >= quiet, timeout, what="the setpoint stream to stop")

    def publish_image(self, image: np.ndarray, stamp: float) -> None:
        h, w, _ = image.shape
        self.pub_image.put(
            Image(header=Header(stamp=stamp), height=h, width=w, step=w * 3, data=image.tobytes())
        )

    # the aircraft
    def _step(self) -> None:
        if self.landing:
            self.z = max(0.0, self.z - STEP_M)
            if self.z == 0.0:
                self.armed, self.landing = False, False
        elif self.armed and self.mode == "OFFBOARD" and self.z_goal is not None:
            self.z += max(-STEP_M, min(STEP_M, self.z_goal - self.z))
        elif self.armed and self.climb_to is not None:
            self.z += max(-STEP_M, min(STEP_M, self.climb_to - self.z))

    def _publish(self) -> None:
        header = Header(stamp=time.time())
        self.pub_state.put(
            State(
                header=header,
                connected=self.connected,
                armed=self.armed,
                guided=self.mode == "OFFBOARD",
                mode=self.mode,
                autopilot=self.autopilot,
            )
        )
        landed = LANDED_STATE_IN_AIR if self.in_air else LANDED_STATE_ON_GROUND
        self.pub_ext.put(ExtendedState(header=header, landed_state=landed))
        position = Point(x=self.x, y=self.y, z=self.z)
        self.pub_pose.put(PoseStamped(header=header, pose=Pose(position=position)))
        turning = Twist(angular=Vector3(z=0.25))
        self.pub_vel.put(TwistStamped(header=header, twist=turning))
        for pub, msg in (
            (self.pub_vel_local, TwistStamped(header=header)),
            (self.pub_battery, BatteryState(header=header, percentage=0.8)),
        ):
            if pub.key not in self.silent:
                pub.put(msg)
        for name, (x, y, z) in self.objects.items():
            pose = Pose(position=Point(x=x, y=y, z=z))
            self.pub_objects[name].put(PoseStamped(header=header, pose=pose))

    def _run(self) -> None:
        rate = Ratekeeper(20, stop=self.node.stop_event)
        while rate.sleep():
            self._step()
            if self.paused:
                continue
            try:
                self._publish()
            except Exception:
                return

    def close(self) -> None:
        self.node.close()
        self.thread.join(5)
