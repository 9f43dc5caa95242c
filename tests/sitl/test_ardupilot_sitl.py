"""The paper's listing, velocity / position / mixed control and the commander-lost failsafe,
flown through compose/ardupilot_sitl.yaml (router + bridge_mavlink on tcp:127.0.0.1:PORT) by
the SDK against real ArduCopter SITL (opt-in: DRONEWRAPPER_ARDUPILOT_SITL, see conftest.py).

The tests share one SITL vehicle and run in file order. Each prints its measured figures
(``pytest -s``); docs/ardupilot.md records them. Margins are ArduCopter's own behaviour on a
loaded 2-core machine, not our simulator's.
"""

from __future__ import annotations

import math
import time
from collections.abc import Iterator
from dataclasses import dataclass, field

import numpy as np
import pytest
from ardupilot_sitl import sitl_binary, sitl_tree
from sitl_ready import wait_ready

from dronewrapper import DroneWrapper
from dronewrapper.msgs import registry
from dronewrapper_sim.external.firmware import arducopter
from support import Process, client_node, free_endpoint, python_module, wait_for

pytestmark = [pytest.mark.ardupilot_sitl, pytest.mark.timeout(600)]


@dataclass
class Flight:
    """The running graph, the SDK and what the test watches (monotonic-stamped)."""

    drone: DroneWrapper
    states: list = field(default_factory=list)
    figures: dict[str, str] = field(default_factory=dict)

    def on_state(self, state) -> None:
        self.states.append((time.monotonic(), state))

    def first_state_after(self, since: float, predicate) -> float | None:
        for at, state in list(self.states):
            if at >= since and predicate(state):
                return at - since
        return None

    def figure(self, name: str, text: str) -> None:
        self.figures[name] = text
        print(f"ARDUPILOT_SITL {name}: {text}", flush=True)


@pytest.fixture(scope="module")
def flight(tmp_path_factory) -> Iterator[Flight]:
    binary = sitl_binary()
    assert binary is not None
    work = tmp_path_factory.mktemp("arducopter")
    router = free_endpoint()
    with arducopter(sitl_tree(binary), work) as firmware:
        port, sitl_log = firmware.variables["sitl_port"], firmware.log
        graph = Process(
            python_module(
                "dronewrapper", "up", "compose/ardupilot_sitl.yaml",
                "--router", router, "--var", f"sitl_port={port}",
            ),
            work / "graph.log",
        )  # fmt: skip
        watcher = None
        try:
            wait_for(graph.alive, 5)
            with DroneWrapper("drone", router, timeout=60, cameras=(), land_on_exit=True) as drone:
                watcher = client_node(router, name="sitl_watch")
                result = Flight(drone)
                watcher.subscribe(registry.STATE, result.on_state)
                result.figure("autopilot", f"{drone.get_state().autopilot}")
                result.figure("ready_after_s", f"{wait_ready(drone, 'ardupilot'):.1f}")
                yield result
        finally:
            if watcher is not None:
                watcher.close()
            status = graph.stop(20)
            print(graph.output()[-3000:])
            print(sitl_log.read_text(errors="replace")[-2000:])
            assert status == 0, f"the graph exited with {status}"


def unwrapped_yaw(samples: list[tuple[float, float]]) -> np.ndarray:
    return np.unwrap(np.array([yaw for _, yaw in samples]))


def sample(drone: DroneWrapper, seconds: float, what) -> list[tuple[float, object]]:
    """``what()`` every 50 ms for ``seconds``, with monotonic times."""
    out = []
    end = time.monotonic() + seconds
    while time.monotonic() < end:
        out.append((time.monotonic(), what()))
        time.sleep(0.05)
    return out


def test_parameters_of_ardupilot_4_8(flight):
    """4.8's names (MAV_SYSID, ARMING_SKIPCHK, WP_SPD); an integer equal to 0 is int 0."""
    drone = flight.drone
    sysid = drone.param_get("MAV_SYSID")
    assert sysid == 1 and isinstance(sysid, int)
    fence = drone.param_get("FENCE_ENABLE")
    assert fence == 0 and isinstance(fence, int), repr(fence)
    assert isinstance(drone.param_get("ARMING_SKIPCHK"), int)
    speed = drone.param_get("WP_SPD")
    assert isinstance(speed, float) and speed > 0
    assert drone.param_set("WP_SPD", speed) == pytest.approx(speed)
    flight.figure("params", f"MAV_SYSID {sysid}, FENCE_ENABLE {fence!r}, WP_SPD {speed:g}")


def test_paper_listing(flight):
    """takeoff(h=2.5); set_cmd_vel(az=1); sleep(5); land() - issue 21's failing listing."""
    drone = flight.drone
    started = time.monotonic()
    drone.takeoff(h=2.5)
    took = time.monotonic() - started
    z = drone.get_position()[2]
    assert z == pytest.approx(2.5, abs=0.3)
    assert drone.get_state().mode == "GUIDED" and drone.get_state().armed
    drone.set_cmd_vel(az=1)
    yaws = sample(drone, 5.0, drone.get_yaw)
    landing = time.monotonic()
    drone.land()
    landed = time.monotonic() - landing
    turned = unwrapped_yaw(yaws)
    t = np.array([at for at, _ in yaws])
    late = t >= t[0] + 2.0  # after ArduCopter's yaw acceleration limit
    rate = float(np.polyfit(t[late], turned[late], 1)[0])
    assert 0.85 < rate < 1.1, f"yaw rate {rate:.3f} rad/s for a 1 rad/s command"
    flight.figure("listing_takeoff_s", f"{took:.1f} (to {z:.2f} m)")
    flight.figure(
        "listing_yaw_rate", f"{rate:.3f} rad/s steady, {turned[-1] - turned[0]:.2f} rad in 5 s"
    )
    flight.figure("listing_land_s", f"{landed:.1f} (to disarmed)")


def test_velocity_position_and_mixed_control(flight):
    drone = flight.drone
    drone.takeoff(h=2.5)
    # body-frame velocity: forward is the heading, whatever the heading
    drone.set_cmd_vel(vx=1.0)
    time.sleep(4.0)
    moving = sample(drone, 2.0, lambda: (drone.get_velocity_local().copy(), drone.get_yaw()))
    speeds = [float(np.hypot(v[0], v[1])) for _, (v, _) in moving]
    errors = [
        math.degrees(math.remainder(math.atan2(v[1], v[0]) - yaw, math.tau))
        for _, (v, yaw) in moving
    ]
    speed, worst = float(np.median(speeds)), float(np.max(np.abs(errors)))
    assert speed == pytest.approx(1.0, abs=0.15)
    assert worst < 3.0, f"course {worst:.1f} degrees off the heading"
    flight.figure("velocity_forward", f"{speed:.2f} m/s, course within {worst:.2f} deg of heading")
    # position: 3 m east-north-east and up 1 m, heading kept
    x, y, _z = drone.get_position()
    yaw = drone.get_yaw()
    goal = np.array([x + 3.0, y + 2.0, 3.5])
    started = time.monotonic()
    drone.set_cmd_pos(*goal, yaw)

    def arrived():
        return np.linalg.norm(drone.get_position() - goal) < 0.2

    drone.wait_for(arrived, 25, "the position target")
    reached = time.monotonic() - started
    time.sleep(2.0)
    error = float(np.linalg.norm(drone.get_position() - goal))
    assert error < 0.2
    flight.figure("position_3.6m_s", f"{reached:.1f} to within 0.2 m, {error:.3f} m after 2 s more")
    # mixed: forward 0.5 m/s holding 2.5 m (the bridge emulates the altitude hold with vz)
    drone.set_cmd_mix(vx=0.5, z=2.5)
    time.sleep(3.0)
    heights = sample(drone, 3.0, lambda: drone.get_position()[2])
    worst_z = max(abs(z - 2.5) for _, z in heights)
    assert worst_z < 0.25
    flight.figure("mixed_altitude", f"within {worst_z:.2f} m of 2.5 m at 0.5 m/s forward")


def test_commander_lost_failsafe(flight):
    """Still flying from the previous test: the app stops streaming. Hold after
    setpoint_timeout (0.5 s), LAND after commander_lost_timeout (5 s), then disarmed."""
    drone = flight.drone
    assert drone.is_flying()
    x, y, z = drone.get_position()
    drone.set_cmd_pos(x, y, z, drone.get_yaw())
    time.sleep(2.0)
    stopped = time.monotonic()
    drone.stop_commanding()

    def landed() -> bool:
        state = drone.get_state()
        return not state.armed

    drone.wait_for(landed, 60, "the failsafe landing")
    hold = flight.first_state_after(stopped, lambda s: s.failsafe == "hold")
    land = flight.first_state_after(stopped, lambda s: s.failsafe == "land")
    mode = flight.first_state_after(stopped, lambda s: s.mode == "LAND")
    assert hold is not None and 0.4 < hold < 1.5, hold
    assert land is not None and 4.8 < land < 6.5, land
    assert mode is not None and mode - land < 1.0
    flight.figure(
        "failsafe",
        f"hold at {hold:.2f} s, land request at {land:.2f} s, LAND mode at {mode:.2f} s",
    )
