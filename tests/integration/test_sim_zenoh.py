"""The simulator on Zenoh: liveliness, ground truth, object poses, teleop, cameras (raw and
JPEG on request), and the instance rule (namespace drone{N}, system id 1+N)."""

from __future__ import annotations

import socket
import time

import cv2
import numpy as np
import pytest
from pymavlink.dialects.v20 import common as mavlink

from dronewrapper.msgs import registry
from dronewrapper.msgs.geometry import Twist, Vector3
from support import client_node, python_module, wait_for

pytestmark = pytest.mark.integration

INSTANCE = 3
NS = f"drone{INSTANCE}"


def test_sim_publishes_truth_objects_and_cameras(spawn, router):
    udp = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    udp.bind(("127.0.0.1", 0))
    udp.settimeout(0.5)
    argv = python_module(
        "dronewrapper_sim", "--scenario", "beacon_static", "--instance", str(INSTANCE),
        "--connect", router, "--udp-onboard", f"{udp.getsockname()[1]}:0", "--udp-gcs", "off",
        "--width", "160", "--height", "120", "--camera-rate", "10",
    )  # fmt: skip
    proc = spawn(argv, "sim")
    try:
        with client_node(router, namespace=NS) as node:
            alive_key = registry.ALIVE.key(NS, service="sim")

            def alive() -> bool:
                replies = node.session.liveliness().get(alive_key, timeout=1.0)
                return any(r.ok is not None for r in replies)

            wait_for(alive, 30, interval=0.2, what=f"liveliness token {alive_key}")

            # the instance's system id on MAVLink
            data, _ = udp.recvfrom(4096)
            parser = mavlink.MAVLink(None)
            msgs = parser.parse_buffer(data) or []
            assert msgs and msgs[0].get_srcSystem() == 1 + INSTANCE

            truth = []
            node.subscribe(registry.SIM_GROUND_TRUTH, truth.append)
            target_poses = []
            node.subscribe(registry.SIM_OBJECT_POSE, target_poses.append, name="target")
            frontal = node.latest(registry.IMAGE_RAW, camera="cam_frontal")
            ventral = node.latest(registry.IMAGE_RAW, camera="cam_ventral")
            jpeg = node.latest(registry.IMAGE_COMPRESSED, camera="cam_frontal")

            wait_for(lambda: truth and target_poses, 10, what="ground truth and object poses")
            n_truth, n_target = len(truth), len(target_poses)
            time.sleep(2.0)
            assert (len(truth) - n_truth) / 2.0 >= 30  # >= 30 Hz
            assert (len(target_poses) - n_target) / 2.0 >= 10  # >= 10 Hz
            pose = truth[-1]
            assert pose.header.frame_id == "map"
            assert abs(pose.header.stamp - time.time()) < 1.0
            assert pose.pose.position.z == pytest.approx(0.0, abs=0.01)  # on the ground
            q = pose.pose.orientation
            assert q.x**2 + q.y**2 + q.z**2 + q.w**2 == pytest.approx(1.0)

            image = frontal.wait(10)
            assert (image.width, image.height, image.encoding) == (160, 120, "bgr8")
            assert image.header.frame_id == "cam_frontal"
            assert abs(image.header.stamp - time.time()) < 2.0
            assert len(image.data) == image.step * image.height == 160 * 120 * 3
            pixels = np.frombuffer(image.data, np.uint8).reshape(120, 160, 3)
            assert pixels.std() > 5  # a rendered scene, not a blank frame
            assert ventral.wait(10).header.frame_id == "cam_ventral"
            compressed = jpeg.wait(10)
            assert compressed.format == "jpeg"
            decoded = cv2.imdecode(np.frombuffer(compressed.data, np.uint8), cv2.IMREAD_COLOR)
            assert decoded.shape == (120, 160, 3)
            stamps = []
            node.subscribe(
                registry.IMAGE_RAW, lambda m: stamps.append(m.header.stamp), camera="cam_frontal"
            )
            time.sleep(2.0)
            assert 12 <= len(stamps) <= 24  # --camera-rate 10 (two subscribers here: one)

            # teleoperate the target east at 1 m/s
            start_x = target_poses[-1].pose.position.x
            cmd = node.publisher(registry.SIM_OBJECT_CMD_VEL, name="target")
            for _ in range(15):
                cmd.put(Twist(linear=Vector3(x=1.0)))
                time.sleep(0.1)
            moved = target_poses[-1].pose.position.x - start_x
            assert 0.8 < moved < 2.0
            time.sleep(1.0)  # a command older than 0.5 s stops the object
            still = target_poses[-1].pose.position.x
            time.sleep(0.5)
            assert target_poses[-1].pose.position.x == pytest.approx(still, abs=0.05)
    finally:
        udp.close()
    assert proc.stop() == 0
