"""Real PX4 SITL flown through the PX4 Zenoh bridge, with no MAVLink in between (opt-in).

Runs when ``PX4_SITL_DIR`` names a ``px4_sitl_zenoh`` build (tests/sitl/px4_zenoh_sitl.py), in
a network namespace of its own (PX4 dials the router on 7447). The graph compose/px4_zenoh.yaml
(the bridge on the router PX4 dials) and PX4 SIH with its zenoh module on; then:

* Listing 1 from an SDK app: connect, take off to 2.5 m, fly forward at 1 m/s for 3 s, land;
  judged from what the app reads (height, distance flown, landed and disarmed);
* follow-color (beacon_smooth) and follow-person (people_crossing_front) through
  compose/px4_zenoh_follow_{color,person}.yaml, judged from ground truth with the scenario
  tier's thresholds, as tests/sitl/test_follow_sitl.py judges them through the MAVLink bridge,
  and failed when PX4 left OFFBOARD on its own (its offboard-loss failsafe cuts a flight short
  with enough samples to pass); PX4's uORB ``offboard_control_mode`` is echoed back and timed
  beside the router's view of the bridge's writes (``LinkWatch``);
* the failsafe contract when the app is killed (SIGKILL) while streaming: the bridge holds
  within ``setpoint_timeout`` + a tick and asks PX4 to land after ``commander_lost_timeout``,
  and PX4 lands and disarms.

Each run prints its figures (pose rate and age at the app, take-off and landing times).
"""

from __future__ import annotations

import contextlib
import math
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
from busy_core import one_core_busy
from px4_zenoh_sitl import (
    ROUTER_PORT,
    LinkWatch,
    left_offboard_in_flight,
    log_problems,
    px4_zenoh,
    realtime_share,
    router_port_free,
)
from scenario_flight import check_flight, fly, record_result
from test_follow_scenarios import CASES, CROSSING, LOADED_DETECT_RATE_HZ, crossed, passes

from dronewrapper import DroneWrapper
from dronewrapper.errors import CommandRefused, NotConnected
from dronewrapper.msgs import registry
from dronewrapper.msgs.mavros import LANDED_STATE_ON_GROUND
from dronewrapper.runtime.options import DEFAULT_ROUTER
from dronewrapper_compose.launcher import Launcher
from support import client_node

pytestmark = [pytest.mark.px4_zenoh, pytest.mark.timeout(300)]

REPO = Path(__file__).resolve().parents[2]
LINK_RECORD_ENV = "DRONEWRAPPER_PX4_LINK_RECORD"  # a file for the link's arrivals (JSON)
READY_S = 90.0  # PX4 start -> its preflight checks pass (a loaded 2-core machine)


@pytest.fixture
def graph(tmp_path):
    assert router_port_free(), (
        f"port {ROUTER_PORT} is taken: PX4 dials it, so run this tier in a network namespace "
        "of its own (unshare -n as root, loopback up)"
    )
    log = open(tmp_path / "graph.log", "w")  # noqa: SIM115 (closed below)
    launcher = Launcher.from_file(REPO / "compose" / "px4_zenoh.yaml", out=log)
    launcher.start()
    try:
        with px4_zenoh(tmp_path) as firmware:
            yield firmware.version, firmware.log
    finally:
        launcher.stop()
        log.close()
        print((tmp_path / "graph.log").read_text()[-2000:])


def take_off(drone: DroneWrapper, height: float) -> float:
    """Take off, retried while PX4 is not ready (its preflight checks), as the controller's
    ``wait_ready``; the seconds the successful take-off took."""
    deadline = time.monotonic() + READY_S
    while True:
        started = time.monotonic()
        try:
            drone.takeoff(h=height, timeout=40)
            return time.monotonic() - started
        except (NotConnected, CommandRefused) as exc:
            if time.monotonic() > deadline:
                raise
            print(f"take-off not yet: {exc}")
            time.sleep(2.0)


class PoseWatch:
    """Poses as an app receives them: count and age (receipt - the bridge's stamp, s)."""

    def __init__(self) -> None:
        self.ages: list[float] = []
        self.received: list[float] = []

    def __call__(self, pose) -> None:
        now = time.time()
        self.received.append(time.monotonic())
        self.ages.append(now - pose.header.stamp)

    def rate(self, since: float) -> float:
        times = [t for t in self.received if t >= since]
        return (len(times) - 1) / (times[-1] - times[0]) if len(times) > 1 else 0.0

    def age_ms(self, q: float) -> float:
        ages = sorted(self.ages[-500:])
        return 1000 * ages[int(q * (len(ages) - 1))]


def test_listing_1_flies_px4_through_its_own_zenoh(graph):
    version, _ = graph
    watch = PoseWatch()
    with DroneWrapper("drone", DEFAULT_ROUTER, timeout=90, land_on_exit=True) as drone:
        drone.node.subscribe(registry.LOCAL_POSE, watch)
        takeoff_s = take_off(drone, 2.5)
        start = drone.get_position()
        assert start[2] > 2.0, start
        since = time.monotonic()
        drone.set_cmd_vel(vx=1.0)
        time.sleep(3.0)
        drone.set_cmd_vel()
        time.sleep(1.5)
        moved = math.dist(start[:2], drone.get_position()[:2])
        pose_rate = watch.rate(since)
        landing = time.monotonic()
        drone.land()
        landing_s = time.monotonic() - landing
        assert drone.get_landed_state() == LANDED_STATE_ON_GROUND
        assert not drone.get_state().armed
    print(
        f"\n{version} over Zenoh: take-off {takeoff_s:.1f} s; flew {moved:.2f} m forward "
        f"(1 m/s for 3 s); landing {landing_s:.1f} s; pose {pose_rate:.0f} Hz at the app, age "
        f"(bridge stamp -> app) median {watch.age_ms(0.5):.1f} ms, 95 % {watch.age_ms(0.95):.1f} ms"
    )
    assert 1.5 < moved < 4.5, moved  # PX4 SIH settles at ~0.9 of a commanded speed
    assert pose_rate > 25.0, pose_rate  # one pose a stream tick (30 Hz), PX4's ~120 Hz coalesced


APP = """
import sys, time
from dronewrapper import DroneWrapper
from dronewrapper.errors import CommandRefused, NotConnected
drone = DroneWrapper("drone", sys.argv[1], timeout=90)
deadline = time.monotonic() + 90
while True:
    try:
        drone.takeoff(h=2.5, timeout=40)
        break
    except (NotConnected, CommandRefused):
        if time.monotonic() > deadline:
            raise
        time.sleep(2)
drone.set_cmd_vel(vx=0.3)
print("streaming", flush=True)
time.sleep(600)
"""


def test_a_killed_app_is_held_then_landed_by_the_failsafe(graph, tmp_path):
    version, _ = graph
    script = tmp_path / "app.py"
    script.write_text(APP)
    states: list[tuple[float, str, bool]] = []
    node = client_node(DEFAULT_ROUTER, "watch", mode="client")
    node.subscribe(registry.STATE, lambda s: states.append((time.monotonic(), s.failsafe, s.armed)))
    app = subprocess.Popen(
        [sys.executable, str(script), DEFAULT_ROUTER], stdout=subprocess.PIPE, text=True
    )
    try:
        line = app.stdout.readline()
        assert line.strip() == "streaming", line
        time.sleep(3.0)
        app.send_signal(signal.SIGKILL)
        app.wait()
        killed = time.monotonic()
        deadline = killed + 90
        while time.monotonic() < deadline:
            if any(t > killed and not armed for t, _, armed in states):
                break
            time.sleep(0.2)
    finally:
        if app.poll() is None:
            app.kill()
            app.wait()
        node.close()
    after = [(t - killed, failsafe, armed) for t, failsafe, armed in states if t > killed]
    hold = next((t for t, f, _ in after if f == "hold"), None)
    land = next((t for t, f, _ in after if f == "land"), None)
    down = next((t for t, _, armed in after if not armed), None)
    print(
        f"\n{version} over Zenoh, app killed: hold after {hold} s, land asked after {land} s, "
        f"disarmed after {down} s"
    )
    # the last setpoint left the app up to one SDK period before the kill was seen: the bridge's
    # 0.5 s setpoint_timeout and 5 s commander_lost_timeout count from it (+ a tick, + load)
    assert hold is not None and hold < 0.5 + 1.0, after[:5]
    assert land is not None and 4.0 <= land < 5.0 + 1.5, after[:10]
    assert down is not None, "PX4 did not land and disarm within 90 s"


@pytest.mark.parametrize("scenario", ["beacon_smooth", "people_crossing_front"])
def test_follow_flies_px4_through_its_own_zenoh(scenario, tmp_path):
    sim_graph, detector, seconds, max_acquire, min_centred, min_distance = CASES[scenario]
    app = "color" if sim_graph == "sim_follow_color" else "person"
    assert router_port_free(), f"port {ROUTER_PORT} is taken: run in a network namespace"
    with px4_zenoh(tmp_path, echo=True) as firmware:  # zenoh-pico retries until the router is up
        fifo, threads = realtime_share(tmp_path)
        variables = {"truth_port": firmware.variables["truth_port"]}
        if app == "person":
            variables["detector"] = detector
        crossing = scenario in CROSSING
        if crossing:
            variables["detect_rate_hz"] = LOADED_DETECT_RATE_HZ
        with (
            one_core_busy() if crossing else contextlib.nullcontext(),
            LinkWatch() as link,
        ):
            flight = fly(
                f"px4_zenoh_follow_{app}",
                scenario,
                seconds,
                tmp_path,
                variables,
                start_timeout=120.0,
                router=DEFAULT_ROUTER,
            )
    print(
        f"\n{firmware.version} over Zenoh: {flight.describe()}\nrouter: {link.describe()}\n"
        f"PX4's threads with real-time priority: {fifo} of {threads}"
    )
    if os.environ.get(LINK_RECORD_ENV):
        link.dump(Path(os.environ[LINK_RECORD_ENV]))
    cut_short = left_offboard_in_flight(flight.log)
    passed = passes(flight, max_acquire, min_centred, min_distance) and not cut_short
    record_result(flight, f"follow_{app}", "px4_zenoh", firmware.version, passed)
    if not passed:
        print(f"PX4's log ({firmware.log}), warnings and errors:\n{log_problems(firmware.log)}")
    check_flight(flight, max_acquire, min_centred, min_distance)
    assert not cut_short, f"PX4 left OFFBOARD on its own during the flight\n{flight.log[-3000:]}"
    if crossing:
        assert sum(crossed(x) for x in flight.samples) > 0, "no passer-by crossed: proves nothing"
