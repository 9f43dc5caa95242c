"""The controller node in-process on a real Zenoh router, against a small fake of the bridge.

The fake bridge holds the bridge's keys only (State, ExtendedState, pose, the ARMING /
SET_MODE / LAND services) and records every setpoint; the controller embeds the real SDK.
"""

from __future__ import annotations

import itertools
import threading
import time
from collections.abc import Iterator
from contextlib import contextmanager

import pytest

from dronewrapper.msgs import registry
from dronewrapper.msgs.control import (
    CONTROLLER_HOVER,
    CONTROLLER_SEARCH,
    CONTROLLER_TAKEOFF,
    CONTROLLER_TRACKING,
    ControllerStatus,
)
from dronewrapper.msgs.mavros import PositionTarget
from dronewrapper.msgs.std import Header
from dronewrapper.msgs.vision import BoundingBox2D, Detection2D, Detections, Point2D, Pose2D
from dronewrapper.runtime.config import load_config
from dronewrapper_controller.config import Config
from dronewrapper_controller.node import run
from fake_bridge import FakeBridge
from support import client_node, wait_for


def blob(x: float, y: float, radius: float) -> Detection2D:
    box = BoundingBox2D(
        center=Pose2D(position=Point2D(x=x, y=y)), size_x=2 * radius, size_y=2 * radius
    )
    return Detection2D(bbox=box, circle_radius=radius, id="")


class Harness:
    """The controller's run() on its own thread and node, plus a detections/status client."""

    def __init__(self, endpoint: str, overrides: list[str]) -> None:
        self.config = load_config(Config, None, ["search_delay=1.0", *overrides])
        self.node = client_node(endpoint, name="controller")
        self.client = client_node(endpoint, name="tester")
        self.detections = self.client.publisher(registry.DETECTIONS)
        self.statuses: list[ControllerStatus] = []
        self.client.subscribe(registry.CONTROLLER_STATUS, self.statuses.append)
        self.exit_code: int | None = None
        self.thread = threading.Thread(target=self._run, daemon=True)
        self.thread.start()

    def _run(self) -> None:
        self.exit_code = run(self.node, self.config)

    def publish(self, *dets: Detection2D, stamp: float | None = None) -> float:
        stamp = stamp or time.time()
        self.detections.put(
            Detections(
                header=Header(stamp=stamp, frame_id="cam_frontal"),
                detections=list(dets),
                image_width=640,
                image_height=480,
                detector="color",
            )
        )
        return stamp

    def state(self) -> str:
        return self.statuses[-1].state if self.statuses else ""

    def stop(self, timeout: float = 20.0) -> int | None:
        self.node.stop()
        self.thread.join(timeout)
        return self.exit_code

    def close(self) -> None:
        self.stop()
        self.node.close()
        self.client.close()


@contextmanager
def feeding(ctl: Harness, *dets: Detection2D, hz: float = 20.0) -> Iterator[list[float]]:
    """Publish detections (``dets``, maybe none) at ``hz`` on a thread; yields their stamps."""
    stop = threading.Event()
    stamps: list[float] = []

    def run() -> None:
        while not stop.is_set():
            stamps.append(ctl.publish(*dets))
            stop.wait(1.0 / hz)

    thread = threading.Thread(target=run, daemon=True)
    thread.start()
    try:
        yield stamps
    finally:
        stop.set()
        thread.join(5)


@pytest.fixture
def flying_bridge(router):
    bridge = FakeBridge(router, flying=True)
    yield bridge
    bridge.close()


def test_tracks_with_the_frames_stamp_and_right_signs(router, flying_bridge):
    ctl = Harness(router, ["takeoff.on_start=false", "on_exit=stop"])
    try:
        wait_for(
            lambda: ctl.state() == "hover" or ctl.state() == "search", 15, what="controller up"
        )
        # blob up-left of centre and small (far), at 20 Hz
        with feeding(ctl, blob(200, 140, 8)) as stamps:

            def tracked() -> list[PositionTarget]:
                sps = flying_bridge.velocity_setpoints()
                found = [sp for sp in sps if sp.header.stamp in stamps]
                return found if len(found) > 20 else []

            tracked_sps = wait_for(tracked, 20, what="20 setpoints carrying a frame's stamp")
            status = wait_for(
                lambda: next(
                    (s for s in reversed(ctl.statuses) if s.state == CONTROLLER_TRACKING), None
                ),
                10,
                what="a tracking status",
            )
        last = tracked_sps[-1]
        assert last.velocity.x > 0  # too far: forward
        assert last.velocity.y == 0.0  # vy stays 0
        assert last.velocity.z > 0  # above centre: climb
        assert last.yaw_rate > 0  # left of centre: turn left (CCW)
        assert last.velocity.x <= ctl.config.follow_color.vx.out_limit
        assert status.target_visible
        assert status.source_stamp in stamps and status.mode == "follow_color"
    finally:
        assert ctl.stop() == 0
        ctl.close()


def test_status_rate_stale_hover_then_search(router, flying_bridge):
    ctl = Harness(router, ["takeoff.on_start=false", "on_exit=stop", "search_yaw_rate=0.4"])
    try:
        wait_for(lambda: len(ctl.statuses) >= 3, 15, what="status")
        n0 = len(ctl.statuses)
        wait_for(lambda: len(ctl.statuses) >= n0 + 20, 15, what="20 more statuses")
        # >= 5 Hz (10 Hz nominal) by the median interval of the publication stamps: robust to
        # a busy machine stalling the process now and then, not to a slow status thread
        stamps = [s.header.stamp for s in ctl.statuses[n0:]]
        gaps = sorted(b - a for a, b in itertools.pairwise(stamps))
        assert gaps[len(gaps) // 2] <= 1.0 / 5.0, f"median status interval {gaps[len(gaps) // 2]}"
        n1 = len(ctl.statuses)
        with feeding(ctl, blob(600, 240, 20)):  # target on the right ...
            wait_for(
                lambda: any(s.state == CONTROLLER_TRACKING for s in ctl.statuses[n1:]),
                10,
                what="tracking",
            )
        # ... then detections stop (perception died)
        wait_for(lambda: ctl.state() == CONTROLLER_HOVER, 10, what="hover on stale detections")
        n2 = len(ctl.statuses)
        time.sleep(1.5)  # longer than search_delay: still hover, never search blind
        assert {s.state for s in ctl.statuses[n2:]} <= {CONTROLLER_HOVER}
        assert ctl.state() == CONTROLLER_HOVER
        wait_for(lambda: flying_bridge.last_command() == (0.0, 0.0, 0.0), 5, what="zero command")
        # fresh detections without the target: search towards the right (cw)
        with feeding(ctl):
            wait_for(lambda: ctl.state() == CONTROLLER_SEARCH, 10, what="search")
            wait_for(
                lambda: flying_bridge.last_command() == (0.0, 0.0, pytest.approx(-0.4)),
                10,
                what="a clockwise search command",
            )
    finally:
        ctl.close()


def test_exit_with_on_exit_stop_sends_zero_and_stops_commanding(router, flying_bridge):
    ctl = Harness(router, ["takeoff.on_start=false", "on_exit=stop"])
    try:
        wait_for(lambda: ctl.statuses, 15, what="status")
        with feeding(ctl, blob(100, 100, 5)):
            wait_for(
                lambda: any(s.state == CONTROLLER_TRACKING for s in ctl.statuses),
                10,
                what="tracking",
            )
            wait_for(lambda: flying_bridge.velocity_setpoints(), 10, what="setpoints")
            assert ctl.stop() == 0
        flying_bridge.wait_quiet()  # nothing streamed any more ...
        assert flying_bridge.last_command() == (0.0, 0.0, 0.0)  # ... after a zero command
        assert flying_bridge.land_calls == 0
    finally:
        ctl.close()


def test_takes_off_on_start_and_lands_on_exit(router):
    bridge = FakeBridge(router, flying=False)
    ctl = Harness(router, ["takeoff.height=1.5", "on_exit=land"])
    try:
        wait_for(
            lambda: any(s.state == CONTROLLER_TAKEOFF for s in ctl.statuses), 15, what="takeoff"
        )
        wait_for(lambda: bridge.z >= 1.5 - 1e-6, 15, what="climb")
        wait_for(lambda: ctl.state() in (CONTROLLER_HOVER, CONTROLLER_SEARCH), 15, what="servoing")
        # taking off, the controller only watches: its first velocity command came at the top
        # (the SDK's take-off returns within 0.1 m of the 1.5 m goal)
        wait_for(lambda: bridge.z_at_first_velocity is not None, 10, what="a velocity command")
        first_z = bridge.z_at_first_velocity
        assert first_z >= 1.4 - 1e-6, f"velocity commanded at z={first_z:.2f} m, mid-climb"
        assert bridge.armed and bridge.mode == "OFFBOARD"
        assert ctl.stop() == 0
        assert bridge.land_calls == 1 and not bridge.armed
    finally:
        ctl.close()
        bridge.close()


def test_no_bridge_gives_up_with_an_error(router):
    ctl = Harness(router, ["ready_timeout=1.5", "takeoff.on_start=false"])
    try:
        ctl.thread.join(15)
        assert not ctl.thread.is_alive() and ctl.exit_code == 1
    finally:
        ctl.close()
