"""After a router restart the SDK never resends a command that went stale meanwhile (issue 12
item 8): a real router is stopped and restarted on the same endpoint between an SDK app and a
subscriber standing in for the bridge."""

from __future__ import annotations

import threading
import time

from dronewrapper import DroneWrapper
from dronewrapper.msgs import registry
from dronewrapper.msgs.mavros import PositionTarget
from support import client_node, free_endpoint, wait_for, zenoh_router


class Received:
    def __init__(self) -> None:
        self.lock = threading.Lock()
        self.targets: list[tuple[float, PositionTarget]] = []

    def __call__(self, target: PositionTarget) -> None:
        with self.lock:
            self.targets.append((time.monotonic(), target))

    def since(self, t: float) -> list[PositionTarget]:
        with self.lock:
            return [m for at, m in self.targets if at >= t]


def test_a_stale_command_is_not_resent_after_a_router_restart():
    endpoint = free_endpoint()
    received = Received()
    with zenoh_router(endpoint):
        bridge = client_node(endpoint, name="bridge_mavlink")
        bridge.subscribe(registry.SETPOINT_RAW_LOCAL, received)
        drone = DroneWrapper(connect=endpoint, cameras=(), wait=False)
        try:
            streamer = drone.client.stream.core
            wait_for(lambda: streamer._matched_once, 20, what="the setpoint route")
            drone.set_cmd_vel(vx=1.0)
            wait_for(lambda: len(received.since(0)) >= 5, 20, what="setpoints at the bridge")
            stopped = True
        except BaseException:
            drone.close()
            bridge.close()
            raise
    try:
        assert stopped
        wait_for(lambda: not streamer.link_ok, 30, what="the SDK to notice the link gap")
        withheld = streamer.withheld
        wait_for(lambda: streamer.withheld > withheld, 5, what="setpoints withheld in the gap")
        stale_at = streamer._set_at + streamer.expiry + 0.2  # the gap outlasts the expiry
        while time.monotonic() < stale_at:
            time.sleep(0.05)
        with zenoh_router(endpoint):
            wait_for(lambda: streamer.link_ok, 60, what="the SDK to see the bridge again")
            back = time.monotonic()
            assert streamer.dropped_after_gap == 1, vars(streamer)
            assert drone.commanding is None  # the stale 1 m/s is forgotten
            # the link works: a new command goes through, and only that one
            wait_for(lambda: streamer.link_ok, 5)
            time.sleep(0.5)
            assert received.since(back) == [], len(received.since(back))
            drone.set_cmd_vel(vx=0.2)
            got = wait_for(lambda: received.since(back), 20, what="the new command")
            assert all(t.velocity.x == 0.2 for t in got)
    finally:
        drone.close()
        bridge.close()
