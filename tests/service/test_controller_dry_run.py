"""The controller's dry run (``dry_run: true``, the webcam desk graph): with no aircraft at all
it servoes on the detections and shows its commands in its status, and commands nothing."""

from __future__ import annotations

import threading
import time

from dronewrapper.msgs import registry
from dronewrapper.msgs.control import CONTROLLER_TRACKING
from dronewrapper.msgs.std import Header
from dronewrapper.msgs.vision import BoundingBox2D, Detection2D, Detections, Point2D, Pose2D
from dronewrapper.runtime.config import load_config
from dronewrapper_controller.config import Config
from dronewrapper_controller.node import run
from support import client_node, wait_for


def test_dry_run_shows_commands_and_sends_none(router):
    config = load_config(Config, None, ["mode=follow_color", "dry_run=true"])
    tester = client_node(router, name="tester")
    setpoints: list = []
    tester.subscribe(registry.SETPOINT_RAW_LOCAL, setpoints.append)
    status = tester.latest(registry.CONTROLLER_STATUS)
    detections = tester.publisher(registry.DETECTIONS)
    node = client_node(router, name="controller")
    result: list[int] = []
    thread = threading.Thread(target=lambda: result.append(run(node, config)), daemon=True)
    thread.start()
    box = BoundingBox2D(center=Pose2D(position=Point2D(x=520, y=200)), size_x=30, size_y=30)
    blob = Detection2D(bbox=box, circle_radius=15.0, id="")
    try:

        def tracking() -> bool:
            stamp = time.time()
            detections.put(
                Detections(
                    header=Header(stamp=stamp, frame_id="cam_frontal"),
                    detections=[blob],
                    image_width=640,
                    image_height=480,
                    detector="color",
                )
            )
            s = status.value
            return s is not None and s.state == CONTROLLER_TRACKING and s.source_stamp > 0

        wait_for(tracking, 20, interval=0.05, what="the dry-run controller tracking")
        s = status.value
        assert s.cmd_yaw_rate < 0  # blob right of centre: turn right (clockwise, negative)
        assert s.error_yaw != 0
        time.sleep(0.3)  # a setpoint stream would have sent several by now
        assert setpoints == []
    finally:
        node.stop()
        thread.join(10)
        node.close()
        tester.close()
    assert result == [0]
