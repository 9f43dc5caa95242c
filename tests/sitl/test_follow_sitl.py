"""The paper's follow experiments flown by real firmware in our world, judged from ground truth.

Opt-in: PX4 flights run when ``PX4_SITL_DIR`` names a PX4 SITL build, ArduCopter flights when
``AP_SITL_DIR`` names an ArduCopter SITL build (started by dronewrapper_sim.external.firmware);
otherwise they are deselected and the run says why. Each flight starts the firmware (a free
instance), runs the autopilot's follow graph
(compose/{px4,ardupilot}_sitl_follow_{color,person}.yaml: the world posed from the firmware's
own simulation, perception, the controller with its config for that firmware) and judges it with
the scenario tier's thresholds (tests/scenario/ test_follow_scenarios.py: acquisition, centred
share, distance share; the crossing: pointing at the target 90 % of the time after acquiring it,
on a loaded machine). Each flight's figures are written to ``$DRONEWRAPPER_CAPABILITIES`` (a
JSON-lines file) when it is set, for docs/capabilities.md.
"""

from __future__ import annotations

import contextlib

import firmware
import pytest
from busy_core import one_core_busy
from scenario_flight import check_flight, fly, record_result
from test_follow_scenarios import CASES, CROSSING, LOADED_DETECT_RATE_HZ, crossed, passes

pytestmark = [pytest.mark.timeout(420)]

SCENARIOS = ("beacon_smooth", "beacon_abrupt", "person_moving", "people_crossing_front")
START_TIMEOUT_S = {"px4": 90.0, "ardupilot": 150.0}  # graph up -> servoing (GPS fix, take-off)


def judge(flight, scenario: str) -> None:
    """The scenario tier's thresholds for ``scenario`` (test_follow_scenarios.CASES)."""
    _graph, _detector, _seconds, max_acquire, min_centred, min_distance = CASES[scenario]
    check_flight(flight, max_acquire, min_centred, min_distance)


@pytest.mark.parametrize("autopilot", firmware.AUTOPILOTS)
@pytest.mark.parametrize("scenario", SCENARIOS)
def test_follow_on_real_firmware(autopilot, scenario, tmp_path):
    sim_graph, detector, seconds, max_acquire, min_centred, min_distance = CASES[scenario]
    app = "color" if sim_graph == "sim_follow_color" else "person"
    graph = f"{autopilot}_sitl_follow_{app}"
    with firmware.start(autopilot, tmp_path) as fw:
        variables = dict(fw.variables)
        if app == "person":
            variables["detector"] = detector
        loaded = one_core_busy() if scenario in CROSSING else contextlib.nullcontext()
        if scenario in CROSSING:
            variables["detect_rate_hz"] = LOADED_DETECT_RATE_HZ
        with loaded:
            flight = fly(graph, scenario, seconds, tmp_path, variables, START_TIMEOUT_S[autopilot])
    print(f"{fw.version}: {flight.describe()}")
    ages = [line for line in flight.log.splitlines() if "pose age" in line]
    print(ages[-1] if ages else "no pose-age report in the log")
    passed = passes(flight, max_acquire, min_centred, min_distance)
    crossings = sum(crossed(x) for x in flight.samples) if scenario in CROSSING else None
    record_result(flight, f"follow_{app}", autopilot, fw.version, passed)
    judge(flight, scenario)
    if scenario in CROSSING:
        assert crossings > 0, "no passer-by crossed the line of sight: the test proves nothing"
