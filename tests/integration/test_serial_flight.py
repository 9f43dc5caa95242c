"""Listing 1 over a serial line at real speed: the simulator's autopilot <- a pseudo-terminal
paced at 57600 or 921600 baud (dronewrapper_sim.serial_relay) -> the bridge on that device.

The bridge is configured as on a drone (``connection`` = the device, ``baud``); it fits its
stream requests to the line and reports the line's load on ``{ns}/bridge/link``. Each run
prints its figures (pose rate, load, the frames' time on the line, drops) for docs/serial.md.
"""

from __future__ import annotations

import contextlib
import math
import os
import select
import socket
import subprocess
import time
from collections.abc import Iterator, Sequence
from typing import Any

import pytest
from pymavlink.dialects.v20 import common as mavlink

from dronewrapper import DroneWrapper
from dronewrapper.geodesy import to_geodetic
from dronewrapper.msgs import registry
from dronewrapper.msgs.mavros import LANDED_STATE_ON_GROUND
from dronewrapper.security.keystore import KeyStore
from dronewrapper_bridge_mavlink.config import DEFAULT_MESSAGE_RATES
from dronewrapper_bridge_mavlink.link_budget import fit_rates
from dronewrapper_sim.serial_relay import SerialRelay
from support import client_node, free_port, python_module, wait_for

pytestmark = pytest.mark.integration


def start_sim(spawn, router: str, port: int, *extra: str):
    return spawn(
        python_module(
            "dronewrapper_sim", "--scenario", "empty", "--no-cameras",
            "--udp-onboard", f"{port}:0", "--udp-gcs", "off",
            "--connect", router, "--name", "sim", *extra,
        ),
        "sim",
    )  # fmt: skip


def start_bridge(spawn, router: str, device: str, baud: int, *extra: str):
    return spawn(
        python_module(
            "dronewrapper_bridge_mavlink", "--connect", router,
            "--connection", device, "--baud", str(baud), *extra,
        ),
        "bridge",
    )  # fmt: skip


@contextlib.contextmanager
def serial_drone(
    spawn, router: str, baud: int, *, bridge: Sequence[str] = (), sim: Sequence[str] = ()
) -> Iterator[tuple[SerialRelay, Any]]:
    """The simulator's autopilot behind a serial line paced at ``baud``, and the bridge on the
    line's device (``bridge``, ``sim``: more arguments); yields the relay and the bridge."""
    port = free_port(socket.SOCK_DGRAM)
    with SerialRelay(baud, udp_listen=("127.0.0.1", port)) as relay:
        process = start_bridge(spawn, router, relay.path, baud, *bridge)
        start_sim(spawn, router, port, *sim)
        yield relay, process


class Arrivals:
    """Arrival times of a topic's samples."""

    def __init__(self) -> None:
        self.times: list[float] = []

    def __call__(self, _msg) -> None:
        self.times.append(time.monotonic())

    def rate(self, since: float) -> float:
        recent = [t for t in self.times if t >= since]
        return (len(recent) - 1) / (recent[-1] - recent[0]) if len(recent) > 2 else 0.0


@pytest.mark.parametrize("baud", [57600, 921600])
def test_listing_1_flies_over_a_serial_line(baud, router, spawn):
    with serial_drone(spawn, router, baud) as (relay, _):
        user = client_node(router, name="watcher")
        links: list = []
        poses = Arrivals()
        user.subscribe(registry.LINK_STATUS, links.append)
        user.subscribe(registry.LOCAL_POSE, poses)
        try:
            with DroneWrapper("drone", router, timeout=60, land_on_exit=True) as drone:
                started = time.monotonic()
                drone.takeoff(h=2.5)  # Listing 1, with a 2 s spin instead of 5
                takeoff_s = time.monotonic() - started
                dropped_before = relay.down.dropped_frames  # the streams are fitted by now
                relay.down.delays.clear()
                yaw0 = drone.get_yaw()
                drone.set_cmd_vel(az=1)
                spin_from = time.monotonic()
                drone.wait_for(
                    lambda: (drone.get_yaw() - yaw0) % (2 * math.pi) > 1.0, 10, "1 rad turned"
                )
                time.sleep(max(0.0, 2.0 - (time.monotonic() - spin_from)))
                flying_links = list(links)
                pose_rate = poses.rate(spin_from)
                dropped_flying = relay.down.dropped_frames - dropped_before
                delays = sorted(relay.down.delays)
                drone.land()
                assert drone.get_landed_state() == LANDED_STATE_ON_GROUND
        finally:
            user.close()
    assert flying_links, "no link status from the bridge"
    link = flying_links[-1]
    assert (link.kind, link.baud, link.capacity) == ("serial", baud, baud / 10)
    assert 0.0 < link.load < 1.0, link
    line_ms = [delays[int(q * (len(delays) - 1))] * 1000 for q in (0.5, 0.95)]
    print(
        f"\n{baud} baud: take-off {takeoff_s:.1f} s; pose {pose_rate:.0f} Hz; frames' time on "
        f"the line (autopilot to bridge) median {line_ms[0]:.0f} ms, 95 % {line_ms[1]:.0f} ms; "
        f"{link.describe()}; frames dropped by the line {relay.down.dropped_frames} "
        f"({dropped_flying} after take-off), {relay.up.dropped_frames} toward the autopilot"
    )
    # the fitted streams leave room: nothing is dropped (a margin for the relay's thread
    # starved on a busy machine, which then finds more frames waiting than a line would hold)
    assert dropped_flying <= 0.02 * len(delays) and relay.up.dropped_frames == 0
    if baud == 57600:
        assert link.stream_scale < 1.0  # the default rates were fitted to the line
        assert pose_rate >= 15.0, pose_rate  # the controller's pose still arrives often
    else:
        assert link.stream_scale == 1.0 and link.load < 0.2


def test_signed_mavlink_over_a_serial_line(router, spawn, tmp_path):
    """The same line at 57600 with MAVLink 2 signing on both ends: every frame carries 13 bytes
    more, the bridge fits its streams for that, and nothing is rejected."""
    store = KeyStore(tmp_path / "keys")
    store.new_mavlink_key()
    key = str(store.mavlink_key)
    with serial_drone(
        spawn,
        router,
        57600,
        bridge=("--set", f"signing_key_file={key}"),
        sim=("--signing-key", key),
    ):
        user = client_node(router, name="watcher")
        links: list = []
        user.subscribe(registry.LINK_STATUS, links.append)
        try:
            with DroneWrapper("drone", router, timeout=60, land_on_exit=True) as drone:
                drone.takeoff(h=1.5)
                drone.land()
                assert drone.get_landed_state() == LANDED_STATE_ON_GROUND
        finally:
            user.close()
    link = links[-1]
    assert link.rejected == 0 and link.load < 1.0, link
    unsigned = fit_rates(DEFAULT_MESSAGE_RATES, 57600, signed=False)
    assert link.stream_scale < unsigned.scale  # the signatures' bytes were budgeted
    print(f"\n57600 baud, signed: {link.describe()}")


def test_a_line_cut_for_4_s_comes_back_as_one_reconnect(router, spawn):
    """The cable out for 4 s (the relay carries nothing): the bridge loses the heartbeat, finds
    it again by itself when the bytes flow, and counts one reconnect."""
    with serial_drone(spawn, router, 921600) as (relay, _):
        user = client_node(router, name="watcher")
        links: list = []
        states: list = []
        user.subscribe(registry.LINK_STATUS, links.append)
        user.subscribe(registry.STATE, lambda s: states.append((time.monotonic(), s.connected)))
        try:
            wait_for(lambda: states and states[-1][1], 60, what="connected")
            relay.unplugged = True
            time.sleep(4.0)
            wait_for(lambda: not states[-1][1], 10, what="the heartbeat lost")
            relay.unplugged = False
            plugged = time.monotonic()
            wait_for(lambda: states[-1][1], 10, what="connected again")
            back_s = next(t for t, connected in states if t >= plugged and connected) - plugged
            wait_for(lambda: links[-1].reconnects == 1, 5, what="the reconnect counted")
        finally:
            user.close()
    print(f"\nline cut for 4 s: connected again {back_s:.1f} s after; {links[-1].describe()}")


def test_a_nearly_full_line_is_told_in_the_log_and_by_doctor(router, spawn):
    """57600 baud with the configured rates (``link_share`` 1.0: no room kept): the bridge
    warns that the line is nearly full, and ``dronewrapper doctor`` shows how full it is (a
    ``warn`` from 80 %; the load it sees depends on how fast the simulator runs on this
    machine, so its verdict is checked against the figure it prints)."""
    with serial_drone(spawn, router, 57600, bridge=("--set", "link_share=1.0")) as (_, bridge):
        user = client_node(router, name="watcher")
        links: list = []
        user.subscribe(registry.LINK_STATUS, links.append)
        try:
            wait_for(  # past the first second's burst (the autopilot's own rates): steady
                lambda: len(links) > 3 and all(0.8 <= s.load < 1.0 for s in links[-3:]),
                60,
                what="a line steadily 80 to 100 % full",
            )
            doctor = subprocess.run(
                python_module("dronewrapper", "doctor", "--connect", router, "--seconds", "2",
                              "--no-bandwidth"),
                capture_output=True, text=True, timeout=60,
            )  # fmt: skip
        finally:
            user.close()
    said = [line for line in doctor.stdout.splitlines() if "% full (serial 57600 baud" in line]
    assert said, doctor.stdout
    percent = int(said[0].split("link ", 1)[1].split(" %", 1)[0])
    verdict = "FAIL" if percent >= 100 else "warn" if percent >= 80 else "ok  "
    assert said[0].startswith(f"{verdict} drone 'drone': link {percent} % full"), said[0]
    assert "WARNING bridge_mavlink: link " in bridge.output(), bridge.output()[-2000:]
    print(f"\n{said[0]}")


@pytest.mark.parametrize("baud", [57600, 921600])
def test_a_mission_and_parameters_over_a_serial_line(baud, router, spawn):
    """A 20-waypoint mission uploaded (each item asked for and acked over the line), read
    back as the bridge publishes it, and a parameter read and written; figures printed."""
    with serial_drone(spawn, router, baud) as (relay, _):
        user = client_node(router, name="watcher")
        homes: list = []
        links: list = []
        user.subscribe(registry.HOME_POSITION, homes.append)
        user.subscribe(registry.LINK_STATUS, links.append)
        with user, DroneWrapper("drone", router, timeout=60) as drone:
            wait_for(lambda: homes and math.isfinite(homes[-1].latitude), 30, what="home")
            # the transfer is timed on the line as it runs, after the start-up burst (the
            # autopilot's default rates, before the bridge's fitted ones, fill it: docs/serial.md)
            wait_for(lambda: links and links[-1].load < 0.9, 30, what="the line below 90 %")
            lat, lon = homes[-1].latitude, homes[-1].longitude
            plan = [
                (*to_geodetic((lat, lon), 10 * math.cos(a), 10 * math.sin(a)), 5.0)
                for a in (2 * math.pi * i / 20 for i in range(20))
            ]
            started = time.monotonic()
            assert drone.upload_mission(plan) == 20
            upload_s = time.monotonic() - started
            started = time.monotonic()
            assert drone.param_set("MPC_XY_VEL_MAX", 5.0) == pytest.approx(5.0)
            assert drone.param_get("MPC_XY_VEL_MAX") == pytest.approx(5.0)
            params_s = time.monotonic() - started
    assert relay.up.dropped_frames == 0
    print(
        f"\n{baud} baud: 20-item mission uploaded in {upload_s:.2f} s; a parameter written and "
        f"read back in {params_s:.2f} s"
    )


def read_exactly(fd: int, count: int, timeout: float = 5.0) -> bytes:
    data = b""
    deadline = time.monotonic() + timeout
    while len(data) < count and time.monotonic() < deadline:
        if select.select([fd], [], [], 0.05)[0]:
            data += os.read(fd, count - len(data))
    return data


def test_a_pseudo_terminal_for_the_autopilot_carries_whole_frames_both_ways():
    """``pty``: the firmware opens a device of its own (PX4 SITL's ``mavlink start -d``,
    ArduCopter SITL's ``--serial0 uart:``, as tests/sitl/test_serial_sitl.py runs them); frames
    cross whole both ways at the line's pace (about 0.1 s, no process)."""
    mav = mavlink.MAVLink(None, srcSystem=1, srcComponent=1)
    frame = mav.heartbeat_encode(2, 12, 0, 0, 4).pack(mav)
    with SerialRelay(115200, pty=True) as relay:
        autopilot = os.open(relay.autopilot_path, os.O_RDWR | os.O_NOCTTY)
        bridge = os.open(relay.path, os.O_RDWR | os.O_NOCTTY)
        try:
            os.write(autopilot, frame * 3)
            assert read_exactly(bridge, 3 * len(frame)) == frame * 3
            os.write(bridge, frame)
            assert read_exactly(autopilot, len(frame)) == frame
        finally:
            os.close(autopilot)
            os.close(bridge)
    assert relay.down.carried == 3 * len(frame) and relay.up.carried == len(frame)
