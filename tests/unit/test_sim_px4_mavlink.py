"""The simulated PX4 autopilot over MAVLink bytes (packed by a client, parsed by the
vehicle): command acks, status texts, parameters, message intervals and stream rates,
non-finite setpoints, take-off, landing and RTL timings, and a seeded flight's repeatability."""

from __future__ import annotations

import math

import pytest
from pymavlink.dialects.v20 import common as mavlink

from dronewrapper_sim.dynamics import QuadParams, QuadState
from dronewrapper_sim.px4 import params, telemetry
from dronewrapper_sim.px4.autopilot import Autopilot, AutopilotConfig
from dronewrapper_sim.px4.commander import ARM_DENIED, LandedState
from dronewrapper_sim.px4.modes import Mode

DT = 1.0 / 250.0
ACK_ACCEPTED = mavlink.MAV_RESULT_ACCEPTED


# ---- the autopilot over MAVLink bytes ----


class Client:
    """Packs messages like a real client (sysid 255) and hands the parsed bytes to the
    vehicle; collects the replies."""

    def __init__(self, ap: Autopilot, link: str = "onboard", sysid: int = 255) -> None:
        self.ap = ap
        self.link = link
        self.out = mavlink.MAVLink(None, srcSystem=sysid, srcComponent=190)
        self.parser = mavlink.MAVLink(None)

    def send(self, msg) -> list:
        parsed = self.parser.parse_buffer(msg.pack(self.out))
        assert parsed and len(parsed) == 1
        return self.ap.handle(self.link, parsed[0])

    def command(self, command: int, *p: float, target: int = 1) -> list:
        p7 = [*p, *[0.0] * (7 - len(p))]
        return self.send(mavlink.MAVLink_command_long_message(target, 1, command, 0, *p7))

    def setpoint(self, vx=0.0, vy=0.0, vz=0.0, yaw_rate=0.0, frame=8, mask=1991, target=1):
        return self.send(
            mavlink.MAVLink_set_position_target_local_ned_message(
                0, target, 1, frame, mask, 0, 0, 0, vx, vy, vz, 0, 0, 0, 0, yaw_rate
            )
        )

    def heartbeat(self, mav_type: int) -> list:
        return self.send(mavlink.MAVLink_heartbeat_message(mav_type, 8, 0, 0, 4, 3))


def acks(replies: list) -> list[tuple[int, int]]:
    return [(m.command, m.result) for m in replies if m.get_type() == "COMMAND_ACK"]


def texts_of(msgs: list) -> list[str]:
    """STATUSTEXT messages reassembled (chunks share a non-zero id), in order."""
    out: list[str] = []
    by_id: dict[int, int] = {}
    for m in msgs:
        if m.get_type() != "STATUSTEXT":
            continue
        if m.id and m.id in by_id:
            out[by_id[m.id]] += m.text
            continue
        if m.id:
            by_id[m.id] = len(out)
        out.append(m.text)
    return out


def run(ap: Autopilot, seconds: float) -> list:
    out = []
    for _ in range(round(seconds / DT)):
        ap.step(DT)
        for msgs in ap.poll().values():
            out.extend(msgs)
    return out


def test_do_set_mode_is_acked_twice_other_commands_once():
    ap = Autopilot()
    client = Client(ap)
    assert acks(client.command(176, 1, 6, 0)) == [(176, ACK_ACCEPTED)] * 2
    assert ap.mode is Mode.OFFBOARD
    assert acks(client.command(176, 1, 4, 3)) == [(176, ACK_ACCEPTED)] * 2
    assert acks(client.command(400, 1)) == [(400, ACK_ACCEPTED)]
    assert ap.armed


def test_refused_mode_is_acked_accepted_then_rejected_with_the_reason():
    """PX4's receiver acks DO_SET_MODE at once; the commander's refusal is the second ack."""
    ap = Autopilot()
    client = Client(ap, "gcs")
    client.heartbeat(mavlink.MAV_TYPE_GCS)
    assert acks(client.command(400, 1)) == [(400, ACK_ACCEPTED)]  # armed in AUTO.LOITER
    for main, name in ((3, "Position"), (2, "Altitude")):  # POSCTL, ALTCTL: need RC
        refused = acks(client.command(176, 1, main, 0))
        assert refused == [(176, ACK_ACCEPTED), (176, mavlink.MAV_RESULT_TEMPORARILY_REJECTED)]
        assert ap.mode is Mode.LOITER
        texts = texts_of(run(ap, 1.1))  # 1.1 s: past the 1 s between two refusal texts
        assert f"Switching to {name} is currently not available\t" in texts


def test_unknown_command_is_unsupported_and_wrong_target_ignored():
    ap = Autopilot()
    client = Client(ap)
    assert acks(client.command(31337)) == [(31337, mavlink.MAV_RESULT_UNSUPPORTED)]
    assert client.command(400, 1, target=7) == []  # another system's command: silence
    assert not ap.armed
    client.setpoint(vz=-1.0, target=7)
    assert ap.commander.setpoint is None
    ack = client.command(400, 1)[0]
    assert (ack.target_system, ack.target_component) == (255, 190)


def test_statustext_only_on_links_with_a_gcs_heartbeat():
    ap = Autopilot()
    onboard, gcs = Client(ap, "onboard"), Client(ap, "gcs")
    onboard.heartbeat(mavlink.MAV_TYPE_ONBOARD_CONTROLLER)
    gcs.heartbeat(mavlink.MAV_TYPE_GCS)
    onboard.command(176, 1, 6, 0)
    assert acks(onboard.command(400, 1)) == [(400, mavlink.MAV_RESULT_TEMPORARILY_REJECTED)]
    ap.step(DT)
    out = ap.poll()
    texts = {link: texts_of(msgs) for link, msgs in out.items()}
    assert texts["onboard"] == []
    assert texts["gcs"] == [ARM_DENIED + "\t"]


def test_bad_frame_is_refused_with_statustext_and_nothing_flies():
    ap = Autopilot()
    gcs = Client(ap, "gcs")
    gcs.heartbeat(mavlink.MAV_TYPE_GCS)
    gcs.setpoint(vx=1.0, frame=9)
    assert ap.commander.setpoint is None
    assert ap.rejected_setpoints == 1
    ap.step(DT)
    texts = texts_of(ap.poll()["gcs"])
    assert texts == ["SET_POSITION_TARGET_LOCAL_NED coordinate frame 9 unsupported\t"]


def test_long_statustext_is_chunked():
    ap = Autopilot()
    from dronewrapper_sim.px4.commander import StatusText

    chunks = ap.statustext(StatusText(4, "x" * 120))
    assert len(chunks) == 3
    assert len({c.id for c in chunks}) == 1 and chunks[0].id != 0
    assert [c.chunk_seq for c in chunks] == [0, 1, 2]


def test_params_read_list_set_over_mavlink():
    ap = Autopilot()
    client = Client(ap)
    value = client.send(mavlink.MAVLink_param_request_read_message(1, 1, b"COM_OF_LOSS_T", -1))[0]
    assert value.param_id == "COM_OF_LOSS_T" and value.param_value == 1.0
    assert value.param_type == mavlink.MAV_PARAM_TYPE_REAL32
    by_index = client.send(mavlink.MAVLink_param_request_read_message(1, 1, b"", 0))[0]
    assert by_index.param_id == "SYS_AUTOSTART" and by_index.param_index == 0
    assert params.float_bits_to_int32(by_index.param_value) == 10040
    assert client.send(mavlink.MAVLink_param_request_read_message(1, 1, b"NOPE", -1)) == []
    bits = params.int32_to_float_bits(3)
    echo = client.send(mavlink.MAVLink_param_set_message(1, 1, b"NAV_RCL_ACT", bits, 6))[0]
    assert params.float_bits_to_int32(echo.param_value) == 3
    assert ap.params["NAV_RCL_ACT"] == 3
    client.send(mavlink.MAVLink_param_request_list_message(1, 1))
    listed = [m for m in run(ap, 0.2) if m.get_type() == "PARAM_VALUE"]
    names = [m.param_id for m in listed]
    assert len(set(names)) == len(ap.params) == listed[0].param_count
    assert "NAV_RCL_ACT" in names


def test_message_intervals():
    ap = Autopilot()
    client = Client(ap)
    lpn = telemetry.LOCAL_POSITION_NED
    assert acks(client.command(511, lpn, 20_000)) == [(511, ACK_ACCEPTED)]
    assert acks(client.command(511, 0, 100_000)) == [(511, mavlink.MAV_RESULT_FAILED)]
    replies = client.command(510, lpn)
    assert [m.interval_us for m in replies if m.get_type() == "MESSAGE_INTERVAL"] == [20_000]
    out = run(ap, 2.0)
    onboard_lpn = sum(1 for m in out if m.get_type() == "LOCAL_POSITION_NED")
    # onboard link at 50 Hz now, GCS link still 50 Hz: ~200 in 2 s
    assert 190 <= onboard_lpn <= 205
    client.command(511, lpn, -1)
    out = run(ap, 1.0)
    assert 45 <= sum(1 for m in out if m.get_type() == "LOCAL_POSITION_NED") <= 52


def test_telemetry_rates_per_link():
    ap = Autopilot()
    counts: dict[str, dict[str, int]] = {"onboard": {}, "gcs": {}}
    for _ in range(round(2.0 / DT)):
        ap.step(DT)
        for link, msgs in ap.poll().items():
            for m in msgs:
                counts[link][m.get_type()] = counts[link].get(m.get_type(), 0) + 1
    onboard = {k: v / 2.0 for k, v in counts["onboard"].items()}
    assert onboard["ATTITUDE"] == pytest.approx(100, abs=3)
    assert onboard["LOCAL_POSITION_NED"] == pytest.approx(30, abs=2)
    assert onboard["HEARTBEAT"] == pytest.approx(1, abs=0.5)
    assert onboard["EXTENDED_SYS_STATE"] == pytest.approx(5, abs=1)
    assert counts["gcs"]["ATTITUDE"] / 2.0 == pytest.approx(50, abs=2)
    for kind in (
        "GLOBAL_POSITION_INT",
        "SYS_STATUS",
        "BATTERY_STATUS",
        "HOME_POSITION",
        "VFR_HUD",
        "ALTITUDE",
        "POSITION_TARGET_LOCAL_NED",
        "ATTITUDE_QUATERNION",
    ):
        assert counts["onboard"].get(kind, 0) >= 1, kind


def test_a_loop_waking_at_50_hz_keeps_the_streams_up_to_50_hz():
    """Five physics steps a wake-up, streams due within half a wake-up sent early: a 50 Hz
    stream keeps 50 Hz, a 100 Hz one is capped at the loop's 50 Hz, slower ones keep theirs."""
    ap = Autopilot()
    counts: dict[str, int] = {}
    wakes = 0
    while ap.time_s < 2.0 - 1e-9:
        for _ in range(5):  # 250 Hz physics, a wake-up every 20 ms
            ap.step(DT)
        wakes += 1
        for m in ap.poll(ahead_s=0.01)["onboard"]:
            counts[m.get_type()] = counts.get(m.get_type(), 0) + 1
    assert wakes == 100
    rate = {k: v / 2.0 for k, v in counts.items()}
    assert rate["ATTITUDE_QUATERNION"] == pytest.approx(50, abs=0.5)
    assert rate["GLOBAL_POSITION_INT"] == pytest.approx(50, abs=0.5)
    assert rate["ATTITUDE"] == pytest.approx(50, abs=0.5)  # 100 Hz asked: one a wake-up
    assert rate["LOCAL_POSITION_NED"] == pytest.approx(30, abs=1)
    assert rate["EXTENDED_SYS_STATE"] == pytest.approx(5, abs=0.5)


def test_stream_due_ahead_keeps_its_period_when_wake_ups_jitter():
    """Wake-ups on a 20 ms grid, each up to a physics step (4 ms) early or 9 ms late: a
    50 Hz stream is sent at each, none lost, none doubled."""
    from dronewrapper_sim.px4.telemetry import StreamScheduler

    sched = StreamScheduler({1: 50.0}, now=0.0)
    jitter = [0.0, 0.009, -0.004, 0.005, -0.004, 0.0, 0.008, -0.002]
    sent = [len(sched.due(0.02 * k + jitter[k % 8], ahead_s=0.01)) for k in range(1, 501)]
    assert sent == [1] * 500


def test_nan_setpoints_hold_and_never_crash():
    ap = Autopilot()
    client = Client(ap)
    client.setpoint(vz=-1.5)
    client.command(176, 1, 6, 0)
    client.command(400, 1)
    for _ in range(40):
        client.setpoint(vz=-1.5)
        run(ap, 0.1)
    height = ap.state.z
    assert height > 1.0
    for _ in range(20):
        client.setpoint(vx=math.nan, vy=math.nan, vz=math.nan, yaw_rate=math.nan)
        run(ap, 0.1)
    assert ap.nonfinite_setpoints == 20
    assert ap.mode is Mode.OFFBOARD
    s = ap.state
    assert all(math.isfinite(v) for v in (s.x, s.y, s.z, s.vx, s.vy, s.vz))
    assert math.hypot(s.vx, s.vy) < 0.3 and abs(s.vz) < 0.3  # holding, not following NaN
    assert s.z == pytest.approx(height, abs=1.0)


def test_takeoff_command_to_mis_takeoff_alt_then_loiter_and_land():
    ap = Autopilot()
    client = Client(ap)
    assert acks(client.command(400, 1)) == [(400, ACK_ACCEPTED)]
    assert acks(client.command(22, *[math.nan] * 7)) == [(22, ACK_ACCEPTED)]
    assert ap.mode is Mode.TAKEOFF
    t = 0.0
    while ap.mode is Mode.TAKEOFF and t < 15:
        run(ap, 0.1)
        t += 0.1
    assert ap.mode is Mode.LOITER
    assert 4.0 < t < 9.0  # PX4 SITL: back in LOITER ~7.6 s after the command
    run(ap, 2.0)
    assert ap.state.z == pytest.approx(2.5, abs=0.2)
    assert acks(client.command(21, *[math.nan] * 7)) == [(21, ACK_ACCEPTED)]
    t = 0.0
    while ap.armed and t < 20:
        run(ap, 0.1)
        t += 0.1
    assert not ap.armed
    assert 5.0 < t < 12.0  # "Disarmed by landing" 10-12 s from 2-5 m on PX4 SITL
    assert ap.commander.landed_state is LandedState.ON_GROUND


def test_absurd_params_are_refused_or_survived():
    ap = Autopilot()
    client = Client(ap)
    huge = client.send(mavlink.MAVLink_param_set_message(1, 1, b"NAV_RCL_ACT", 1e30, 9))
    assert huge == [] and ap.params["NAV_RCL_ACT"] == 2  # does not fit an int32: ignored
    client.send(mavlink.MAVLink_param_request_list_message(1, 1))
    assert len([m for m in run(ap, 0.1) if m.get_type() == "PARAM_VALUE"]) == len(ap.params)
    # bounded commands keep even absurd gains finite; if the physics ever diverged, the
    # vehicle "crashes" (disarmed, on the ground) instead of NaN reaching the telemetry
    bad = Autopilot(quad=QuadParams(drag_z=-1e308))
    bad.commander.arm(0.0, bad.state, force=True)
    bad.state = QuadState(z=5.0, vz=10.0, on_ground=False)
    out = run(bad, 0.5)
    assert bad.crashes == 1 and not bad.armed
    assert bad.state.z == 0.0
    lpn = [m for m in out if m.get_type() == "LOCAL_POSITION_NED"]
    assert lpn and all(math.isfinite(m.z) for m in lpn)


def takeoff_to(ap: Autopilot, client: Client, height: float) -> None:
    client.command(400, 1)
    client.command(22, *[math.nan] * 6, ap.config.home_alt_m + height)
    for _ in range(600):
        if ap.mode is not Mode.TAKEOFF:
            break
        fly_for(ap, 0.1)
    assert ap.mode is Mode.LOITER
    fly_for(ap, 1.0)
    assert ap.state.z == pytest.approx(height, abs=0.15)


@pytest.mark.parametrize(("height", "low", "high"), [(5.0, 8.0, 13.0), (30.0, 32.0, 42.0)])
def test_nav_land_to_disarm_times_match_px4_sitl(height, low, high):
    """PX4 SITL: "Disarmed by landing" ~10-12 s after NAV_LAND from 2-5 m, 37.6 s from 30 m."""
    ap = Autopilot()
    client = Client(ap)
    takeoff_to(ap, client, height)
    client.command(21, *[math.nan] * 7)
    t = 0.0
    while ap.armed and t < 60:
        fly_for(ap, 0.1)
        t += 0.1
    assert low < t < high


def test_rtl_far_from_home_climbs_returns_lands_and_disarms():
    ap = Autopilot()
    client = Client(ap)
    takeoff_to(ap, client, 5.0)
    client.setpoint()
    client.command(176, 1, 6, 0)
    for _ in range(160):  # 20 m north in OFFBOARD, streaming position setpoints
        client.send(
            mavlink.MAVLink_set_position_target_local_ned_message(
                0, 1, 1, 1, 3064, 20.0, 0, -5.0, 0, 0, 0, 0, 0, 0, 0, 0
            )
        )
        fly_for(ap, 0.05)
    assert ap.state.y == pytest.approx(20.0, abs=0.5)
    top, t = 0.0, 0.0
    while ap.armed and t < 120:  # the stream stopped: failsafe RTL
        fly_for(ap, 0.2)
        t += 0.2
        top = max(top, ap.state.z)
    assert not ap.armed
    assert top == pytest.approx(30.0, abs=0.6)  # RTL_RETURN_ALT
    assert math.hypot(ap.state.x, ap.state.y) < 1.0  # home
    assert ap.mode is Mode.OFFBOARD  # the user-intended mode, disarmed


def fly_for(ap: Autopilot, seconds: float) -> None:
    """Advance physics and autopilot only (no telemetry): for long flights."""
    for _ in range(round(seconds / DT)):
        ap.step(DT)


def test_same_seed_same_flight_through_the_whole_autopilot():
    def flight(seed: int) -> tuple:
        ap = Autopilot(AutopilotConfig(seed=seed, wind_east=2.0, wind_gust=1.5))
        client = Client(ap)
        client.command(400, 1)
        client.command(22, *[math.nan] * 7)
        fly_for(ap, 8.0)
        s = ap.state
        return (s.x, s.y, s.z, s.vx, s.vy, s.yaw, ap.battery.consumed_mah)

    assert flight(3) == flight(3)
    assert flight(3) != flight(4)
