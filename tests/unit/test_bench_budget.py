"""The latency budget's arithmetic (bench/budget.py): stages of one frame, summaries, growth."""

from __future__ import annotations

import math
import sys

import pytest

from support import REPO

sys.path.insert(0, str(REPO))  # bench/ holds scripts at the repository root, not a package

from bench.budget import (
    MIDDLEWARE_KEYS,
    STAGE_KEYS,
    FrameTimes,
    budget_rows,
    growth,
    stages,
    summarise,
)

MS = 1e-3


def frame(t0: float = 1000.0, **changes: float) -> FrameTimes:
    """A frame: render 4 + publish 0.5 + transport 0.3, queue 1, decode 0.1, compute 17,
    Detections 0.4, controller 0.6, bridge 0.5 (ms)."""
    times = {
        "stamp": t0,
        "image_arrival": t0 + 4.8 * MS,
        "queue": 1.0 * MS,
        "decode": 0.1 * MS,
        "processing": 17.1 * MS,
        "detections_arrival": t0 + (4.8 + 1.0 + 17.1 + 0.4) * MS,
        "setpoint_arrival": t0 + (4.8 + 1.0 + 17.1 + 0.4 + 0.6) * MS,
        "mavlink_out": t0 + (4.8 + 1.0 + 17.1 + 0.4 + 0.6 + 0.5) * MS,
    }
    times.update(changes)
    return FrameTimes(**times)


def test_one_frame_splits_into_its_stages():
    got = stages(frame(), render_s=4.0 * MS, publish_s=0.5 * MS)
    want_ms = {"render": 4.0, "publish_image": 0.5, "transport_image": 0.3, "queue": 1.0,
               "decode": 0.1, "compute": 17.0, "publish_detections": 0.4, "controller": 0.6,
               "bridge": 0.5}  # fmt: skip
    for key, value in want_ms.items():
        assert got[key] == pytest.approx(value * MS, abs=1e-9), key
    assert got["total"] == pytest.approx(sum(want_ms.values()) * MS)
    assert got["middleware"] == pytest.approx(
        sum(want_ms[k] for k in MIDDLEWARE_KEYS) * MS, abs=1e-9
    )
    assert set(MIDDLEWARE_KEYS) == set(STAGE_KEYS) - {"render", "compute"}


def test_missing_fields_stay_missing_and_total_ends_at_the_setpoint():
    old = frame(queue=math.nan, decode=math.nan, mavlink_out=math.nan)  # an older perception
    got = stages(old, render_s=4.0 * MS, publish_s=0.5 * MS)
    assert math.isnan(got["queue"]) and math.isnan(got["bridge"])
    assert got["compute"] == pytest.approx(17.1 * MS)  # decode not reported: counted in compute
    assert got["publish_detections"] == pytest.approx(1.4 * MS)  # the queue wait lands here
    assert got["total"] == pytest.approx((4.8 + 1.0 + 17.1 + 0.4 + 0.6) * MS)


def test_summary_percentiles_skip_nans_and_rows_name_every_stage():
    frames = [stages(frame(t0=1000.0 + k), 4.0 * MS, 0.5 * MS) for k in range(100)]
    frames.append({**frames[0], "bridge": math.nan})
    summary = summarise(frames)
    assert summary["compute"]["n"] == 101
    assert summary["bridge"]["n"] == 100
    assert summary["compute"]["p50_ms"] == pytest.approx(17.0)
    rows = budget_rows(summary)
    assert len(rows) == len(STAGE_KEYS) + 2
    assert rows[0][1] == "no" and rows[1][1] == "yes"  # render is not middleware, publish is
    assert rows[-1][2] == pytest.approx(summary["middleware"]["p50_ms"])
    assert summarise([])["total"]["n"] == 0


def test_growth_compares_first_and_last_window():
    times = [float(t) for t in range(600)]  # 10 minutes, one value a second
    values = [0.010 + 0.001 * (t >= 540) for t in range(600)]  # +1 ms in the last minute
    g = growth(times, values, window_s=60.0)
    assert g.first_p50_ms == pytest.approx(10.0)
    assert g.last_p50_ms == pytest.approx(11.0)
    assert g.p50_change_ms == pytest.approx(1.0)
    assert g.first_n == 61 and g.last_n == 61
    flat = growth(times, [0.005] * 600)
    assert flat.p50_change_ms == pytest.approx(0.0)
    assert growth([], []).first_n == 0
    with pytest.raises(ValueError):
        growth([1.0], [])


def test_the_mavlink_relay_reads_setpoints_from_real_datagrams():
    import math as m

    from pymavlink.dialects.v20 import common as mavlink2

    from bench.latency_budget import parse_setpoint, setpoint_key

    link = mavlink2.MAVLink(None, srcSystem=1, srcComponent=191)
    # body vx 1.2 m/s at a 30 degree heading -> local north/east; up 0.3; yaw rate 0.4 CCW
    north, east = 1.2 * m.cos(m.radians(30)), 1.2 * m.sin(m.radians(30))
    msg = mavlink2.MAVLink_set_position_target_local_ned_message(
        1234, 1, 1, 1, 3527, 0, 0, 0, north, east, -0.3, 0, 0, 0, 0, -0.4
    )
    datagram = msg.pack(link)
    assert parse_setpoint(datagram) == pytest.approx(setpoint_key(1.2, 0.0, 0.3, 0.4), abs=1e-6)
    heartbeat = mavlink2.MAVLink_heartbeat_message(6, 8, 0, 0, 0, 3).pack(link)
    assert parse_setpoint(heartbeat) is None
    assert parse_setpoint(b"\x00\x01") is None
