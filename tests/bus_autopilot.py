"""The toy aircraft (tests/fake_aircraft.py) on the fake bus, in injected time.

:class:`BusAutopilot` is a :class:`~fake_aircraft.FakeAircraft` on a
:class:`~dronewrapper.runtime.fake.FakeNode`, ticked in bus time: it climbs or sinks at 1 m/s,
lands at once, accepts any mode, and publishes its telemetry every ``TELEMETRY_PERIOD_S`` of
bus time when stepped. Tests of what commands an aircraft read every request in ``calls`` and
``requests``, and every setpoint from the bus.
It is not the bridge (tests/integration/test_bridge_* test that).

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
from dronewrapper.msgs.mavros import PositionTarget
from dronewrapper.runtime.fake import FakeBus, FakeNode
from fake_aircraft import REFUSED, FakeAircraft

__all__ = ["REFUSED", "T0", "TELEMETRY_PERIOD_S", "BusAutopilot", "SdkRig", "drive"]

T0 = 1_700_000_000.0
"""Bus time the rigs start at (s, Unix time)."""
TELEMETRY_PERIOD_S = 0.05  # 20 Hz, the real bridge's pose rate is higher; enough here


class BusAutopilot(FakeAircraft):
    """The toy aircraft on ``bus`` (see the module doc).

    Args:
        bus: the fake bus.
        flying: start in the air at 2 m, armed in OFFBOARD (else on the ground, disarmed, in
            AUTO.LOITER).
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
        super().__init__(
            FakeNode("bridge_fake", bus, ns=ns),
            bus.clock,
            flying=flying,
            autopilot=autopilot,
            position=(x, 0.0, 0.0),
            refuse=refuse,
            absent=absent,
        )
        self.node.announce()  # its liveliness token, as a real bridge's

    def next_wake(self, now: float) -> float:
        return (self._last_tick if self._last_tick is not None else now) + TELEMETRY_PERIOD_S

    def step(self, now: float) -> None:
        if self._last_tick is None or now >= self.next_wake(now):
            self.tick(now)

    def setpoints(self, since: float = -math.inf) -> list[tuple[float, PositionTarget]]:
        """(bus time, setpoint) of every setpoint published since ``since``."""
        key = registry.SETPOINT_RAW_LOCAL.key(self.node.ns)
        return [(d.time, d.msg) for d in self.bus.published[key] if d.time >= since]


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
    blocking calls (take-off, landing, ``wait_for``) wait on the bus clock, whose stepper moves
    the bus time, ticking the aircraft and running what :meth:`at` scheduled; the getters' ages
    are bus time too. Its setpoint stream repeats on its own thread in the same virtual time
    (tests/unit/test_sdk_streamer* test that); a new setpoint goes out at once.

    ``autopilot`` takes :class:`BusAutopilot`'s arguments; ``drone`` DroneWrapper's
    (:meth:`options`); ``open_drone=False`` leaves ``drone`` None (an aio Drone opens one).
    """

    def __init__(self, autopilot: dict | None = None, *, open_drone: bool = True, **drone) -> None:
        self.bus = FakeBus(start=T0)
        self.pilot = BusAutopilot(self.bus, **{"flying": False, **(autopilot or {})})
        self.node = FakeNode("app", self.bus)
        self.bus.clock.stepper = self.run_until  # the wrapper's waits tick the aircraft
        self._actions: list[tuple[float, Callable[[], None]]] = []
        self.drone = DroneWrapper("drone", **self.options(**drone)) if open_drone else None
        self.run(TELEMETRY_PERIOD_S)  # the first telemetry is in

    def options(self, **drone) -> dict:
        """DroneWrapper's arguments for a wrapper on this bus, in its time."""
        return {"node": self.node, "wait": False, **drone}

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

    def run_until(self, until: float, done: Callable[[], bool]) -> None:
        """The bus clock's stepper: tick the aircraft until ``until`` or ``done()``."""
        drive(self.bus, until, self, self.pilot, stop=done)

    def close(self) -> None:
        self.drone.close()
