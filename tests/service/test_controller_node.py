"""The controller node in-process on a real Zenoh router, against a small fake of the bridge.

The fake bridge holds the bridge's keys only (State, ExtendedState, pose, the ARMING /
SET_MODE / LAND services) and records every setpoint; the controller embeds the real SDK.
"""

from __future__ import annotations

import threading
import time

import pytest

from dronewrapper.msgs import registry
from dronewrapper.msgs.control import (
    CONTROLLER_HOVER,
    CONTROLLER_SEARCH,
    CONTROLLER_TAKEOFF,
    CONTROLLER_TRACKING,
    ControllerStatus,
)
from dronewrapper.msgs.geometry import PoseStamped
from dronewrapper.msgs.mavros import (
    LANDED_STATE_IN_AIR,
    LANDED_STATE_ON_GROUND,
    MASK_POSITION,
    MASK_VELOCITY,
    CommandBoolResult,
    CommandTOLResult,
    ExtendedState,
    PositionTarget,
    SetModeResult,
    State,
)
from dronewrapper.msgs.std import Header
from dronewrapper.msgs.vision import BoundingBox2D, Detection2D, Detections, Point2D, Pose2D
from dronewrapper.runtime.config import load_config
from dronewrapper_controller.config import Config
from dronewrapper_controller.node import run
from support import client_node, wait_for


class FakeBridge:
    """The bridge's keys with a simple aircraft: position setpoints make it climb at 1 m/s."""

    def __init__(self, endpoint: str, *, flying: bool) -> None:
        self.node = client_node(endpoint, name="bridge_fake")
        self.armed = flying
        self.mode = "OFFBOARD" if flying else "AUTO.LOITER"
        self.z = 2.0 if flying else 0.0
        self.z_goal = self.z
        self.landed = LANDED_STATE_IN_AIR if flying else LANDED_STATE_ON_GROUND
        self.setpoints: list[tuple[float, PositionTarget]] = []
        self.land_calls = 0
        self._lock = threading.Lock()
        self._state = self.node.publisher(registry.STATE)
        self._ext = self.node.publisher(registry.EXTENDED_STATE)
        self._pose = self.node.publisher(registry.LOCAL_POSE)
        self.node.subscribe(registry.SETPOINT_RAW_LOCAL, self._on_setpoint)
        self.node.serve(registry.ARMING, self._arming)
        self.node.serve(registry.SET_MODE, self._set_mode)
        self.node.serve(registry.LAND, self._land)
        self._thread = threading.Thread(target=self._publish_loop, daemon=True)
        self._thread.start()
        self.node.announce()

    def _on_setpoint(self, sp: PositionTarget) -> None:
        with self._lock:
            self.setpoints.append((time.monotonic(), sp))
            if sp.type_mask == MASK_POSITION and self.armed:
                self.z_goal = sp.position.z

    def _arming(self, req):
        self.armed = req.value
        return CommandBoolResult(success=True, result=0)

    def _set_mode(self, req):
        self.mode = req.custom_mode
        return SetModeResult(mode_sent=True, result=0)

    def _land(self, _req):
        self.land_calls += 1
        self.mode, self.z_goal, self.landed, self.armed = (
            "AUTO.LAND",
            0.0,
            LANDED_STATE_ON_GROUND,
            False,
        )
        self.z = 0.0
        return CommandTOLResult(success=True, result=0)

    def _publish_loop(self) -> None:
        while not self.node.stop_event.wait(0.05):
            now = time.time()
            with self._lock:
                self.z += max(-0.05, min(0.05, self.z_goal - self.z))  # 1 m/s at 20 Hz
                if self.z > 0.1 and self.armed:
                    self.landed = LANDED_STATE_IN_AIR
            self._state.put(
                State(
                    header=Header(stamp=now),
                    connected=True,
                    armed=self.armed,
                    guided=self.mode == "OFFBOARD",
                    mode=self.mode,
                    autopilot="px4",
                )
            )
            self._ext.put(ExtendedState(header=Header(stamp=now), landed_state=self.landed))
            pose = PoseStamped(header=Header(stamp=now, frame_id="map"))
            pose.pose.position.z = self.z
            pose.pose.orientation.w = 1.0
            self._pose.put(pose)

    def velocity_setpoints(self, since: float = 0.0) -> list[PositionTarget]:
        with self._lock:
            return [sp for t, sp in self.setpoints if t >= since and sp.type_mask == MASK_VELOCITY]

    def close(self) -> None:
        self.node.close()


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
        stamps = []
        deadline = time.monotonic() + 3.0
        while time.monotonic() < deadline:  # blob up-left of centre and small (far): 20 Hz
            stamps.append(ctl.publish(blob(200, 140, 8)))
            time.sleep(0.05)
        sps = flying_bridge.velocity_setpoints()
        tracked = [sp for sp in sps if sp.header.stamp in stamps]
        assert len(tracked) > 20, f"{len(tracked)} setpoints carried a frame's stamp"
        last = tracked[-1]
        assert last.velocity.x > 0  # too far: forward
        assert last.velocity.y == 0.0  # vy stays 0
        assert last.velocity.z > 0  # above centre: climb
        assert last.yaw_rate > 0  # left of centre: turn left (CCW)
        assert last.velocity.x <= ctl.config.follow_color.vx.out_limit
        status = wait_for(lambda: ctl.statuses[-1], 2)
        assert status.state == CONTROLLER_TRACKING and status.target_visible
        assert status.source_stamp in stamps and status.mode == "follow_color"
    finally:
        assert ctl.stop() == 0
        ctl.close()


def test_status_rate_stale_hover_then_search(router, flying_bridge):
    ctl = Harness(router, ["takeoff.on_start=false", "on_exit=stop", "search_yaw_rate=0.4"])
    try:
        wait_for(lambda: len(ctl.statuses) >= 3, 15, what="status")
        n0, t0 = len(ctl.statuses), time.monotonic()
        time.sleep(2.0)
        rate = (len(ctl.statuses) - n0) / (time.monotonic() - t0)
        assert rate >= 5.0, f"status at {rate:.1f} Hz"
        for _ in range(10):  # target on the right, then detections stop (perception died)
            ctl.publish(blob(600, 240, 20))
            time.sleep(0.05)
        wait_for(lambda: ctl.state() == CONTROLLER_TRACKING, 5, what="tracking")
        since = time.monotonic()
        wait_for(lambda: ctl.state() == CONTROLLER_HOVER, 5, what="hover on stale detections")
        time.sleep(1.5)  # longer than search_delay: still hover, never search blind
        assert ctl.state() == CONTROLLER_HOVER
        last = flying_bridge.velocity_setpoints(since)[-1]
        assert (last.velocity.x, last.velocity.z, last.yaw_rate) == (0.0, 0.0, 0.0)
        # fresh detections without the target: hover, then search towards the right (cw)
        end = time.monotonic() + 2.5
        while time.monotonic() < end:
            ctl.publish()
            time.sleep(0.05)
        assert ctl.state() == CONTROLLER_SEARCH
        last = flying_bridge.velocity_setpoints()[-1]
        assert last.yaw_rate == pytest.approx(-0.4) and last.velocity.x == 0.0
    finally:
        ctl.close()


def test_exit_with_on_exit_stop_sends_zero_and_stops_commanding(router, flying_bridge):
    ctl = Harness(router, ["takeoff.on_start=false", "on_exit=stop"])
    try:
        wait_for(lambda: ctl.statuses, 15, what="status")
        for _ in range(10):
            ctl.publish(blob(100, 100, 5))
            time.sleep(0.05)
        wait_for(lambda: flying_bridge.velocity_setpoints(), 5, what="setpoints")
        assert ctl.stop() == 0
        last = flying_bridge.velocity_setpoints()[-1]
        assert (last.velocity.x, last.velocity.z, last.yaw_rate) == (0.0, 0.0, 0.0)
        n = len(flying_bridge.setpoints)
        time.sleep(0.5)
        assert len(flying_bridge.setpoints) == n  # nothing streamed any more
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
        assert not bridge.velocity_setpoints()  # taking off: the controller only watches
        wait_for(lambda: bridge.z >= 1.5 - 1e-6, 15, what="climb")
        wait_for(lambda: ctl.state() in (CONTROLLER_HOVER, CONTROLLER_SEARCH), 15, what="servoing")
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
