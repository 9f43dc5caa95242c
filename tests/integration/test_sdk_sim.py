"""The whole DroneWrapper API against the simulator and the real bridge (compose/sim_iris.yaml).

One graph per module (sim + bridge_mavlink on a free loopback router, free UDP ports); the tests
run in file order on the same aircraft: on the ground, one flight, then errors.
"""

from __future__ import annotations

import math
import time
from collections.abc import Iterator

import numpy as np
import pytest

from dronewrapper import CommandRefused, DroneWrapper, InvalidArgument, NoData, list_drones
from dronewrapper.msgs.mavros import LANDED_STATE_IN_AIR, LANDED_STATE_ON_GROUND

pytestmark = pytest.mark.integration


@pytest.fixture(scope="module")
def drone(sim_iris) -> Iterator[DroneWrapper]:
    with DroneWrapper("drone", sim_iris, timeout=30, land_on_exit=True) as wrapper:
        yield wrapper


def test_getters_on_the_ground(drone, sim_iris):
    assert list_drones(sim_iris) == ["drone"]
    state = drone.get_state()
    assert state.connected and state.autopilot == "px4" and not state.armed
    drone.wait_for_landed_state(LANDED_STATE_ON_GROUND, timeout=10)
    position = drone.get_position()
    assert isinstance(position, np.ndarray) and position.shape == (3,)
    assert np.all(np.abs(position) < 0.5), position  # the take-off point is the origin
    roll, pitch, yaw = drone.get_orientation()
    assert abs(roll) < 0.1 and abs(pitch) < 0.1 and -math.pi <= yaw <= math.pi
    assert drone.get_yaw() == pytest.approx(yaw, abs=0.05)
    assert np.all(np.abs(drone.get_velocity()) < 0.2)
    drone.wait_for(lambda: drone.get_battery() > 0, 10, "battery")
    assert 0.0 < drone.get_battery() <= 1.0
    lat, lon, _alt = drone.wait_for(drone.get_global_position, 10, "GPS fix")
    assert -90 <= lat <= 90 and -180 <= lon <= 180
    for camera in ("frontal", "ventral"):
        image = drone.wait_for_image(camera, timeout=30)
        assert image.dtype == np.uint8 and image.ndim == 3 and image.shape[2] == 3
        assert image.std() > 1.0  # a rendered scene, not a blank buffer
    _, stamp = drone.get_image("frontal", with_stamp=True)
    assert abs(time.time() - stamp) < 5.0


def test_bad_requests_are_refused_with_a_reason(drone):
    with pytest.raises(CommandRefused) as info:
        drone.set_mode("NOT_A_MODE")
    assert "NOT_A_MODE" in str(info.value)
    with pytest.raises(InvalidArgument):
        drone.set_cmd_vel(vx=float("nan"))
    assert drone.param_get("MIS_TAKEOFF_ALT") == pytest.approx(2.5)
    assert drone.param_set("MPC_XY_VEL_MAX", 5.0) == pytest.approx(5.0)
    assert drone.param_get("MPC_XY_VEL_MAX") == pytest.approx(5.0)


def test_flight(drone):
    t0 = time.monotonic()
    drone.takeoff(h=1.0, timeout=40)
    assert drone.get_position()[2] == pytest.approx(1.0, abs=0.2)
    assert drone.get_state().mode == "OFFBOARD" and drone.get_state().armed
    drone.wait_for_landed_state(LANDED_STATE_IN_AIR, timeout=10)
    t1 = time.monotonic()
    drone.takeoff(h=1.0)  # idempotent: already flying
    # at once: no command, no climb (a take-off takes seconds; 3 s covers a loaded machine)
    assert time.monotonic() - t1 < 3.0, "second takeoff should return at once"
    print(f"takeoff took {t1 - t0:.1f} s")

    # body velocity: vx is forward, whatever the heading
    start, yaw = drone.get_position(), drone.get_yaw()
    drone.set_cmd_vel(vx=1.0)

    def forward() -> float:
        moved = drone.get_position() - start
        return moved[0] * math.cos(yaw) + moved[1] * math.sin(yaw)

    drone.wait_for(lambda: forward() > 0.6, 10, "0.6 m forward")
    assert drone.get_velocity()[0] > 0.3

    # yaw rate: positive az turns counter-clockwise
    yaw0 = drone.get_yaw()
    drone.set_cmd_vel(az=1.0)
    drone.wait_for(lambda: drone.get_yaw_rate() > 0.5, 10, "yaw rate > 0.5 rad/s")

    def turned() -> float:
        return (drone.get_yaw() - yaw0 + math.pi) % (2 * math.pi) - math.pi

    drone.wait_for(lambda: turned() > 0.5, 10, "a counter-clockwise turn of 0.5 rad")

    # mixed: altitude hold at a commanded z
    drone.set_cmd_mix(z=1.6)
    drone.wait_for_altitude(1.6, timeout=15, tolerance=0.2)

    # position: back above the start point
    drone.set_cmd_pos(start[0], start[1], 1.0, 0.0)
    drone.wait_for(
        lambda: (
            np.linalg.norm(drone.get_position() - [start[0], start[1], 1.0]) < 0.3
            and abs(drone.get_yaw()) < 0.2
        ),
        30,
        "back at the start, facing yaw 0",
    )

    drone.land(timeout=40)
    assert drone.get_landed_state() == LANDED_STATE_ON_GROUND
    assert not drone.get_state().armed
    assert drone.get_position()[2] < 0.3
    assert drone.commanding is None


def test_compressed_images_and_no_camera(sim_iris):
    with DroneWrapper(
        "drone", sim_iris, timeout=30, cameras=("frontal",), compressed_images=True
    ) as drone:
        image = drone.wait_for_image("frontal", timeout=15)
        assert image.dtype == np.uint8 and image.ndim == 3 and image.shape[2] == 3
        with pytest.raises(NoData, match="was not requested"):
            drone.get_ventral_image()
