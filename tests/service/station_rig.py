"""The station's app on the fake bus, in bus time: a :class:`BusAutopilot` flying in OFFBOARD
behind namespace ``drone`` (discovered by its liveliness token, ``bridge_fake``), a simulated
object ``target`` whose pose the rig publishes with each telemetry tick, and the app driven in
process (:mod:`asgi_driver`: no server, no socket).

The station's blocking commands (take-off, landing) wait by moving the bus (:meth:`run`), as
the SDK's do on :class:`~bus_autopilot.SdkRig`; ages and the teleop dead-man read the bus clock.
"""

from __future__ import annotations

from typing import Any

from asgi_driver import AsgiClient
from bus_autopilot import T0, TELEMETRY_PERIOD_S, BusAutopilot, drive

from dronewrapper.msgs import registry
from dronewrapper.msgs.geometry import Point, Pose, PoseStamped, Quaternion
from dronewrapper.msgs.mavros import PositionTarget
from dronewrapper.msgs.std import Header
from dronewrapper.runtime.fake import FakeBus, FakeNode
from dronewrapper_ground_station.access import Access
from dronewrapper_ground_station.app import create_app
from dronewrapper_ground_station.config import Config
from dronewrapper_ground_station.fleet import Fleet
from dronewrapper_ground_station.node import PORTS
from dronewrapper_sim.cli import PORTS as SIM_PORTS

TOKEN = "operator-token-0123456789"
X = 1.0
"""The autopilot's east position (m); it flies at 2 m (BusAutopilot's ``flying``)."""
TARGET = (5.0, -1.0, 0.0)
"""The simulated object's pose (ENU, m)."""
REMOTE = {"Host": "station.example:8080"}  # a page reached by a name that is not loopback


class WorldObjects:
    """The simulator's side the station watches: ``target``'s pose at every wake."""

    def __init__(self, bus: FakeBus) -> None:
        self.node = FakeNode("sim", bus, ports=SIM_PORTS)
        self._pose = self.node.publisher(registry.SIM_OBJECT_POSE, name="target")
        self._last: float | None = None

    def step(self, now: float) -> None:
        if self._last is None or now >= self.next_wake(now):
            self._last = now
            x, y, z = TARGET
            pose = Pose(position=Point(x=x, y=y, z=z), orientation=Quaternion(w=1.0))
            self._pose.put(PoseStamped(header=Header(stamp=now, frame_id="map"), pose=pose))

    def next_wake(self, now: float) -> float:
        return (now if self._last is None else self._last) + TELEMETRY_PERIOD_S


class StationRig:
    """The station (token :data:`TOKEN`) over the fake bus; ``config`` overrides Config."""

    def __init__(
        self,
        *,
        autopilot: dict[str, Any] | None = None,
        **config: Any,
    ) -> None:
        self.bus = FakeBus(start=T0)
        self.pilot = BusAutopilot(self.bus, **{"flying": True, "x": X, **(autopilot or {})})
        self.pilot.node.announce()
        self.world = WorldObjects(self.bus)
        self.node = FakeNode("station", self.bus, ports=PORTS)
        self.config = Config(port=0, command_timeout=5.0, **config)
        self.bus.clock.stepper = self.run_until  # blocking commands tick the aircraft
        self.fleet = Fleet(self.node, self.config)
        self.client = AsgiClient(create_app(self.fleet, self.config, Access(TOKEN)))
        self.fleet.discover()
        self.run(2 * TELEMETRY_PERIOD_S)  # the first telemetry and object poses are in

    @property
    def link(self):
        return self.fleet.get("drone")

    def run(self, seconds: float) -> None:
        """Move the bus ``seconds`` on: the aircraft and the world tick."""
        drive(self.bus, self.bus.clock() + seconds, self.pilot, self.world)

    def run_until(self, until: float, done) -> None:
        """The bus clock's stepper: the aircraft and the world tick until ``until`` or
        ``done()``."""
        drive(self.bus, until, self.pilot, self.world, stop=done)

    def http(self, method: str, path: str, body: Any = None, headers: dict | None = None):
        return self.client.http(method, path, body, headers)

    def websocket(self, path: str, headers: dict | None = None):
        return self.client.websocket(path, headers)

    def setpoint(self) -> PositionTarget:
        """The newest setpoint the station sent."""
        setpoints = self.pilot.setpoints()
        assert setpoints, "no setpoint was sent"
        return setpoints[-1][1]

    def close(self) -> None:
        self.client.close()
        self.fleet.close()
