"""The ground station in a real headless Chromium against the simulated Iris.

One flight, driven only through the page: it loads with no console errors, video frames
arrive and change, a take-off click makes the true altitude rise, a forward stick drag moves
the drone forward (along its heading, in ground truth), releasing the stick stops it, and a
land click lands it. A screenshot of the page is saved to ``out/station_e2e.png``.
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

from dronewrapper.msgs import registry
from dronewrapper.telemetry import euler_from_quaternion
from dronewrapper_ground_station.browser import chromium, console_errors
from support import REPO, Process, client_node, free_port, python_module, wait_for

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


def test_fly_from_the_page(tmp_path: Path) -> None:
    sim_dir = tmp_path / "sim"
    sim_dir.mkdir()
    with sim_graph(sim_dir) as (router, _graph):
        port = free_port()
        station = Process(
            python_module("dronewrapper_ground_station", "--connect", router, "--port", str(port)),
            tmp_path / "station.log",
        )
        try:
            with (
                client_node(router, name="test_station") as node,
                chromium(tmp_path / "profile") as driver,
            ):
                truth = node.latest(registry.SIM_GROUND_TRUTH)
                wait_for(lambda: truth.fresh(1.0), 20, what="ground truth")
                url = wait_for(
                    lambda: (
                        f"http://127.0.0.1:{port}/" if "station: open" in station.output() else None
                    ),
                    30,
                    what=f"the station to serve:\n{station.output()}",
                )
                driver.get(url)

                # loads, finds the drone, shows video that changes
                wait_for(lambda: _page(driver, "window.station.frames") >= 3, 30, what="frames")
                assert _page(driver, "window.station.role") == "operator"
                assert _page(driver, "window.station.ns") == "drone"
                seq0 = _page(driver, "window.station.lastFrame.seq")
                before = _page(driver, "document.getElementById('video').toDataURL()")
                wait_for(
                    lambda: _page(driver, "window.station.lastFrame.seq") > seq0 + 5,
                    10,
                    what="new frames",
                )

                # take-off click -> the true altitude rises
                z_ground = _truth(truth)[2]
                driver.find_element(By.ID, "btn-takeoff").click()
                wait_for(lambda: _truth(truth)[2] > z_ground + 2.0, 45, what="altitude rising")
                wait_for(
                    lambda: "done" in driver.find_element(By.ID, "result").text,
                    30,
                    what="take-off reported done",
                )
                after = _page(driver, "document.getElementById('video').toDataURL()")
                assert after != before, "the video did not change while climbing"

                # a forward stick drag moves the drone forward along its heading
                x0, y0, _, yaw = _truth(truth)
                stick = driver.find_element(By.ID, "stick-right")
                actions = ActionChains(driver, duration=50)
                actions.move_to_element(stick).click_and_hold().move_by_offset(0, -60)
                actions.pause(3.0).perform()
                x1, y1, _, _ = _truth(truth)
                forward = (x1 - x0) * math.cos(yaw) + (y1 - y0) * math.sin(yaw)
                sideways = -(x1 - x0) * math.sin(yaw) + (y1 - y0) * math.cos(yaw)
                assert forward > 1.0, f"stick forward moved {forward:.2f} m forward"
                assert abs(sideways) < 0.5 * forward, f"and {sideways:.2f} m sideways"

                # releasing it stops the drone (the station holds it where it is)
                ActionChains(driver).release().perform()
                wait_for(lambda: _speed(truth) < 0.15, 10, interval=0, what="the drone to stop")
                assert _page(driver, "window.station.teleopActive") is False
                wait_for(
                    lambda: (
                        (_page(driver, "window.station.drone.command") or {}).get("what") == "hold"
                    ),
                    3,
                    what="station holding",
                )
                xs, ys, _, _ = _truth(truth)
                time.sleep(1.5)
                assert math.dist((xs, ys), _truth(truth)[:2]) < 0.3, "drifts after release"

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
                wait_for(
                    lambda: "land: done" in driver.find_element(By.ID, "result").text,
                    30,
                    what="landing reported done (disarmed)",
                )
                ARTIFACT.parent.mkdir(exist_ok=True)
                driver.save_screenshot(str(ARTIFACT))
                shutil.copy(ARTIFACT, tmp_path / ARTIFACT.name)
                assert console_errors(driver) == []
        finally:
            code = station.stop(15)
        assert code == 0, station.output()
