"""The paper's follow experiments, flown in the simulator and judged from its ground truth.

Every fixed scenario name: the colour graph on the beacon scenarios, the YOLOX graph on the
person scenarios (and HOG on the static person). Each flight checks that the target is acquired
within a bound, kept near the image centre (bearing from ground truth) and near the intended
distance for most of the run, and, in the crossing scenarios, that the drone still points at
the person named ``target`` (not at a passer-by) at the end.

The crossing scenarios fly as on a drone's busy computer: an unrelated process keeps one of the
cores busy and perception detects on at most 10 frames a second; the drone must still point at
the target (within 10 deg, from ground truth) 90 % of the time after acquiring it.
"""

from __future__ import annotations

import math

import pytest
from busy_core import one_core_busy
from scenario_flight import check_flight, crossed, fly, passes, record_result

pytestmark = [pytest.mark.scenario, pytest.mark.timeout(240)]

# scenario -> (graph, detector, seconds of servoing after the take-off, max acquire s, min
# centred, min within distance)
CASES = {
    "beacon_static": ("sim_follow_color", "color", 17, 15, 0.85, 0.85),
    "beacon_smooth": ("sim_follow_color", "color", 27, 15, 0.7, 0.7),
    "beacon_abrupt": ("sim_follow_color", "color", 27, 15, 0.5, 0.5),
    "person_static": ("sim_follow_person", "yolox", 20, 18, 0.8, 0.7),
    "person_moving": ("sim_follow_person", "yolox", 27, 18, 0.6, 0.5),
    "people_crossing_behind": ("sim_follow_person", "yolox", 27, 18, 0.9, 0.6),
    "people_crossing_front": ("sim_follow_person", "yolox", 27, 18, 0.9, 0.5),
}
CROSSING = ("people_crossing_behind", "people_crossing_front")
LOADED_DETECT_RATE_HZ = "10"  # crossing flights: perception capped, one core kept busy
CENTRED = math.radians(10.0)


@pytest.mark.parametrize("scenario", list(CASES))
def test_follow(scenario, tmp_path):
    graph, detector, seconds, max_acquire, min_centred, min_distance = CASES[scenario]
    variables = {"detector": detector} if graph == "sim_follow_person" else {}
    if scenario in CROSSING:
        variables["detect_rate_hz"] = LOADED_DETECT_RATE_HZ
        with one_core_busy():
            flight = fly(graph, scenario, seconds, tmp_path, variables)
    else:
        flight = fly(graph, scenario, seconds, tmp_path, variables)
    app = "follow_color" if graph == "sim_follow_color" else "follow_person"
    ok = passes(flight, max_acquire, min_centred, min_distance)
    record_result(flight, app, "sim", "dronewrapper_sim (ours)", ok)
    check_flight(flight, max_acquire, min_centred, min_distance)
    if scenario in CROSSING:
        crossings = sum(crossed(s) for s in flight.samples)
        assert crossings > 0, "no passer-by crossed the line of sight: the test proves nothing"
        # still on the same person at the end. The target stands still while passers-by walk
        # across at 0.6-1 m/s, so a drone that had switched to one would carry the target tens
        # of degrees off the axis. Over the last quarter the target must be centred most of the
        # time, be the object nearest the optical axis most of the time, and have a median
        # bearing error inside the centred tolerance. (On a loaded 2-core machine the drone may
        # turn a little while the target is hidden, and come back: that is identity kept.)
        tail = flight.samples[-int(len(flight.samples) * 0.25) :]
        centred = sum(s.centred(CENTRED) for s in tail) / len(tail)
        nearest = sum(s.closest_to_axis() == "target" for s in tail) / len(tail)
        median_bearing = sorted(abs(s.bearing) for s in tail)[len(tail) // 2]
        detail = (
            f"target centred {centred:.0%}, nearest the axis {nearest:.0%} of the last part, "
            f"median bearing {math.degrees(median_bearing):.1f} deg"
        )
        print(detail)
        assert centred >= 0.6 and nearest >= 0.5 and median_bearing <= CENTRED, (
            f"{detail}\n{flight.timeline()}"
        )


def test_follow_person_with_hog(tmp_path):
    """HOG works on the static person, though it is slow here (frames ~1 s old on this CPU), so
    the yaw loop swings more; its looser boxes put the intended distance farther away (~7.4 m
    against the 6 m start), and with about one detection a second the drone backs off slowly:
    a third of the flight within 1.5 m of that distance still fails a drone that drifts off."""
    flight = fly("sim_follow_person", "person_static", 25, tmp_path, {"detector": "hog"})
    check_flight(flight, 18, 0.5, 0.33)
