"""The simulator on Zenoh: liveliness, ground truth, object poses, teleop, cameras (raw and
JPEG on request), and the instance rule (namespace drone{N}, system id 1+N)."""

from __future__ import annotations

import itertools
import time

import cv2
import numpy as np
import pytest
from pymavlink.dialects.v20 import common as mavlink

from dronewrapper.msgs import registry
from dronewrapper.msgs.geometry import Twist, Vector3
from support import client_node, loopback_udp, python_module, wait_for

pytestmark = pytest.mark.integration

INSTANCE = 3
NS = f"drone{INSTANCE}"


def test_sim_publishes_truth_objects_and_cameras(spawn, router):
    udp = loopback_udp(10.0)  # the first datagram may follow the liveliness token late
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

            # rates from the publisher's stamps (median period: robust to a stalled test)
            wait_for(
                lambda: len(truth) > 60 and len(target_poses) > 25,
                20,
                what="ground truth and object poses",
            )
            assert median_period(truth) <= 1 / 30  # >= 30 Hz (50 Hz configured)
            assert median_period(target_poses) <= 1 / 10  # >= 10 Hz (20 Hz configured)
            pose = truth[-1]
            assert pose.header.frame_id == "map"
            assert abs(pose.header.stamp - time.time()) < 5.0  # wall clock (epoch), not sim time
            assert pose.pose.position.z == pytest.approx(0.0, abs=0.01)  # on the ground
            q = pose.pose.orientation
            assert q.x**2 + q.y**2 + q.z**2 + q.w**2 == pytest.approx(1.0)

            image = frontal.wait(10)
            assert (image.width, image.height, image.encoding) == (160, 120, "bgr8")
            assert image.header.frame_id == "cam_frontal"
            assert abs(image.header.stamp - time.time()) < 5.0  # wall clock (epoch)
            assert len(image.data) == image.step * image.height == 160 * 120 * 3
            pixels = np.frombuffer(image.data, np.uint8).reshape(120, 160, 3)
            assert pixels.std() > 5  # a rendered scene, not a blank frame
            assert ventral.wait(10).header.frame_id == "cam_ventral"
            compressed = jpeg.wait(10)
            assert compressed.format == "jpeg"
            decoded = cv2.imdecode(np.frombuffer(compressed.data, np.uint8), cv2.IMREAD_COLOR)
            assert decoded.shape == (120, 160, 3)
            frames = []
            node.subscribe(registry.IMAGE_RAW, frames.append, camera="cam_frontal")
            wait_for(lambda: len(frames) >= 16, 20, what="16 frontal frames")
            # --camera-rate 10, each frame once (two subscribers here: one render, one put)
            assert len({f.header.seq for f in frames}) == len(frames)
            assert 0.08 <= median_period(frames) <= 0.15

            # teleoperate the target east at 1 m/s: it moves east, no faster than commanded
            cmd = node.publisher(registry.SIM_OBJECT_CMD_VEL, name="target")
            start = target_poses[-1]
            first_cmd = time.time()

            def moved(pose) -> float:
                return pose.pose.position.x - start.pose.position.x

            def commanded_and_moved(distance: float):
                cmd.put(Twist(linear=Vector3(x=1.0)))
                return next((p for p in reversed(target_poses) if moved(p) >= distance), None)

            early = wait_for(lambda: commanded_and_moved(0.2), 10, interval=0.1, what="0.2 m")
            late = wait_for(lambda: commanded_and_moved(1.0), 10, interval=0.1, what="1 m")
            last_cmd = time.time()
            speed = (moved(late) - moved(early)) / (late.header.stamp - early.header.stamp)
            assert 0.5 < speed < 1.3, speed
            assert moved(late) <= 1.0 * (late.header.stamp - first_cmd) + 0.2
            assert abs(late.pose.position.y - start.pose.position.y) < 0.1

            # a command older than 0.5 s stops the object (within about 0.5 m)
            def stopped():
                now = target_poses[-1]
                before = [p for p in target_poses if p.header.stamp <= now.header.stamp - 0.5]
                return before and abs(moved(now) - moved(before[-1])) < 0.01 and now

            still = wait_for(stopped, 10, what="the target to stop")
            assert still.header.stamp > last_cmd
            assert moved(still) - moved(late) < 1.0, moved(still) - moved(late)
    finally:
        udp.close()
    assert proc.stop() == 0


def median_period(msgs: list) -> float:
    """The median interval (s) between the header stamps of ``msgs`` (in arrival order)."""
    stamps = [m.header.stamp for m in msgs]
    gaps = sorted(b - a for a, b in itertools.pairwise(stamps))
    return gaps[len(gaps) // 2]


def test_world_control_loads_a_scenario_and_resets_it(spawn, router):
    """The world services a ground station uses: which scenario runs; load another one; load
    the same one again to put its objects back at their start. Only fixed names load."""
    from dronewrapper.msgs.simulation import WorldLoad, WorldQuery
    from dronewrapper.runtime import ServiceError

    argv = python_module(
        "dronewrapper_sim", "--scenario", "beacon_static", "--connect", router,
        "--udp-onboard", "off", "--udp-gcs", "off", "--no-cameras",
    )  # fmt: skip
    spawn(argv, "sim")
    with client_node(router) as node:
        state = wait_for(
            lambda: _call_or_none(node, registry.SIM_WORLD, WorldQuery()), 30, what="world info"
        )
        assert state.scenario == "beacon_static" and state.objects == ["target"]
        assert "people_crossing_front" in state.available and state.loads == 0

        target = node.latest(registry.SIM_OBJECT_POSE, name="target")
        start = target.wait(10).pose.position
        push = node.publisher(registry.SIM_OBJECT_CMD_VEL, name="target")
        for _ in range(20):  # 1 s east at 1 m/s
            push.put(Twist(linear=Vector3(x=1.0)))
            time.sleep(0.05)
        wait_for(lambda: target.value.pose.position.x > start.x + 0.4, 10, what="target moved")

        reset = node.call(registry.SIM_WORLD_LOAD, WorldLoad(scenario="beacon_static"))
        assert reset.loads == 1
        wait_for(
            lambda: abs(target.value.pose.position.x - start.x) < 0.05, 10, what="target reset"
        )

        crossing = node.call(registry.SIM_WORLD_LOAD, WorldLoad(scenario="people_crossing_front"))
        assert crossing.scenario == "people_crossing_front" and len(crossing.objects) >= 2
        person = next(name for name in crossing.objects if name != "target")
        node.latest(registry.SIM_OBJECT_POSE, name=person).wait(10)

        for bad in ("nope", "../sim/scenarios/beacon_static.yaml", "/etc/passwd"):
            with pytest.raises(ServiceError, match="unknown scenario") as info:
                node.call(registry.SIM_WORLD_LOAD, WorldLoad(scenario=bad))
            assert info.value.code == "bad_request"


def _call_or_none(node, service, request):
    from dronewrapper.runtime import ServiceUnavailable

    try:
        return node.call(service, request, timeout=2.0)
    except ServiceUnavailable:
        return None
