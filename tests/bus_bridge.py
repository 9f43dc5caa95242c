"""bridge_mavlink's real ``Bridge`` facing the simulated autopilot on the fake bus, so the SDK's
DroneWrapper and the ground station fly the simulator through the real bridge in bus time.

:class:`SimBridge` is the bridge as its process makes it (``Bridge(node, config, link)``,
``start()``) on a FakeNode, its link the simulator's PX4-like autopilot in process
(tests/clocked_autopilot.py): the bridge's threads, the autopilot's physics and every waiting
call move on the bus's virtual clock together. :class:`SimSdk` is the DroneWrapper on that
bus, its blocking calls moving the bus time.
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from pathlib import Path
from typing import Any

from clocked_autopilot import ClockedAutopilot

from dronewrapper import DroneWrapper
from dronewrapper.geodesy import to_enu
from dronewrapper.plan import read_plan
from dronewrapper.runtime.fake import FakeBus, FakeNode
from dronewrapper_bridge_mavlink.config import Config
from dronewrapper_bridge_mavlink.node import PORTS, Bridge
from dronewrapper_sim.px4.autopilot import AutopilotConfig

EPOCH = 1.7e9
"""The bus's start (s); the autopilot's time 0."""
HOME = (47.397742, 8.545594)
"""The simulator's home (latitude, longitude, degrees)."""
ACCEPTANCE_M = 2.0
"""The autopilot's acceptance radius of a waypoint whose own is 0 (NAV_ACC_RAD, m)."""


class SimBridge:
    """The real bridge on a node of ``bus`` facing the simulated autopilot (started).

    Args:
        bus: the fake bus (its clock is the bridge's and the autopilot's).
        wind: east and north wind (m/s); params: the autopilot's parameters; start: where it
            starts (local ENU m).
        bridge_config: the bridge's config (``message_rates`` empty unless given).
    """

    def __init__(
        self,
        bus: FakeBus,
        *,
        wind: tuple[float, float] = (0.0, 0.0),
        params: dict[str, float] | None = None,
        start: tuple[float, float] = (0.0, 0.0),
        **bridge_config: Any,
    ) -> None:
        self.node = FakeNode("bridge_mavlink", bus, ports=PORTS)
        autopilot = AutopilotConfig(
            wind_east=wind[0],
            wind_north=wind[1],
            params=params or {},
            start_x=start[0],
            start_y=start[1],
        )
        self.link = ClockedAutopilot(bus.clock, self.node.stop_event, config=autopilot)
        bridge_config.setdefault("message_rates", {})  # the autopilot's own rates, kept low
        self.bridge = Bridge(self.node, Config(**bridge_config), link=self.link)
        self.threads = self.bridge.start()
        self.node.announce()
        self.autopilot = self.link.autopilot
        self.core = self.bridge.core

    @property
    def t(self) -> float:
        """The autopilot's time (s since the bus's EPOCH)."""
        return self.autopilot.time_s

    @property
    def truth(self) -> list[tuple[float, tuple[float, float, float], str]]:
        """Ground truth: (t, local ENU position, mode) at each of the autopilot's polls."""
        return self.link.truth

    @property
    def position(self) -> tuple[float, float, float]:
        s = self.autopilot.state
        return (s.x, s.y, s.z)

    def closest_approach(self, point: tuple[float, float, float], since: float = 0.0) -> float:
        """The ground truth's closest distance (m) to ``point`` since ``since``."""
        return min(math.dist(p, point) for t, p, _ in self.truth if t >= since)

    def close(self) -> None:
        self.node.stop()
        for thread in self.threads:
            thread.join(10.0)


class SimSdk:
    """A DroneWrapper flying the simulator through :class:`SimBridge`, in bus time
    (``pair``: the flight, as tests read it)."""

    def __init__(self, **pair: Any) -> None:
        self.bus = FakeBus(start=EPOCH)
        self.pair = SimBridge(self.bus, **pair)
        self.node = FakeNode("app", self.bus)
        self.drone = DroneWrapper("drone", node=self.node, wait=False)
        self.run(3.0)  # connected, home and envelope known

    def run(self, seconds: float) -> None:
        self.bus.clock.run_for(seconds)

    def fly_mission(self, seconds: float) -> None:
        """Start the uploaded mission and run until it is finished, at most ``seconds``."""
        self.drone.start_mission()
        for _ in range(round(seconds / 0.5)):
            self.run(0.5)
            if self.drone.mission_progress().finished:
                break

    def close(self) -> None:
        self.drone.close()
        self.pair.close()


def returning_sim(return_alt: float) -> Iterator[SimSdk]:
    """A fixture's body: a :class:`SimSdk` whose autopilot returns at ``return_alt`` m,
    descends to 3 m over home and lands at once; closed after the test."""
    rig = SimSdk(
        params={"RTL_RETURN_ALT": return_alt, "RTL_DESCEND_ALT": 3.0, "RTL_LAND_DELAY": 0.0}
    )
    yield rig
    rig.close()


def assert_each_waypoint_passed(sim: SimSdk, plan: Path, start: float) -> None:
    """The ground truth since ``start`` came within :data:`ACCEPTANCE_M` of each
    NAV_WAYPOINT of the QGroundControl ``plan`` (frame 3: m above home)."""
    for wp in read_plan(plan).waypoints:
        if wp.command == 16:
            east, north = to_enu(HOME, wp.x_lat, wp.y_long)
            assert sim.pair.closest_approach((east, north, wp.z_alt), start) <= ACCEPTANCE_M, wp
