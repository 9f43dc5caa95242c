"""A bridge's keys on the fake bus, in injected time, for tests of what commands an aircraft.

:class:`BusAutopilot` serves SET_MODE, ARMING, TAKEOFF and LAND on a
:class:`~dronewrapper.runtime.fake.FakeNode` and publishes State, ExtendedState and the local
pose each time it is ticked. Its aircraft climbs or sinks at 1 m/s towards the height of the
newest position setpoint (PX4 OFFBOARD) or of a TAKEOFF request while armed; LAND puts it on
the ground, disarmed. It is not the bridge (tests/integration/test_bridge_* test that): only enough
of its contract for a commander's logic, with every request recorded in ``calls``.

:func:`drive` runs steppers (anything with ``step(now)`` and ``next_wake(now)``) and the
autopilot on the bus until a given time, delivering scheduled messages in order.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable

from dronewrapper.msgs import registry
from dronewrapper.msgs.geometry import Point, Pose, PoseStamped, Quaternion
from dronewrapper.msgs.mavros import (
    LANDED_STATE_IN_AIR,
    LANDED_STATE_ON_GROUND,
    MASK_POSITION,
    CommandBoolResult,
    CommandTOLResult,
    ExtendedState,
    PositionTarget,
    SetModeResult,
    State,
)
from dronewrapper.msgs.std import Header
from dronewrapper.runtime.fake import FakeBus, FakeNode

TELEMETRY_PERIOD_S = 0.05  # 20 Hz, the real bridge's pose rate is higher; enough here
CLIMB_RATE = 1.0  # m/s


class BusAutopilot:
    """A simple aircraft behind the bridge's keys (see the module doc).

    Args:
        bus: the fake bus.
        flying: start in the air at 2 m, armed in OFFBOARD (else on the ground, disarmed).
        autopilot: ``State.autopilot`` (``px4``, ``ardupilotmega``, ``tello``).
        refuse: service name (``set_mode``, ``arming``, ``takeoff``, ``land``) -> the reason
            given when refusing it.
        absent: services not served at all (a call gets no reply).
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
    ) -> None:
        self.bus = bus
        self.node = FakeNode("bridge_fake", bus, ns=ns)
        self.autopilot = autopilot
        self.connected = True
        self.armed = flying
        self.mode = "OFFBOARD" if flying else "AUTO.LOITER"
        self.z = 2.0 if flying else 0.0
        self.z_goal = self.z
        self.landed = LANDED_STATE_IN_AIR if flying else LANDED_STATE_ON_GROUND
        self.calls: list[tuple[float, str]] = []
        self.refuse = refuse or {}
        self.z_at_first_velocity: float | None = None
        self._last_tick: float | None = None
        self._state = self.node.publisher(registry.STATE)
        self._ext = self.node.publisher(registry.EXTENDED_STATE)
        self._pose = self.node.publisher(registry.LOCAL_POSE)
        self.node.subscribe(registry.SETPOINT_RAW_LOCAL, self._on_setpoint)
        handlers: dict[str, tuple[registry.Service, Callable]] = {
            "set_mode": (registry.SET_MODE, self._set_mode),
            "arming": (registry.ARMING, self._arming),
            "takeoff": (registry.TAKEOFF, self._takeoff),
            "land": (registry.LAND, self._land),
        }
        for name, (service, handler) in handlers.items():
            if name not in absent:
                self.node.serve(service, handler)

    # ---- the services ----

    def _refused(self, name: str) -> str:
        self.calls.append((self.bus.clock(), name))
        return self.refuse.get(name, "")

    def _set_mode(self, req) -> SetModeResult:
        reason = self._refused("set_mode")
        if reason:
            return SetModeResult(mode_sent=False, result=4, message=reason)
        self.mode = req.custom_mode
        return SetModeResult(mode_sent=True, result=0)

    def _arming(self, req) -> CommandBoolResult:
        reason = self._refused("arming")
        if reason:
            return CommandBoolResult(success=False, result=4, message=reason)
        self.armed = req.value
        return CommandBoolResult(success=True, result=0)

    def _takeoff(self, req) -> CommandTOLResult:
        reason = self._refused("takeoff")
        if reason:
            return CommandTOLResult(success=False, result=4, message=reason)
        self.armed = True
        self.z_goal = req.altitude
        return CommandTOLResult(success=True, result=0)

    def _land(self, _req) -> CommandTOLResult:
        reason = self._refused("land")
        if reason:
            return CommandTOLResult(success=False, result=4, message=reason)
        self.mode, self.z, self.z_goal = "AUTO.LAND", 0.0, 0.0
        self.landed, self.armed = LANDED_STATE_ON_GROUND, False
        return CommandTOLResult(success=True, result=0)

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
        pose = Pose(position=Point(z=self.z), orientation=Quaternion(w=1.0))
        self._pose.put(PoseStamped(header=Header(stamp=now, frame_id="map"), pose=pose))

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
