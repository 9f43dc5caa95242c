"""The ground station shows what the bridge refused of its commands beside its buttons, in a
real headless Chromium against the simulated Iris with the command lease on
(compose/sim_iris.yaml, ``command_lease=true``): another commander holds the lease, the W key's
teleop is refused by the bridge, and the page lists the refusal under the command buttons
naming the holder, and logs it."""

from __future__ import annotations

import time
from pathlib import Path

import pytest
from sdk_sim_graph import sim_graph
from selenium.webdriver.common.action_chains import ActionChains
from selenium.webdriver.common.by import By

from dronewrapper import DroneWrapper
from dronewrapper_ground_station.browser import chromium, console_errors
from support import station_process, station_serving, wait_for

pytestmark = [pytest.mark.integration, pytest.mark.timeout(240)]


def _page(driver, script: str):
    return driver.execute_script(f"return {script}")


def test_a_refused_teleop_is_listed_under_the_buttons(tmp_path: Path) -> None:
    with sim_graph(tmp_path, variables=["command_lease=true"]) as (router, _):
        station, page = station_process(router, tmp_path)
        try:
            with (
                DroneWrapper("drone", router, timeout=30, commander="ada") as ada,
                chromium(tmp_path / "profile") as driver,
            ):
                station_serving(station)
                driver.get(page)
                wait_for(lambda: _page(driver, "window.station.ns") == "drone", 30, what="drone")
                assert _page(driver, "window.station.role") == "operator"
                assert driver.find_element(By.ID, "refusals").text == ""
                ada.take_command()  # the lease is ada's: the station's setpoints are refused
                ActionChains(driver).key_down("w").pause(1.0).key_up("w").perform()
                wait_for(
                    lambda: (
                        "holds the command lease" in driver.find_element(By.ID, "refusals").text
                    ),
                    15,
                    what="the refusal under the buttons",
                )
                shown = driver.find_element(By.ID, "refusals").text
                assert "setpoint refused (lease, command_lease)" in shown and "'ada'" in shown
                logged = driver.find_element(By.ID, "log").text
                assert "setpoint refused (lease, command_lease)" in logged
                time.sleep(0.5)  # the page's next telemetry tick: still no error in the console
                assert console_errors(driver) == []
        finally:
            code = station.stop(15)
        assert code == 0, station.output()
