"""A bridge's keys on the fake bus, in injected time, for tests of what commands an aircraft.

:class:`BusAutopilot` serves SET_MODE, ARMING, TAKEOFF, LAND, PARAM_GET and PARAM_SET on a
:class:`~dronewrapper.runtime.fake.FakeNode` and publishes State, ExtendedState, the local
pose, the velocities and the battery each time it is ticked (and a status text with each
refusal). Its aircraft climbs or sinks at 1 m/s towards the height of the
newest position setpoint (PX4 OFFBOARD) or of a TAKEOFF request while armed; LAND puts it on
the ground, disarmed. It is not the bridge (tests/integration/test_bridge_* test that): only enough
of its contract for a commander's logic, with every request recorded in ``calls``.

:func:`drive` runs steppers (anything with ``step(now)`` and ``next_wake(now)``) and the
autopilot on the bus until a given time, delivering scheduled messages in order.
:class:`SdkRig` is the user's :class:`~dronewrapper.drone.DroneWrapper` on that bus, its
blocking calls waiting in bus time.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable

from dronewrapper import DroneWrapper
from dronewrapper.msgs import registry
from dronewrapper.msgs.geometry import (
    Point,
    Pose,
    PoseStamped,
    Quaternion,
    Twist,
    TwistStamped,
    Vector3,
)
from dronewrapper.msgs.mavros import (
    LANDED_STATE_IN_AIR,
    LANDED_STATE_ON_GROUND,
    MASK_POSITION,
    CommandBoolResult,
    CommandTOLResult,
    ExtendedState,
    ParamGetResult,
    ParamSetResult,
    ParamValue,
    PositionTarget,
    SetModeResult,
    State,
    StatusText,
)
from dronewrapper.msgs.sensor import BatteryState
from dronewrapper.msgs.std import Header
from dronewrapper.runtime.fake import FakeBus, FakeNode

T0 = 1_700_000_000.0
"""Bus time the rigs start at (s, Unix time)."""
TELEMETRY_PERIOD_S = 0.05  # 20 Hz, the real bridge's pose rate is higher; enough here
CLIMB_RATE = 1.0  # m/s
REFUSED = 4  # MAV_RESULT_FAILED, the result code of every refusal
YAW_RATE = 0.25  # rad/s, the body yaw rate it reports
BATTERY = 0.8  # the charge it reports (fraction)


class BusAutopilot:
    """A simple aircraft behind the bridge's keys (see the module doc).

    Args:
        bus: the fake bus.
        flying: start in the air at 2 m, armed in OFFBOARD (else on the ground, disarmed).
        autopilot: ``State.autopilot`` (``px4``, ``ardupilotmega``, ``tello``).
        refuse: service name (``set_mode``, ``arming``, ``takeoff``, ``land``) -> the reason
            given when refusing it.
        absent: services not served at all (a call gets no reply).
        x: the east position it reports (m; the take-off point is at x, 0, 0).
    """

    def __init__(
        self,
        bus: FakeBus,
        *,
        flying: bool,
        autopilot: str = "px4",
        refuse: dict[str, str] | None = None,
        absent: Iterable[str] = (),
        ns: str = "drone",
        x: float = 0.0,
    ) -> None:
        self.bus = bus
        self.x = x
        self.node = FakeNode("bridge_fake", bus, ns=ns)
        self.autopilot = autopilot
        self.connected = True
        self.armed = flying
        self.mode = "OFFBOARD" if flying else "AUTO.LOITER"
        self.z = 2.0 if flying else 0.0
        self.z_goal = self.z
        self.landed = LANDED_STATE_IN_AIR if flying else LANDED_STATE_ON_GROUND
        self.calls: list[tuple[float, str]] = []
        self.requests: list = []  # every service request, as received
        self.refuse = refuse or {}
        self.z_at_first_velocity: float | None = None
        self.params: dict[str, ParamValue] = {"MPC_XY_VEL_MAX": ParamValue(real=12.0)}
        self._last_tick: float | None = None
        self._state = self.node.publisher(registry.STATE)
        self._ext = self.node.publisher(registry.EXTENDED_STATE)
        self._pose = self.node.publisher(registry.LOCAL_POSE)
        self._velocity_body = self.node.publisher(registry.VELOCITY_BODY)
        self._velocity_local = self.node.publisher(registry.VELOCITY_LOCAL)
        self._battery = self.node.publisher(registry.BATTERY)
        self._text = self.node.publisher(registry.STATUSTEXT)
        self.node.subscribe(registry.SETPOINT_RAW_LOCAL, self._on_setpoint)
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
                self.node.serve(service, handler)

    # ---- the services ----

    def _refused(self, name: str, request) -> str:
        """Record the call; the reason it is refused for ("": accepted), said as a text too."""
        self.calls.append((self.bus.clock(), name))
        self.requests.append(request)
        reason = self.refuse.get(name, "")
        if reason:
            self.say(reason)
        return reason

    def say(self, text: str) -> None:
        """Publish an autopilot text message now."""
        self._text.put(StatusText(header=Header(stamp=self.bus.clock()), text=text))

    def _set_mode(self, req) -> SetModeResult:
        reason = self._refused("set_mode", req)
        if reason:
            return SetModeResult(mode_sent=False, result=REFUSED, message=reason)
        self.mode = req.custom_mode
        return SetModeResult(mode_sent=True, result=0)

    def _arming(self, req) -> CommandBoolResult:
        reason = self._refused("arming", req)
        if reason:
            return CommandBoolResult(success=False, result=REFUSED, message=reason)
        self.armed = req.value
        return CommandBoolResult(success=True, result=0)

    def _takeoff(self, req) -> CommandTOLResult:
        reason = self._refused("takeoff", req)
        if reason:
            return CommandTOLResult(success=False, result=REFUSED, message=reason)
        self.armed = True
        self.z_goal = req.altitude
        return CommandTOLResult(success=True, result=0)

    def _land(self, req) -> CommandTOLResult:
        reason = self._refused("land", req)
        if reason:
            return CommandTOLResult(success=False, result=REFUSED, message=reason)
        self.mode, self.z, self.z_goal = "AUTO.LAND", 0.0, 0.0
        self.landed, self.armed = LANDED_STATE_ON_GROUND, False
        return CommandTOLResult(success=True, result=0)

    def _param_get(self, req) -> ParamGetResult:
        if req.param_id not in self.params:
            return ParamGetResult(success=False, message=f"no parameter {req.param_id}")
        return ParamGetResult(success=True, value=self.params[req.param_id])

    def _param_set(self, req) -> ParamSetResult:
        self.params[req.param_id] = req.value
        return ParamSetResult(success=True, value=req.value)

    def _on_setpoint(self, sp: PositionTarget) -> None:
        if sp.type_mask == MASK_POSITION:
            if self.armed:
                self.z_goal = sp.position.z
        elif self.z_at_first_velocity is None:
            self.z_at_first_velocity = self.z

    # ---- telemetry ----

    def tick(self, now: float) -> None:
        """Move the aircraft to ``now`` (bus time, s) and publish its telemetry."""
        dt = 0.0 if self._last_tick is None else now - self._last_tick
        self._last_tick = now
        if self.armed:
            step = CLIMB_RATE * dt
            self.z += max(-step, min(step, self.z_goal - self.z))
            if self.z > 0.1:
                self.landed = LANDED_STATE_IN_AIR
        header = Header(stamp=now)
        self._state.put(
            State(
                header=header,
                connected=self.connected,
                armed=self.armed,
                guided=self.mode in ("OFFBOARD", "GUIDED"),
                mode=self.mode,
                autopilot=self.autopilot,
            )
        )
        self._ext.put(ExtendedState(header=header, landed_state=self.landed))
        pose = Pose(position=Point(x=self.x, z=self.z), orientation=Quaternion(w=1.0))
        self._pose.put(PoseStamped(header=Header(stamp=now, frame_id="map"), pose=pose))
        turning = Twist(angular=Vector3(z=YAW_RATE))
        self._velocity_body.put(TwistStamped(header=header, twist=turning))
        self._velocity_local.put(TwistStamped(header=header))
        self._battery.put(BatteryState(header=header, percentage=BATTERY))

    def next_wake(self, now: float) -> float:
        return (self._last_tick if self._last_tick is not None else now) + TELEMETRY_PERIOD_S

    def step(self, now: float) -> None:
        if self._last_tick is None or now >= self.next_wake(now):
            self.tick(now)

    # ---- what was commanded ----

    def setpoints(self, since: float = -math.inf) -> list[tuple[float, PositionTarget]]:
        """(bus time, setpoint) of every setpoint published since ``since``."""
        key = registry.SETPOINT_RAW_LOCAL.key(self.node.ns)
        return [(d.time, d.msg) for d in self.bus.published[key] if d.time >= since]

    def called(self, name: str) -> int:
        return sum(1 for _, n in self.calls if n == name)


def drive(bus: FakeBus, until: float, *steppers, stop: Callable[[], bool] = lambda: False) -> None:
    """Run ``steppers`` on the bus until bus time ``until`` or ``stop()``: each is stepped at
    every wake; the bus moves to the earliest of their next wakes and the next scheduled
    message (delivered first)."""
    while bus.clock() < until and not stop():
        now = bus.clock()
        for stepper in steppers:
            stepper.step(now)
        if stop():
            return
        wake = min([until, *(s.next_wake(now) for s in steppers)])
        wake = max(wake, now + 1e-6)  # always move on
        queued = bus.next_time()
        if queued is not None and queued <= wake:
            bus.step()
        else:
            bus.clock.advance_to(wake)


class SdkRig:
    """A :class:`DroneWrapper` on the fake bus with a :class:`BusAutopilot` behind it: its
    blocking calls (take-off, landing, ``wait_for``) move the bus time, ticking the aircraft
    and running what :meth:`at` scheduled, instead of sleeping; the getters' ages are bus time
    too. Its setpoint stream repeats on its own thread (tests/unit/test_sdk_streamer* test
    that); a new setpoint goes out at once.

    ``autopilot`` takes :class:`BusAutopilot`'s arguments; ``drone`` DroneWrapper's
    (:meth:`options`); ``open_drone=False`` leaves ``drone`` None (an aio Drone opens one).
    """

    def __init__(self, autopilot: dict | None = None, *, open_drone: bool = True, **drone) -> None:
        self.bus = FakeBus(start=T0)
        self.pilot = BusAutopilot(self.bus, **{"flying": False, **(autopilot or {})})
        self.node = FakeNode("app", self.bus)
        self._actions: list[tuple[float, Callable[[], None]]] = []
        self.drone = DroneWrapper("drone", **self.options(**drone)) if open_drone else None
        self.run(TELEMETRY_PERIOD_S)  # the first telemetry is in

    def options(self, **drone) -> dict:
        """DroneWrapper's arguments for a wrapper on this bus, in its time."""
        return {
            "node": self.node,
            "clock": self.bus.clock,
            "sleep": self.run,
            "wait": False,
            **drone,
        }

    def at(self, delay: float, action: Callable[[], None]) -> None:
        """Run ``action`` once ``delay`` s of bus time have passed (while a call blocks)."""
        self._actions.append((self.bus.clock() + delay, action))

    def step(self, now: float) -> None:
        due = [a for a in self._actions if a[0] <= now]
        self._actions = [a for a in self._actions if a[0] > now]
        for _, action in due:
            action()

    def next_wake(self, now: float) -> float:
        return min((t for t, _ in self._actions), default=math.inf)

    def run(self, seconds: float) -> None:
        """Move the bus ``seconds`` on, ticking the aircraft."""
        drive(self.bus, self.bus.clock() + seconds, self, self.pilot)

    def close(self) -> None:
        self.drone.close()
