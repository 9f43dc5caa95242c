"""The latency budget's arithmetic (bench/budget.py): stages of one frame, summaries, growth."""

from __future__ import annotations

import math
import sys

import pytest

from support import REPO

sys.path.insert(0, str(REPO))  # bench/ holds scripts at the repository root, not a package

from bench.budget import (
    MATCH_WINDOW_S,
    MEASURED_KEYS,
    MIDDLEWARE_KEYS,
    STAGE_KEYS,
    FrameTimes,
    OutOfOrder,
    budget_rows,
    first_datagram,
    growth,
    split_all,
    stages,
    summarise,
)

MS = 1e-3


def frame(t0: float = 1000.0, **changes: float) -> FrameTimes:
    """A frame: render 4 + publish 0.5 + transport 0.3, queue 1, decode 0.1, compute 17,
    Detections -> setpoint sent 1.0, sent -> MAVLink out 0.5 (ms); the probe sees the
    Detections 0.4 ms after they were published and the setpoint 0.8 ms after its send."""
    published = 4.8 + 1.0 + 17.1
    times = {
        "stamp": t0,
        "image_arrival": t0 + 4.8 * MS,
        "queue": 1.0 * MS,
        "decode": 0.1 * MS,
        "processing": 17.1 * MS,
        "detections_arrival": t0 + (published + 0.4) * MS,
        "setpoint_sent": t0 + (published + 1.0) * MS,
        "setpoint_arrival": t0 + (published + 1.0 + 0.8) * MS,
        "mavlink_out": t0 + (published + 1.0 + 0.5) * MS,
    }
    times.update(changes)
    return FrameTimes(**times)


def test_one_frame_splits_into_its_stages():
    got = stages(frame(), render_s=4.0 * MS, publish_s=0.5 * MS)
    want_ms = {"render": 4.0, "publish_image": 0.5, "transport_image": 0.3, "queue": 1.0,
               "decode": 0.1, "compute": 17.0, "controller": 1.0, "bridge": 0.5}  # fmt: skip
    for key, value in want_ms.items():
        assert got[key] == pytest.approx(value * MS, abs=1e-9), key
    assert got["total"] == pytest.approx(sum(want_ms.values()) * MS)
    assert got["middleware"] == pytest.approx(
        sum(want_ms[k] for k in MIDDLEWARE_KEYS) * MS, abs=1e-9
    )
    assert got["detections_to_subscriber"] == pytest.approx(0.4 * MS)  # a reference figure
    assert set(MIDDLEWARE_KEYS) == set(STAGE_KEYS) - {"render", "compute"}


def test_a_probe_that_sees_the_setpoint_after_the_datagram_makes_no_stage_negative():
    # the probe, another process, sees the setpoint 2 ms late: after the bridge's datagram
    late = frame(setpoint_arrival=1000.0 + 30.0 * MS)
    assert late.setpoint_arrival > late.mavlink_out
    got = stages(late, render_s=4.0 * MS, publish_s=0.5 * MS)
    assert got == stages(frame(), render_s=4.0 * MS, publish_s=0.5 * MS)
    assert all(got[key] >= 0.0 for key in MEASURED_KEYS)
    assert got["bridge"] == pytest.approx(0.5 * MS)


def test_stages_between_path_instants_are_never_negative():
    # every measured stage ends at a path instant after the one it starts from
    for sent_ms, out_ms in [(0.0, 0.0), (0.01, 0.02), (5.0, 90.0)]:
        published = 1000.0 + (4.8 + 1.0 + 17.1) * MS
        f = frame(setpoint_sent=published + sent_ms * MS,
                  mavlink_out=published + (sent_ms + out_ms) * MS)  # fmt: skip
        got = stages(f, render_s=4.0 * MS, publish_s=0.5 * MS)
        assert all(got[key] >= 0.0 for key in MEASURED_KEYS), got


@pytest.mark.parametrize(
    ("changes", "named"),
    [
        ({"mavlink_out": 1000.0 + 23.0 * MS}, "MAVLink out"),  # before the setpoint was sent
        ({"setpoint_sent": 1000.0 + 22.0 * MS}, "setpoint sent"),  # before Detections
        ({"image_arrival": 999.0}, "arrival at perception"),  # before the stamp
    ],
)
def test_a_frame_out_of_path_order_is_refused_not_counted(changes, named):
    with pytest.raises(OutOfOrder, match=named):
        stages(frame(**changes), render_s=4.0 * MS, publish_s=0.5 * MS)


def test_a_run_keeps_the_frames_in_order_and_names_those_left_out():
    bad = frame(t0=2000.0, mavlink_out=2000.0 + 23.0 * MS)
    per_frame, kept, left_out = split_all([frame(), bad, frame(t0=3000.0)], 4.0 * MS, 0.5 * MS)
    assert [f.stamp for f in kept] == [1000.0, 3000.0] and len(per_frame) == 2
    assert len(left_out) == 1 and "MAVLink out" in left_out[0]


def test_missing_fields_stay_missing_and_total_ends_at_the_last_instant_seen():
    old = frame(queue=math.nan, decode=math.nan, mavlink_out=math.nan)  # an older perception
    got = stages(old, render_s=4.0 * MS, publish_s=0.5 * MS)
    assert math.isnan(got["queue"]) and math.isnan(got["bridge"])
    assert got["compute"] == pytest.approx(17.1 * MS)  # decode not reported: counted in compute
    assert got["controller"] == pytest.approx(2.0 * MS)  # the queue wait lands here
    assert got["total"] == pytest.approx((4.8 + 1.0 + 17.1 + 1.0) * MS)  # ends at the send
    unsent = stages(frame(setpoint_sent=math.nan, mavlink_out=math.nan), 4.0 * MS, 0.5 * MS)
    assert math.isnan(unsent["controller"]) and math.isnan(unsent["bridge"])
    assert unsent["total"] == pytest.approx((4.8 + 1.0 + 17.1) * MS)


def test_a_setpoints_datagram_is_never_one_that_left_before_the_send():
    key = (1.2, 0.3, 0.4)
    other = (0.5, 0.0, 0.0)
    sent = 50.0
    datagrams = [(sent - 0.001, key), (sent + 0.0002, other), (sent + 0.0005, key),
                 (sent + 0.0006, key)]  # fmt: skip
    used: set[int] = set()
    assert first_datagram(sent, key, datagrams, used) == sent + 0.0005
    assert first_datagram(sent, key, datagrams, used) == sent + 0.0006  # each used once
    assert math.isnan(first_datagram(sent, key, datagrams, used))
    assert math.isnan(first_datagram(sent, key, [(sent - 1e-6, key)], set()))
    late = [(sent + MATCH_WINDOW_S + 0.001, key)]
    assert math.isnan(first_datagram(sent, key, late, set()))
    assert math.isnan(first_datagram(math.nan, key, datagrams, set()))  # no send time known


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


def test_each_setpoint_is_joined_to_the_first_frame_with_its_values_after_its_send():
    from bench.budget import setpoint_paths

    slow, turn = (1.0, 0.0, 0.2), (0.0, 0.0, 0.5)
    setpoints = {  # frame stamp -> (sent, key)
        10.000: (10.020, slow),
        10.033: (10.050, slow),  # the same values again: the next frame, not the first
        10.066: (10.080, turn),
        10.100: (math.nan, turn),  # sent time unknown: never joined
    }
    frames = [(10.045, slow), (10.060, slow), (10.030, slow), (10.500, turn)]  # unsorted
    paths = setpoint_paths(setpoints, frames, window_s=0.1)
    assert [p.stamp for p in paths] == [10.000, 10.033, 10.066, 10.100]
    assert paths[0].out == pytest.approx(10.030)
    assert paths[0].glass_to_out == pytest.approx(0.030)
    assert paths[0].sent_to_out == pytest.approx(0.010)
    assert paths[1].out == pytest.approx(10.060)  # 10.045 was before its send
    assert math.isnan(paths[2].out)  # its frame came 0.42 s after the send: outside the window
    assert math.isnan(paths[3].out)
    assert setpoint_paths(setpoints, frames, window_s=0.5)[2].out == pytest.approx(10.500)
