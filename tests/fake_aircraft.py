"""A toy aircraft behind the bridge's keys, for the tests of what commands one: the one model.

:class:`FakeAircraft` declares on a node (a real :class:`~dronewrapper.runtime.node.Node` or a
:class:`~dronewrapper.runtime.fake.FakeNode`, whichever is given) what a bridge publishes and
serves: State, ExtendedState, the local pose, the velocities, the battery and status texts
(simulated objects' poses, and a camera's image key declared but silent, when asked); the
ARMING, SET_MODE, TAKEOFF, LAND, PARAM_GET and PARAM_SET services. It has no thread and reads
no clock but the one it is given: :meth:`FakeAircraft.tick` moves it to ``now`` and publishes
its telemetry stamped ``now``.

The aircraft: while armed it climbs or sinks at ``climb_rate`` toward its goal altitude, the
newest of a TAKEOFF request's and (in OFFBOARD or GUIDED) a position setpoint's; velocity
setpoints keep the goal. LAND descends at ``landing_speed`` and disarms on the ground. It
refuses what an autopilot refuses, saying why in the reply and in a status text: a refusal set
in ``refuse``, an unknown mode, OFFBOARD before any setpoint (when ``offboard_needs_stream``), a
take-off while disarmed (a Tello arms itself), disarming in flight. Every request is recorded.

It is not the bridge (tests/service/test_bridge_* test that): only enough of its contract for
the SDK, the controller, the commander and the ground station. Two ways to run it:
tests/bus_autopilot.py (``BusAutopilot``: the fake bus, ticked in bus time) and
tests/fake_bridge.py (``FakeBridge``: a real Zenoh router, ticked by its own thread at 20 Hz).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable
from typing import TYPE_CHECKING, Any

from dronewrapper import msgs
from dronewrapper.msgs import registry
from dronewrapper.msgs.mavros import (
    LANDED_STATE_IN_AIR,
    LANDED_STATE_ON_GROUND,
    MASK_POSITION,
    MASK_VELOCITY,
    SEVERITY_CRITICAL,
)

if TYPE_CHECKING:
    from dronewrapper.runtime.fake import FakeNode
    from dronewrapper.runtime.node import Node

REFUSED = 4
"""MAV_RESULT_FAILED: the result code of every refusal."""
GUIDED_MODES = ("OFFBOARD", "GUIDED")
"""The modes that follow position setpoints (PX4, ArduPilot); State.guided in them."""
IN_AIR_ABOVE_M = 0.1
"""Armed above this altitude (m) is in the air; a landing touches down below it."""
YAW_RATE = 0.25
"""The body yaw rate it reports (rad/s)."""
BATTERY = 0.8
"""The charge it reports (fraction)."""


class FakeAircraft:
    """A simple aircraft behind the bridge's keys on ``node`` (see the module doc).

    Args:
        node: where it publishes and serves (``publisher``, ``subscribe``, ``serve``).
        clock: the time requests and status texts are stamped with (s).
        flying: start armed in OFFBOARD at ``position``'s altitude (2 m when that is 0),
            else on the ground, disarmed, in ``ground_mode``.
        autopilot: ``State.autopilot`` (``px4``, ``ardupilotmega``, ``tello``).
        position: where it is (x, y, z in m, ENU); only the altitude moves.
        climb_rate: vertical speed toward the goal altitude (m/s).
        landing_speed: descent speed after LAND (m/s); ``math.inf``: on the ground at once.
        ground_mode: the mode it starts in on the ground.
        modes: the modes SET_MODE accepts (``unknown mode NAME`` for another); None: any.
        offboard_needs_stream: refuse OFFBOARD until a setpoint has arrived (as PX4 does).
        camera: declare the image stream of this camera (``pub_image``; nothing is sent).
        objects: simulated object poses (name -> x, y, z in m, ENU) published each tick.
        refuse: service name (``set_mode``, ``arming``, ``takeoff``, ``land``) -> the reason
            given when refusing it (a dict the tests may change).
        absent: services not served at all (a call gets no reply).
    """

    def __init__(
        self,
        node: Node | FakeNode,
        clock: Callable[[], float],
        *,
        flying: bool = False,
        autopilot: str = "px4",
        position: tuple[float, float, float] = (0.0, 0.0, 0.0),
        climb_rate: float = 1.0,
        landing_speed: float = math.inf,
        ground_mode: str = "AUTO.LOITER",
        modes: Iterable[str] | None = None,
        offboard_needs_stream: bool = False,
        camera: str | None = None,
        objects: dict[str, tuple[float, float, float]] | None = None,
        refuse: dict[str, str] | None = None,
        absent: Iterable[str] = (),
    ) -> None:
        self.node = node
        self.clock = clock
        self.autopilot = autopilot
        self.climb_rate = climb_rate
        self.landing_speed = landing_speed
        self.modes = None if modes is None else tuple(modes)
        self.offboard_needs_stream = offboard_needs_stream
        self.x, self.y, self.z = position
        if flying and self.z == 0.0:
            self.z = 2.0
        self.connected = True
        self.armed = flying
        self.mode = "OFFBOARD" if flying else ground_mode
        self.goal = self.z  # the altitude it flies to while armed (m)
        self.landing = False
        self.streamed = False  # a setpoint has arrived
        self.z_at_first_velocity: float | None = None  # altitude when the first one arrived
        self.refuse = refuse if refuse is not None else {}
        self.calls: list[tuple[float, str]] = []  # (clock s, service) of every command
        self.requests: list[Any] = []  # every service request, as received
        self.params: dict[str, msgs.ParamValue] = {"MPC_XY_VEL_MAX": msgs.ParamValue(real=12.0)}
        self.objects = dict(objects or {})
        self.silent: set[str] = set()  # keys of streams left out
        self._last_tick: float | None = None
        self._state = node.publisher(registry.STATE)
        self._ext = node.publisher(registry.EXTENDED_STATE)
        self._pose = node.publisher(registry.LOCAL_POSE)
        self._velocity_body = node.publisher(registry.VELOCITY_BODY)
        self._velocity_local = node.publisher(registry.VELOCITY_LOCAL)
        self._battery = node.publisher(registry.BATTERY)
        self._text = node.publisher(registry.STATUSTEXT)
        self.pub_image = node.publisher(registry.IMAGE_RAW, camera=camera) if camera else None
        self._object_poses = {
            name: node.publisher(registry.SIM_OBJECT_POSE, name=name) for name in self.objects
        }
        node.subscribe(registry.SETPOINT_RAW_LOCAL, self._on_setpoint)
        handlers: dict[str, tuple[registry.Service, Callable]] = {
            "set_mode": (registry.SET_MODE, self._set_mode),
            "arming": (registry.ARMING, self._arming),
            "takeoff": (registry.TAKEOFF, self._takeoff),
            "land": (registry.LAND, self._land),
            "param_get": (registry.PARAM_GET, self._param_get),
            "param_set": (registry.PARAM_SET, self._param_set),
        }
        for name, (service, handler) in handlers.items():
            if name not in absent:
                node.serve(service, handler)

    @property
    def in_air(self) -> bool:
        return self.armed and self.z > IN_AIR_ABOVE_M

    def called(self, name: str) -> int:
        """How many ``name`` commands (``set_mode``, ``arming``, ``takeoff``, ``land``) came."""
        return sum(1 for _, n in self.calls if n == name)

    def say(self, text: str, severity: int = SEVERITY_CRITICAL) -> None:
        """Publish an autopilot text message now."""
        self._text.put(
            msgs.StatusText(header=msgs.Header(stamp=self.clock()), severity=severity, text=text)
        )

    # ---- the services ----

    def _command(self, name: str, request: Any, refusal: str = "") -> str:
        """Record a command; the reason it is refused for ("": accepted), said as a text too:
        the one set in ``refuse``, else ``refusal`` (the aircraft's own)."""
        self.calls.append((self.clock(), name))
        self.requests.append(request)
        reason = self.refuse.get(name, "") or refusal
        if reason:
            self.say(reason)
        return reason

    def _set_mode(self, req: msgs.SetMode) -> msgs.SetModeResult:
        mode = req.custom_mode
        refusal = ""
        if self.modes is not None and mode not in self.modes:
            refusal = f"unknown mode {mode}"
        elif mode == "OFFBOARD" and self.offboard_needs_stream and not self.streamed:
            refusal = "no setpoint stream"
        reason = self._command("set_mode", req, refusal)
        if reason:
            return msgs.SetModeResult(mode_sent=False, result=REFUSED, message=reason)
        self.mode = mode
        return msgs.SetModeResult(mode_sent=True, result=0)

    def _arming(self, req: msgs.CommandBool) -> msgs.CommandBoolResult:
        in_flight = not req.value and self.in_air
        reason = self._command("arming", req, "disarming denied in flight" if in_flight else "")
        if reason:
            return msgs.CommandBoolResult(success=False, result=REFUSED, message=reason)
        self.armed = req.value
        return msgs.CommandBoolResult(success=True, result=0)

    def _takeoff(self, req: msgs.CommandTOL) -> msgs.CommandTOLResult:
        arms_itself = self.autopilot == "tello"  # a Tello arms and lifts off on "takeoff"
        refusal = "" if self.armed or arms_itself else "not armed"
        reason = self._command("takeoff", req, refusal)
        if reason:
            return msgs.CommandTOLResult(success=False, result=REFUSED, message=reason)
        self.armed, self.goal = True, req.altitude
        return msgs.CommandTOLResult(success=True, result=0)

    def _land(self, req: msgs.CommandTOL) -> msgs.CommandTOLResult:
        reason = self._command("land", req)
        if reason:
            return msgs.CommandTOLResult(success=False, result=REFUSED, message=reason)
        self.mode, self.landing = "AUTO.LAND", True
        if self.landing_speed == math.inf:
            self._touch_down()
        return msgs.CommandTOLResult(success=True, result=0)

    def _param_get(self, req: msgs.ParamGet) -> msgs.ParamGetResult:
        self.requests.append(req)
        if req.param_id not in self.params:
            return msgs.ParamGetResult(success=False, message=f"no parameter {req.param_id}")
        return msgs.ParamGetResult(success=True, value=self.params[req.param_id])

    def _param_set(self, req: msgs.ParamSet) -> msgs.ParamSetResult:
        self.requests.append(req)
        self.params[req.param_id] = req.value
        return msgs.ParamSetResult(success=True, value=req.value)

    def _on_setpoint(self, sp: msgs.PositionTarget) -> None:
        self.streamed = True
        if sp.type_mask == MASK_VELOCITY and self.z_at_first_velocity is None:
            self.z_at_first_velocity = self.z
        if sp.type_mask == MASK_POSITION and self.armed and self.mode in GUIDED_MODES:
            self.goal = sp.position.z

    # ---- the flight and the telemetry ----

    def _touch_down(self) -> None:
        self.z = self.goal = 0.0
        self.armed = self.landing = False

    def move(self, dt: float) -> None:
        """Fly ``dt`` s on: toward the goal while armed, down while landing."""
        if self.landing:
            self.z = max(0.0, self.z - self.landing_speed * dt)
            if self.z <= IN_AIR_ABOVE_M:
                self._touch_down()
        elif self.armed:
            step = self.climb_rate * dt
            self.z += max(-step, min(step, self.goal - self.z))

    def tick(self, now: float) -> None:
        """Move the aircraft to ``now`` (s, the clock's time) and publish its telemetry."""
        dt = 0.0 if self._last_tick is None else max(0.0, now - self._last_tick)
        self._last_tick = now
        self.move(dt)
        self.publish(now)

    def publish(self, now: float) -> None:
        """Publish the telemetry, stamped ``now``, but the streams in ``silent``."""
        header = msgs.Header(stamp=now)
        state = msgs.State(
            header=header,
            connected=self.connected,
            armed=self.armed,
            guided=self.mode in GUIDED_MODES,
            mode=self.mode,
            autopilot=self.autopilot,
        )
        landed = LANDED_STATE_IN_AIR if self.in_air else LANDED_STATE_ON_GROUND
        pose = msgs.Pose(position=msgs.Point(x=self.x, y=self.y, z=self.z))
        in_map = msgs.Header(stamp=now, frame_id="map")
        turning = msgs.Twist(angular=msgs.Vector3(z=YAW_RATE))
        for pub, msg in (
            (self._state, state),
            (self._ext, msgs.ExtendedState(header=header, landed_state=landed)),
            (self._pose, msgs.PoseStamped(header=in_map, pose=pose)),
            (self._velocity_body, msgs.TwistStamped(header=header, twist=turning)),
            (self._velocity_local, msgs.TwistStamped(header=header)),
            (self._battery, msgs.BatteryState(header=header, percentage=BATTERY)),
        ):
            if pub.key not in self.silent:
                pub.put(msg)
        for name, (x, y, z) in self.objects.items():
            pose = msgs.Pose(position=msgs.Point(x=x, y=y, z=z))
            self._object_poses[name].put(msgs.PoseStamped(header=header, pose=pose))
