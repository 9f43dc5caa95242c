"""One flight over a serial line at a real baud rate to real firmware, run by
tests/sitl/test_serial_sitl.py inside a private network namespace (a free firmware instance, or
``DRONEWRAPPER_SITL_INSTANCE``: PX4's instance lock is machine-wide). Prints one JSON line of
figures; exits 0 when it ran to the end.

    python serial_sitl_flight.py px4 57600 PX4_BUILD_DIR WORKDIR
    python serial_sitl_flight.py ardupilot 921600 ARDUPILOT_TREE WORKDIR [signed]

The line: a pseudo-terminal pair for the bridge, paced at ``baud / 10`` B/s each way, and a
second pseudo-terminal that the firmware opens as its own serial port (serial_taps.paced_relay;
the autopilot's transmit buffer that of a Pixhawk's TELEM port). The firmware is started by
dronewrapper_sim.external.firmware with ``serial``: PX4 runs a MAVLink instance on it in onboard
mode (a companion computer's TELEM2 setup, its data rate left to PX4: baud / 20 B/s),
ArduCopter its SERIAL0. The firmware sizes its streams to the baud as on a flight
controller, the bridge fits its stream requests to the line, and the SDK flies: Listing 1
(take off, turn, move, land), a parameter sweep, a 20-item mission upload, then a small square
mission flown. ``signed``: a new MAVLink 2 signing key is provisioned on the autopilot over the
line first (``dronewrapper_bridge_mavlink.provision``, SETUP_SIGNING) and the bridge signs and
checks every frame with it (ArduCopter; PX4 at this version has no MAVLink signing).
"""

from __future__ import annotations

import collections
import json
import math
import os
import sys
import time
from pathlib import Path

from serial_taps import paced_relay
from sitl_ready import wait_ready

from dronewrapper import DroneWrapper
from dronewrapper.geodesy import to_geodetic
from dronewrapper.msgs import registry
from dronewrapper.msgs.mavros import LANDED_STATE_ON_GROUND
from dronewrapper.security.keystore import KeyStore
from dronewrapper_bridge_mavlink.provision import provision
from dronewrapper_sim.external.firmware import arducopter, px4_sih
from dronewrapper_sim.serial_relay import SerialRelay
from support import Process, free_endpoint, python_module, wait_for, zenoh_router

PARAMS = {  # read all, write the first two (a new value, then the old one back)
    "px4": ["MPC_XY_VEL_MAX", "NAV_ACC_RAD", "MPC_Z_VEL_MAX_UP", "MIS_TAKEOFF_ALT",
            "COM_DISARM_LAND", "MPC_LAND_SPEED"],
    "ardupilot": ["WP_SPD", "WP_RADIUS_M", "WP_SPD_UP", "WP_SPD_DN", "PILOT_SPD_UP",
                  "FENCE_ENABLE"],
}  # fmt: skip
SQUARE_M = 8.0  # the flown mission: a square of this side at 5 m, starting 8 m north of home


class Watch:
    """What the app receives: pose arrivals (monotonic s, age s) and the bridge's link status."""

    def __init__(self) -> None:
        self.poses: list[tuple[float, float]] = []
        self.links: list = []

    def on_pose(self, msg) -> None:
        self.poses.append((time.monotonic(), time.time() - msg.header.stamp))

    def pose_figures(self, since: float, until: float) -> dict:
        ages = sorted(age for t, age in self.poses if since <= t <= until)
        count = len(ages)
        return {
            "pose_hz": round(count / (until - since), 1),
            "pose_age_bridge_to_app_ms_p50": round(1000 * ages[count // 2], 1) if ages else None,
        }


def quantile_ms(delays, q: float) -> float | None:
    ordered = sorted(delays)
    return round(1000 * ordered[int(q * (len(ordered) - 1))], 1) if ordered else None


def line_figures(relay: SerialRelay, offered_before: collections.Counter, seconds: float) -> dict:
    """The autopilot's frames a second by name (the busiest), and each frame's time on the line
    (write to last byte across): autopilot to bridge, and bridge to autopilot (the setpoints)."""
    offered = relay.down.offered - offered_before
    top = {name: round(n / seconds, 1) for name, n in offered.most_common(8)}
    return {
        "autopilot_sends_hz": top,
        "line_ms_p50": quantile_ms(relay.down.delays, 0.5),
        "line_ms_p95": quantile_ms(relay.down.delays, 0.95),
        "uplink_ms_p50": quantile_ms(relay.up.delays, 0.5),
        "uplink_ms_p95": quantile_ms(relay.up.delays, 0.95),
    }


def link_figures(link) -> dict:
    return {
        "load": round(link.load, 3),
        "down_kBps": round(link.received_rate / 1000, 2),
        "up_kBps": round(link.sent_rate / 1000, 2),
        "lost": link.lost,
        "stream_scale": round(link.stream_scale, 2),
        "link": link.describe(),
    }


class Window:
    """What crossed the line from now on: frames offered by name, drops, times on the line."""

    def __init__(self, relay: SerialRelay, watch: Watch) -> None:
        self.relay, self.watch = relay, watch
        relay.down.delays.clear()
        relay.up.delays.clear()
        self.offered = relay.down.offered.copy()
        self.dropped = relay.down.dropped_frames
        self.since = time.monotonic()

    def figures(self) -> dict:
        now = time.monotonic()
        return {
            **line_figures(self.relay, self.offered, now - self.since),
            **self.watch.pose_figures(self.since, now),
            **link_figures(self.watch.links[-1]),
            "dropped_frames": self.relay.down.dropped_frames - self.dropped,
        }


def parameter_sweep(drone: DroneWrapper, names: list[str]) -> dict:
    """Read every parameter; write the first two (a new value, read back), then restore them."""
    started = time.monotonic()
    values = {name: drone.param_get(name) for name in names}
    for name in names[:2]:
        new = values[name] * 1.25 if isinstance(values[name], float) else values[name] + 1
        assert math.isclose(drone.param_set(name, new), new, rel_tol=1e-6), name
        assert math.isclose(drone.param_get(name), new, rel_tol=1e-6), name
        drone.param_set(name, values[name])
    return {"reads": len(names) + 2, "writes": 4, "seconds": round(time.monotonic() - started, 2)}


def listing_1(drone: DroneWrapper, relay: SerialRelay, watch: Watch, report: dict) -> None:
    """Take off, turn at 1 rad/s for 5 s, forward at 1 m/s for 4 s (figures), land."""
    started = time.monotonic()
    drone.takeoff(h=2.5)
    report["takeoff_s"] = round(time.monotonic() - started, 1)
    window = Window(relay, watch)  # from the take-off on
    yaw0 = drone.get_yaw()
    drone.set_cmd_vel(az=1)
    time.sleep(5.0)
    turned = (drone.get_yaw() - yaw0) % (2 * math.pi)
    x0, y0, _ = drone.get_position()
    drone.set_cmd_vel(vx=1)
    time.sleep(4.0)
    x1, y1, z1 = drone.get_position()
    report["flying"] = window.figures()
    moved = math.hypot(x1 - x0, y1 - y0)
    report["listing"] = {"turned_rad": round(turned, 2), "moved_m": round(moved, 2),
                         "altitude_m": round(z1, 2)}  # fmt: skip
    # still flying (PX4 holds no altitude under velocity setpoints: it drifted 2.9 to 1.2 m)
    assert turned > 1.0 and moved > 1.0 and z1 > 0.5, report["listing"]
    started = time.monotonic()
    drone.land()
    report["land_s"] = round(time.monotonic() - started, 1)
    assert drone.get_landed_state() == LANDED_STATE_ON_GROUND


def square_mission(drone: DroneWrapper, home: tuple[float, float]) -> dict:
    """A 4-item square uploaded, taken off for and flown as a mission, then landed."""
    corners = [(SQUARE_M, 0.0), (SQUARE_M, SQUARE_M), (0.0, SQUARE_M), (0.0, 0.0)]
    square = [(*to_geodetic(home, east, north), 5.0) for north, east in corners]
    assert drone.upload_mission(square) == 4
    drone.takeoff(h=5.0)
    current = drone.mission_progress().current  # the autopilot's current item, as published
    started = time.monotonic()
    drone.start_mission()
    drone.wait_for(lambda: drone.mission_progress().finished, 120, "the square flown")
    seconds = round(time.monotonic() - started, 1)
    reached = list(drone.mission_progress().reached_items)
    drone.land()
    return {"seconds": seconds, "reached": reached, "current_before_start": current}


def fly(kind: str, relay: SerialRelay, drone: DroneWrapper, report: dict) -> None:
    watch = Watch()
    drone.subscribe(registry.LOCAL_POSE, watch.on_pose)
    drone.subscribe(registry.LINK_STATUS, watch.links.append)
    report["ready_after_s"] = round(wait_ready(drone, kind), 1)
    wait_for(lambda: len(watch.links) >= 3, 10, what="link status")
    ground = Window(relay, watch)  # on the ground, the streams settled
    time.sleep(8.0)
    report["ground"] = ground.figures()
    report["param_sweep"] = parameter_sweep(drone, PARAMS[kind])
    home = drone.home()
    lat, lon = home.latitude, home.longitude
    circle = [
        (*to_geodetic((lat, lon), 10 * math.cos(a), 10 * math.sin(a)), 5.0)
        for a in (2 * math.pi * i / 20 for i in range(20))
    ]
    started = time.monotonic()
    assert drone.upload_mission(circle) == 20  # each item asked for and acknowledged
    report["mission_upload_20_s"] = round(time.monotonic() - started, 2)
    listing_1(drone, relay, watch, report)
    report["square_mission"] = square_mission(drone, (lat, lon))
    report["final_link"] = link_figures(watch.links[-1])
    report["rejected"] = watch.links[-1].rejected
    report["dropped_frames_total"] = relay.down.dropped_frames
    report["dropped_toward_autopilot"] = relay.up.dropped_frames


def main(kind: str, baud: int, firmware: Path, work: Path, signed: bool = False) -> int:
    report: dict = {"autopilot": kind, "baud": baud, "signed": signed}
    with paced_relay(baud) as relay:
        start = px4_sih if kind == "px4" else arducopter
        config = [] if kind == "px4" else [
            "--config", "services/bridge_mavlink/dronewrapper_bridge_mavlink/config/"
            "ardupilot_sitl.yaml"]  # fmt: skip
        serial = (relay.autopilot_path, baud)
        with start(firmware, work, serial=serial), zenoh_router(free_endpoint()) as r:
            if signed:
                store = KeyStore(work / "keys")
                key = store.new_mavlink_key()
                report["provision"] = provision(relay.path, key, baud=baud, timeout=60)
                config += ["--set", f"signing_key_file={store.mavlink_key}"]
            bridge = Process(
                python_module("dronewrapper_bridge_mavlink", "--connect", r, *config,
                              "--connection", relay.path, "--baud", str(baud)),
                work / "bridge.log",
            )  # fmt: skip
            try:
                with DroneWrapper("drone", r, timeout=60, cameras=(), land_on_exit=True) as drone:
                    report["autopilot_named"] = drone.get_state().autopilot
                    try:
                        fly(kind, relay, drone, report)
                        report["ok"] = True
                    except Exception as exc:  # the report says what failed
                        report["error"] = f"{type(exc).__name__}: {exc}"
            finally:
                bridge.stop(10)
                report["bridge_warnings"] = [
                    line[-200:] for line in bridge.output().splitlines() if "WARNING" in line
                ][-6:]
    report["load_average"] = [round(x, 1) for x in os.getloadavg()]  # the machine's, at the end
    print(json.dumps(report), flush=True)
    return 0 if report.get("ok") else 1


if __name__ == "__main__":
    args = sys.argv[1:]
    sys.exit(main(args[0], int(args[1]), Path(args[2]), Path(args[3]), args[4:] == ["signed"]))
