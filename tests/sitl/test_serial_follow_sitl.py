"""Opt-in: the follow-colour app on real firmware at the far end of a paced serial line.

The autopilot's follow graph (compose/{px4,ardupilot}_sitl_follow_color.yaml: our world posed
from the firmware's own simulation, its camera, perception, the controller) flies the red beacon
(``beacon_smooth``) and is judged as in test_follow_sitl.py, with the scenario tier's
thresholds; only the bridge's link differs: a pseudo-terminal paced at 57600, 115200 or 921600
baud (serial_taps.paced_relay), whose far end the firmware opens as its serial port
(dronewrapper_sim.external.firmware with ``serial``: PX4's MAVLink instance in onboard mode,
ArduCopter's SERIAL0). ``PX4_SITL_DIR`` / ``AP_SITL_DIR`` turn the flights on
(tests/sitl/conftest.py).

Each flight also measures **glass-to-setpoint at the autopilot**: from a camera frame's capture
stamp (carried by perception's Detections and the controller's setpoint) to the last byte of
the SET_POSITION_TARGET_LOCAL_NED it became crossing the line into the autopilot, joined by the
setpoint's values (bench.budget.setpoint_paths), and the line's load while following (the
bridge's LinkStatus). It prints them as one JSON line, ``SERIAL_FOLLOW {...}`` (``pytest -s``;
docs/serial.md records them).
"""

from __future__ import annotations

import json
import math
import os
import sys

import firmware
import numpy as np
import pytest
from scenario_flight import fly
from serial_taps import paced_relay
from test_follow_scenarios import CASES
from test_follow_sitl import START_TIMEOUT_S, judge

from dronewrapper.msgs import codec, registry
from support import REPO

sys.path.insert(0, str(REPO))  # bench/ holds scripts at the repository root, not a package

from bench.budget import setpoint_paths
from bench.latency_budget import Probe, parse_setpoint

pytestmark = [pytest.mark.timeout(420)]

BAUDS = (57600, 115200, 921600)
SCENARIO = "beacon_smooth"
MATCH_WINDOW_S = 0.5  # s from a setpoint's send to its frame at the autopilot, at the most
MIN_JOINED = 0.8  # share of the frames' setpoints found at the autopilot (else the tap is wrong)


class SerialWatch:
    """Beside the graph: the setpoints with their frames' stamps (bench.latency_budget.Probe)
    and the bridge's LinkStatus."""

    def __init__(self) -> None:
        self.probe: Probe | None = None
        self.links: list = []
        self._sub = None

    def open(self, session, ns: str) -> SerialWatch:
        self.probe = Probe(session, ns)
        decoder = codec.decoder(registry.LINK_STATUS.type)
        self._sub = session.declare_subscriber(
            registry.LINK_STATUS.key(ns),
            lambda sample: self.links.append(decoder.decode(sample.payload.to_bytes())),
        )
        return self

    def close(self) -> None:
        if self.probe is not None:
            self.probe.close()
        if self._sub is not None:
            self._sub.undeclare()

    def frame_setpoints(self) -> dict[float, tuple[float, float, tuple[float, float, float]]]:
        """Frame stamp -> (arrival at the probe, sent, key) of each setpoint that answered a
        camera frame (its stamp is a Detections' stamp)."""
        assert self.probe is not None
        with self.probe.lock:
            return {
                stamp: value
                for stamp, value in self.probe.setpoints.items()
                if stamp in self.probe.detections
            }


def quantiles_ms(values) -> dict:
    finite = [v for v in values if math.isfinite(v)]
    if not finite:
        return {"n": 0}
    p50, p90, p99 = np.percentile(np.asarray(finite) * 1e3, [50, 90, 99])
    return {"n": len(finite), "p50": round(p50, 1), "p90": round(p90, 1), "p99": round(p99, 1)}


def figures(watch: SerialWatch, relay) -> dict:
    """Glass-to-setpoint at the autopilot and the line while the controller followed."""
    answered = watch.frame_setpoints()
    crossed = [(t, key) for t, frame in relay.up.setpoints if (key := parse_setpoint(frame))]
    paths = setpoint_paths(
        {stamp: (sent, key) for stamp, (_, sent, key) in answered.items()},
        crossed,
        MATCH_WINDOW_S,
    )
    joined = [p for p in paths if math.isfinite(p.out)]
    first, last = (paths[0].stamp, paths[-1].stamp) if paths else (0.0, 0.0)
    following = [x for x in watch.links if first <= x.header.stamp <= last]
    median = lambda name: round(float(np.median([getattr(x, name) for x in following])), 3)  # noqa: E731
    span = max(last - first, 1e-9)
    return {
        "frames_commanded": len(paths),
        "frames_commanded_hz": round(len(paths) / span, 1),
        "setpoints_crossed_hz": round(sum(first <= t <= last for t, _ in crossed) / span, 1),
        "joined": len(joined),
        "glass_to_autopilot_ms": quantiles_ms([p.glass_to_out for p in joined]),
        "sent_to_autopilot_ms": quantiles_ms([p.sent_to_out for p in joined]),
        "glass_to_subscriber_ms": quantiles_ms([a - s for s, (a, _, _) in answered.items()]),
        "line": {
            "load": median("load") if following else None,
            "load_max": round(max(x.load for x in following), 3) if following else None,
            "down_kBps": median("received_rate") / 1000 if following else None,
            "up_kBps": median("sent_rate") / 1000 if following else None,
            "stream_scale": watch.links[-1].stream_scale if watch.links else None,
            "lost": watch.links[-1].lost if watch.links else None,
        },
        "dropped_toward_bridge": relay.down.dropped_frames,
        "unread_bytes_toward_bridge": relay.unwritten,  # before the bridge opened its device
        "dropped_toward_autopilot": relay.up.dropped_frames,
    }


@pytest.mark.parametrize("autopilot", firmware.AUTOPILOTS)
@pytest.mark.parametrize("baud", BAUDS)
def test_follow_over_a_serial_line(autopilot, baud, tmp_path):
    seconds = CASES[SCENARIO][2]
    watch = SerialWatch()
    with paced_relay(baud) as relay:
        bridge_on_the_line = {"bridge_mavlink": {"connection": relay.path, "baud": str(baud)}}
        with firmware.start(autopilot, tmp_path, serial=(relay.autopilot_path, baud)) as fw:
            flight = fly(
                f"{autopilot}_sitl_follow_color",
                SCENARIO,
                seconds,
                tmp_path,
                dict(fw.variables),
                START_TIMEOUT_S[autopilot],
                settings=bridge_on_the_line,
                watch=watch.open,
            )
        report = {
            "autopilot": autopilot,
            "firmware": fw.version,
            "baud": baud,
            "load_average": [round(x, 1) for x in os.getloadavg()],
            "follow": flight.describe(),
            "pose_age": next((x for x in reversed(flight.log.splitlines()) if "pose age" in x), ""),
            **figures(watch, relay),
        }
    print(f"\nSERIAL_FOLLOW {json.dumps(report)}")
    judge(flight, SCENARIO)
    assert report["joined"] >= MIN_JOINED * report["frames_commanded"] > 0, report
    assert report["line"]["load_max"] < 1.0, report  # the bridge's stream requests fit the line
    assert report["dropped_toward_autopilot"] == 0, report
