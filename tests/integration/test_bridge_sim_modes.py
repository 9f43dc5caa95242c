"""Mode changes end to end (issue 12, item 2): the SDK, the bridge process and the simulator
process, and a ground station on the simulator's GCS link over real UDP. The simulator's
refusal of a mode that needs RC (ACCEPTED, then TEMPORARILY_REJECTED with "Switching to
Position is currently not available") reaching the bridge's set_mode is held in virtual time
by tests/service/test_mavlink_flight_virtual.py, the SDK's CommandRefused for it by
tests/integration/test_bridge_mode_acks.py.
"""

from __future__ import annotations

import time

import pytest
from pymavlink import mavutil
from test_bridge_sim import rig  # noqa: F401  (the sim + bridge processes, free ports)

from dronewrapper import DroneWrapper
from support import wait_for

pytestmark = pytest.mark.integration

AUTO_LOITER, OFFBOARD = (4, 3), (6, 0)  # PX4 (main, sub)


def gcs_set_mode(gcs, main_sub: tuple[int, int]) -> None:
    """DO_SET_MODE from a ground station (retried until acked: UDP)."""
    for confirmation in range(5):
        gcs.mav.command_long_send(
            1, 1, mavutil.mavlink.MAV_CMD_DO_SET_MODE, confirmation, 1, *main_sub, 0, 0, 0, 0
        )
        if gcs.recv_match(type="COMMAND_ACK", blocking=True, timeout=2):
            return
    raise AssertionError(f"no ack for DO_SET_MODE {main_sub}")


def test_ground_station_hands_offboard_back_then_the_app_dies_bridge_lands(rig):  # noqa: F811
    """Before: the bridge stayed 'overridden' and PX4's own offboard-loss failsafe flew RTL."""
    gcs = mavutil.mavlink_connection(
        f"udpin:127.0.0.1:{rig.gcs_port}", source_system=254, source_component=190
    )
    try:
        assert gcs.recv_match(type="HEARTBEAT", blocking=True, timeout=10), "no GCS heartbeat"
        with DroneWrapper("drone", rig.router, timeout=30, cameras=()) as drone:
            drone.takeoff(h=1.5, timeout=40)
            x, y, _z = drone.get_position()
            drone.set_cmd_pos(x, y, 1.5, drone.get_yaw())  # the app hovers, streaming
            gcs_set_mode(gcs, AUTO_LOITER)
            wait_for(lambda: rig.state.value.mode == "AUTO.LOITER", 10, what="GCS AUTO.LOITER")
            wait_for(lambda: any("not switching back" in t.text for t in rig.texts), 10)
            gcs_set_mode(gcs, OFFBOARD)
            wait_for(lambda: rig.state.value.mode == "OFFBOARD", 10, what="OFFBOARD again")
            since = len(rig.states)
            drone.stop_commanding()  # the app dies
            died = time.monotonic()
            heights: list[float] = []

            def landing() -> bool:
                heights.append(rig.z())
                state = rig.state.value
                return state.failsafe == "land" and state.mode == "AUTO.LAND"

            wait_for(landing, 25, what="commander-lost land in AUTO.LAND")
            after = rig.states[since:]
            assert "hold" in [s.failsafe for s in after]  # held first, then landed
            assert all(s.mode != "AUTO.RTL" for s in after), [s.mode for s in after]
            assert 4.0 < time.monotonic() - died < 25.0
            rig.wait_landed_disarmed(60)
            assert max(heights) < 2.2, max(heights)  # RTL would have climbed
    finally:
        gcs.close()
