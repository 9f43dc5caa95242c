"""bridge_mavlink's core and the simulated autopilot (tests/sim_pair.py) behind the fake bus,
so the SDK's DroneWrapper flies the simulator through the real bridge logic in bus time.

:class:`BusBridge` serves the bridge's keys on a FakeNode: each service call runs the core's
operation while the pair (and the bus clock with it) moves on; what the core publishes goes
on the bus; the SDK's setpoints reach the core at 20 Hz while the SDK streams. :class:`SimSdk`
is the DroneWrapper on that bus, its blocking calls moving the bus time.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from bus_autopilot import drive
from sim_pair import EPOCH, SimPair

from dronewrapper import DroneWrapper
from dronewrapper.msgs import registry
from dronewrapper.runtime.caller import current_commander
from dronewrapper.runtime.fake import FakeBus, FakeNode
from dronewrapper_bridge_mavlink import actions, flight, missions, parameters
from dronewrapper_bridge_mavlink import operations as ops

STEP_S = 0.02


class BusBridge:
    """The pair's bridge on ``bus`` (see module docstring); bus time = EPOCH + pair time."""

    def __init__(self, bus: FakeBus, pair: SimPair, ns: str = "drone") -> None:
        self.bus = bus
        self.pair = pair
        self.node = FakeNode("bridge_mavlink", bus, ns=ns)
        self._published = 0
        self._publishers: dict[Any, Any] = {}
        self.node.subscribe(registry.SETPOINT_RAW_LOCAL, self._on_setpoint)
        services = [
            (registry.FLIGHT_TAKEOFF, flight.takeoff_to),
            (registry.FLIGHT_LAND, flight.land_here),
            (registry.FLIGHT_GOTO, actions.goto_point),
            (registry.FLIGHT_RETURN, actions.return_home),
            (registry.FLIGHT_MISSION, actions.mission_action),
            (registry.MISSION_CONTROL, actions.control),
            (registry.ARMING, ops.arming),
            (registry.TAKEOFF, ops.takeoff),
            (registry.LAND, ops.land),
            (registry.SET_MODE, ops.set_mode),
            (registry.PARAM_GET, parameters.param_get),
            (registry.PARAM_SET, parameters.param_set),
            *((service, steps) for service, steps, _ in missions.SERVICES),
        ]
        for service, steps in services:
            self.node.serve(service, lambda request, steps=steps: self._call(steps, request))
        self.node.announce()
        self._beats: dict[str, float] = {}  # key -> bus time of its last beat
        self.node.subscribe(registry.COMMANDER_BEAT, self._on_beat)
        pair.alive = lambda: {k for k, t in self._beats.items() if self.pair.t + EPOCH - t < 1.5}

    def _on_beat(self, beat: Any) -> None:
        self._beats[beat.key] = self.bus.clock()

    def _on_setpoint(self, target: Any) -> None:
        self.pair.setpoint = target

    def _publish(self) -> None:
        self.bus.clock.advance_to(EPOCH + self.pair.t)
        for _, topic, msg in self.pair.samples[self._published :]:
            if topic not in self._publishers:
                self._publishers[topic] = self.node.publisher(topic)
            self._publishers[topic].put(msg)
        self._published = len(self.pair.samples)

    def _advance(self, until: float) -> None:
        while self.pair.t < until - EPOCH:
            self.pair.step()
        self._publish()

    def _call(self, steps: Any, request: Any, limit: float = 60.0) -> Any:
        core = self.pair.core  # the request's commander as the real wiring hands it on
        steps = steps(core, request)
        op = core.request(steps, current_commander(), "", self.pair.t, EPOCH + self.pair.t)
        end = self.pair.t + limit
        steps = 0
        while not op.done and self.pair.t < end:
            self.pair.step()
            steps += 1
            if steps % 5 == 0:
                self._publish()
        self._publish()
        return op.result()

    def step(self, now: float) -> None:
        self._advance(now)

    def next_wake(self, now: float) -> float:
        return now + STEP_S


class SimSdk:
    """A DroneWrapper flying the simulator through :class:`BusBridge`, in bus time."""

    def __init__(self, **pair: Any) -> None:
        self.pair = SimPair(**pair)
        self.bus = FakeBus(start=EPOCH)
        self.bridge = BusBridge(self.bus, self.pair)
        self.node = FakeNode("app", self.bus)
        self.bus.clock.stepper = self.run_until  # the wrapper's waits fly the simulator
        self.drone = DroneWrapper("drone", node=self.node, wait=False)
        self.pair.streaming = lambda: self.drone.commanding is not None
        self.run(3.0)  # connected, home and envelope known

    def run(self, seconds: float) -> None:
        drive(self.bus, self.bus.clock() + seconds, self.bridge)

    def run_until(self, until: float, done: Callable[[], bool]) -> None:
        """The bus clock's stepper: the simulator runs until ``until`` or ``done()``."""
        drive(self.bus, until, self.bridge, stop=done)

    def close(self) -> None:
        self.drone.close()
