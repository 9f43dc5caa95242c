"""The world around an external autopilot, wired: ``dronewrapper sim --autopilot px4-sih`` binds
its truth port, asks the sender for a faster truth stream, and publishes the truth it receives
over real UDP (HIL_STATE_QUATERNION bytes built by pymavlink, as PX4 SIH sends them) as ground
truth in the scenario's frame, with the object poses, the pose source's status and the frames."""

from __future__ import annotations

import math
import socket
import time

import pytest
from pymavlink.dialects.v20 import ardupilotmega as mavlink

from dronewrapper.msgs import registry
from dronewrapper.rotations import quat_from_rpy
from support import client_node, free_port, loopback_udp, python_module, wait_for

pytestmark = pytest.mark.integration

LAT0, LON0, ALT0 = 47.397742, 8.545594, 488.0
M_PER_DEG = math.radians(1.0) * 6371000.0


def truth_bytes(mav, t_s: float, north: float, up: float) -> bytes:
    x, y, z, w = quat_from_rpy(0.0, 0.0, 0.0)  # facing north
    msg = mavlink.MAVLink_hil_state_quaternion_message(
        int(t_s * 1e6), [w, x, y, z], 0.0, 0.0, 0.0,
        round((LAT0 + north / M_PER_DEG) * 1e7), round(LON0 * 1e7), round((ALT0 + up) * 1000),
        100, 0, 0, 0, 0, 0, 0, -981,
    )  # fmt: skip
    return msg.pack(mav)


def test_ground_truth_comes_from_the_external_autopilot(spawn, router):
    truth_port = free_port(socket.SOCK_DGRAM)  # for the world to bind
    argv = python_module(
        "dronewrapper_sim", "--scenario", "beacon_static", "--connect", router,
        "--autopilot", "px4-sih", "--autopilot-link", f"udp:127.0.0.1:{truth_port}",
        "--width", "160", "--height", "120", "--camera-rate", "10",
    )  # fmt: skip
    spawn(argv, "sim")
    px4 = loopback_udp(0.02)
    mav = mavlink.MAVLink(None, srcSystem=1, srcComponent=1)
    with client_node(router) as node:
        truth, status, requests = [], [], []
        node.subscribe(registry.SIM_GROUND_TRUTH, truth.append)
        node.subscribe(registry.SIM_POSE_SOURCE, status.append)
        target = node.latest(registry.SIM_OBJECT_POSE, name="target")
        frontal = node.latest(registry.IMAGE_RAW, camera="cam_frontal")
        t0 = time.monotonic()
        sent = 0
        flying_since: float | None = None  # on the ground until the world has aligned

        def send_due() -> None:
            nonlocal sent, flying_since
            t = time.monotonic() - t0
            if t < 0.04 * sent:
                return
            if flying_since is None and truth:
                flying_since = t
            airborne = flying_since is not None
            north = t - flying_since if airborne else 0.0  # 1 m/s north
            up = 2.0 if airborne else 0.0
            px4.sendto(truth_bytes(mav, 100.0 + t, north, up), ("127.0.0.1", truth_port))
            sent += 1

        def fly() -> bool:
            send_due()
            try:
                data, _ = px4.recvfrom(4096)
                requests.extend(mavlink.MAVLink(None).parse_buffer(data) or [])
            except TimeoutError:
                pass
            return len(truth) >= 40 and bool(requests)

        wait_for(fly, 30, interval=0.0, what="40 ground-truth poses and a rate request")
        request = next(r for r in requests if r.get_type() == "COMMAND_LONG")
        assert (request.command, request.param1, request.param2) == (511, 115, 20000)
        assert truth[0].pose.position.x == pytest.approx(0.0, abs=0.02)  # the scenario's start
        last = truth[-1]
        # north in the autopilot is the scenario's +x (it starts facing east); 2 m up
        flown = (time.monotonic() - t0) - flying_since
        assert 0.0 < last.pose.position.x <= flown + 0.05
        assert last.pose.position.y == pytest.approx(0.0, abs=0.02)
        assert last.pose.position.z == pytest.approx(2.0, abs=0.01)
        assert abs(last.header.stamp - time.time()) < 2.0  # wall clock (epoch)
        assert target.wait(5).pose.position.x == pytest.approx(6.0)  # the world runs as today
        image = frontal.wait(10)
        assert abs(image.header.stamp - time.time()) < 5.0
        wait_for(lambda: any(s.frames > 0 and s.aligned for s in status), 10, what="status")
        report = next(s for s in reversed(status) if s.frames > 0)
        assert report.source == "px4-sih" and report.link.endswith(str(truth_port))
        assert report.rotation_rad == pytest.approx(-math.pi / 2)
        assert 0.0 <= report.extrapolated_share <= 1.0 and report.age_max_s < 1.0
    px4.close()
