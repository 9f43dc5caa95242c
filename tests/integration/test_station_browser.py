"""The ground station in a real headless Chromium against the simulated Iris.

One flight, driven only through the page: it loads with no console errors, video frames
arrive and change, the ventral camera can be picked, a take-off click makes the true altitude
rise, a forward stick drag moves the drone forward (along its heading, in ground truth),
releasing the stick stops it, the W key does the same, a map click sends it east, the arrow
keys move the simulated beacon east, and a land click lands it. A screenshot of the page is
saved to ``out/station_e2e.png``.
"""

from __future__ import annotations

import math
import shutil
import time
from pathlib import Path

import pytest
from sdk_sim_graph import sim_graph
from selenium.webdriver.common.action_chains import ActionChains
from selenium.webdriver.common.by import By
from selenium.webdriver.common.keys import Keys

from dronewrapper.msgs import registry
from dronewrapper.telemetry import euler_from_quaternion
from dronewrapper_ground_station.browser import chromium, console_errors
from support import (
    REPO,
    client_node,
    station_process,
    station_serving,
    wait_for,
)

pytestmark = [pytest.mark.integration, pytest.mark.timeout(240)]

ARTIFACT = REPO / "out" / "station_e2e.png"


def _truth(latest):
    msg = latest.fresh(1.0)
    assert msg is not None, "no fresh ground truth"
    p = msg.pose.position
    return p.x, p.y, p.z, euler_from_quaternion(msg.pose.orientation)[2]


def _speed(latest, window: float = 0.5) -> float:
    x0, y0, z0, _ = _truth(latest)
    time.sleep(window)
    x1, y1, z1, _ = _truth(latest)
    return math.dist((x0, y0, z0), (x1, y1, z1)) / window


def _page(driver, script: str):
    return driver.execute_script(f"return {script}")


def _result(driver) -> str:
    return driver.find_element(By.ID, "result").text


def _moved_forward(truth, drive) -> tuple[float, float]:
    """(forward, sideways) metres, along the heading at the start, while ``drive()`` runs."""
    x0, y0, _, yaw = _truth(truth)
    drive()
    x1, y1, _, _ = _truth(truth)
    forward = (x1 - x0) * math.cos(yaw) + (y1 - y0) * math.sin(yaw)
    sideways = -(x1 - x0) * math.sin(yaw) + (y1 - y0) * math.cos(yaw)
    return forward, sideways


def _stops_and_holds(driver, truth) -> None:
    wait_for(lambda: _speed(truth) < 0.15, 10, interval=0, what="the drone to stop")
    assert _page(driver, "window.station.teleopActive") is False
    wait_for(
        lambda: (_page(driver, "window.station.drone.command") or {}).get("what") == "hold",
        3,
        what="the station holding",
    )
    xs, ys, _, _ = _truth(truth)
    time.sleep(1.0)
    assert math.dist((xs, ys), _truth(truth)[:2]) < 0.3, "drifts after release"


def test_fly_from_the_page(tmp_path: Path) -> None:
    with sim_graph(tmp_path, variables=["scenario=beacon_static"]) as (router, _):
        station, page = station_process(router, tmp_path)
        try:
            with (
                client_node(router, name="test_station") as node,
                chromium(tmp_path / "profile") as driver,
            ):
                truth = node.latest(registry.SIM_GROUND_TRUTH)
                beacon = node.latest(registry.SIM_OBJECT_POSE, name="target")
                wait_for(lambda: truth.fresh(1.0) and beacon.fresh(1.0), 20, what="the sim")
                station_serving(station)
                driver.get(page)

                # loads, finds the drone, shows video that changes; both cameras
                wait_for(lambda: _page(driver, "window.station.frames") >= 3, 30, what="frames")
                assert _page(driver, "window.station.role") == "operator"
                assert _page(driver, "window.station.ns") == "drone"
                seq0 = _page(driver, "window.station.lastFrame.seq")
                wait_for(
                    lambda: _page(driver, "window.station.lastFrame.seq") > seq0 + 5,
                    10,
                    what="new frames",
                )
                driver.find_element(By.ID, "cam-ventral").click()
                wait_for(
                    lambda: _page(driver, "window.station.lastFrame.camera") == "ventral",
                    10,
                    what="ventral frames",
                )
                driver.find_element(By.ID, "cam-frontal").click()
                wait_for(
                    lambda: _page(driver, "window.station.lastFrame.camera") == "frontal",
                    10,
                    what="frontal frames",
                )
                before = _page(driver, "document.getElementById('video').toDataURL()")

                # take-off click -> the true altitude rises
                z_ground = _truth(truth)[2]
                driver.find_element(By.ID, "btn-takeoff").click()
                wait_for(lambda: _truth(truth)[2] > z_ground + 2.0, 45, what="altitude rising")
                wait_for(lambda: "takeoff: done" in _result(driver), 30, what="take-off done")
                after = _page(driver, "document.getElementById('video').toDataURL()")
                assert after != before, "the video did not change while climbing"

                # a forward stick drag moves the drone forward along its heading
                stick = driver.find_element(By.ID, "stick-right")
                forward, sideways = _moved_forward(
                    truth,
                    lambda: (
                        ActionChains(driver, duration=50)
                        .move_to_element(stick)
                        .click_and_hold()
                        .move_by_offset(0, -60)
                        .pause(3.0)
                        .perform()
                    ),
                )
                assert forward > 1.0, f"stick forward moved {forward:.2f} m forward"
                assert abs(sideways) < 0.5 * forward, f"and {sideways:.2f} m sideways"
                # releasing it stops the drone (the station holds it where it is)
                ActionChains(driver).release().perform()
                _stops_and_holds(driver, truth)

                # the keyboard: W held is forward, released stops
                forward, _ = _moved_forward(
                    truth,
                    lambda: ActionChains(driver).key_down("w").pause(2.5).key_up("w").perform(),
                )
                assert forward > 0.7, f"W moved {forward:.2f} m forward"
                _stops_and_holds(driver, truth)

                # a map click 5 m east of the drone (12 px/m, the map follows the drone)
                x_before = _truth(truth)[0]
                the_map = driver.find_element(By.ID, "map")
                css_per_px = the_map.size["width"] / _page(
                    driver, "document.getElementById('map').width"
                )
                ActionChains(driver).move_to_element_with_offset(
                    the_map, round(60 * css_per_px), 0
                ).click().perform()
                wait_for(lambda: "goto: done" in _result(driver), 10, what="goto accepted")
                wait_for(
                    lambda: _truth(truth)[0] > x_before + 3.0, 30, what="flying east to the click"
                )

                # the arrow keys move the simulated beacon (east with ArrowRight)
                assert _page(driver, "document.getElementById('object-select').value") == "target"
                start = beacon.fresh(1.0).pose.position
                ActionChains(driver).key_down(Keys.ARROW_RIGHT).pause(2.0).key_up(
                    Keys.ARROW_RIGHT
                ).perform()
                moved = wait_for(
                    lambda: (b := beacon.fresh(1.0)) and b.pose.position.x - start.x > 0.8 and b,
                    5,
                    what="the beacon moving east",
                )
                assert abs(moved.pose.position.y - start.y) < 0.1, "ArrowRight is east only"

                # Reset puts the beacon back where the scenario starts it
                wait_for(
                    lambda: (
                        "running beacon_static"
                        in _page(driver, "document.getElementById('world-state').textContent")
                    ),
                    15,
                    what="the world shown",
                )
                driver.find_element(By.ID, "btn-world-reset").click()
                wait_for(
                    lambda: (b := beacon.fresh(1.0)) and abs(b.pose.position.x - start.x) < 0.1,
                    15,
                    what="the beacon reset to its start",
                )
                # picking another scenario loads its world (people appear)
                driver.execute_script(
                    "document.getElementById('scenario-select').value = 'people_crossing_front'"
                )
                driver.find_element(By.ID, "btn-world-load").click()
                try:
                    wait_for(
                        lambda: "world: people_crossing_front loaded" in _result(driver),
                        20,
                        what="the load reported",
                    )
                except AssertionError as exc:
                    raise AssertionError(f"{exc}; the page says {_result(driver)!r}") from None
                person = node.latest(registry.SIM_OBJECT_POSE, name="person1")
                wait_for(lambda: person.fresh(1.0), 15, what="a passer-by on the bus")

                # land click -> on the ground
                driver.find_element(By.ID, "btn-land").click()
                wait_for(
                    lambda: (
                        _page(driver, "window.station.drone.landed.landed_state") == "on_ground"
                        and _truth(truth)[2] < z_ground + 0.2
                    ),
                    60,
                    what="landing",
                )
                wait_for(lambda: "land: done" in _result(driver), 30, what="landed, disarmed")
                ARTIFACT.parent.mkdir(exist_ok=True)
                driver.save_screenshot(str(ARTIFACT))
                shutil.copy(ARTIFACT, tmp_path / ARTIFACT.name)
                assert console_errors(driver) == []
        finally:
            code = station.stop(15)
        assert code == 0, station.output()
