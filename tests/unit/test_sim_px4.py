"""The PX4-like autopilot as pure logic: modes, params, offboard setpoints, commander state
machine (arming rules, auto-disarm, failsafe timing with injected time) and the MAVLink
message handling, fed with real MAVLink bytes (packed by a client, parsed by the vehicle)."""

from __future__ import annotations

import math

import pytest
from pymavlink.dialects.v20 import common as mavlink

from dronewrapper_sim.dynamics import QuadParams, QuadState
from dronewrapper_sim.px4 import modes, offboard, params, telemetry
from dronewrapper_sim.px4.autopilot import Autopilot, AutopilotConfig
from dronewrapper_sim.px4.commander import ARM_DENIED, Commander, LandedState
from dronewrapper_sim.px4.modes import Mode

DT = 1.0 / 250.0
ACK_ACCEPTED = mavlink.MAV_RESULT_ACCEPTED


# ---- modes and params ----


def test_custom_mode_encoding_matches_px4():
    assert Mode.OFFBOARD.custom_mode == 6 << 16 == 393216
    assert Mode.LOITER.custom_mode == (4 << 16) | (3 << 24) == 50593792
    assert Mode.LAND.custom_mode == (4 << 16) | (6 << 24)
    assert modes.decode(Mode.RTL.custom_mode) == (4, 5)
    assert modes.from_custom_mode(Mode.TAKEOFF.custom_mode) is Mode.TAKEOFF
    assert modes.from_main_sub(6, 7) is Mode.OFFBOARD  # sub ignored outside AUTO
    assert modes.from_main_sub(4, 42) is None
    assert modes.from_name("AUTO.LOITER") is Mode.LOITER
    assert modes.from_name("offboard") is Mode.OFFBOARD
    assert Mode.RTL.mavros_name == "AUTO.RTL"


def test_param_defaults_are_px4s():
    store = params.ParamStore()
    assert store["COM_OF_LOSS_T"] == 1.0
    assert store["COM_OBL_RC_ACT"] == 0
    assert store["NAV_RCL_ACT"] == 2
    assert store["NAV_DLL_ACT"] == 0
    assert store["COM_DISARM_PRFLT"] == 10.0
    assert store["COM_DISARM_LAND"] == 2.0
    assert store["MIS_TAKEOFF_ALT"] == 2.5
    assert store["MPC_XY_VEL_MAX"] == 12.0
    assert store["MPC_Z_VEL_MAX_UP"] == 3.0
    assert store["MPC_TKO_SPEED"] == 1.5
    assert store["COM_RC_IN_MODE"] == 1
    assert store["COM_ARM_WO_GPS"] == 1
    assert len({p.name for p in store.defs}) == len(store)
    assert all(len(p.name) <= 16 for p in store.defs)


def test_int32_params_travel_as_raw_bits():
    store = params.ParamStore()
    wire = store.wire_value("SYS_AUTOSTART")
    assert wire != 10040.0 and wire == pytest.approx(1.4069e-41, rel=1e-3)
    assert params.float_bits_to_int32(wire) == 10040
    assert store.type_of("SYS_AUTOSTART") == mavlink.MAV_PARAM_TYPE_INT32
    assert store.type_of("COM_OF_LOSS_T") == mavlink.MAV_PARAM_TYPE_REAL32
    assert store.wire_value("COM_OF_LOSS_T") == 1.0
    bits = params.int32_to_float_bits(3)
    assert store.from_wire("NAV_RCL_ACT", bits, mavlink.MAV_PARAM_TYPE_INT32) == 3
    with pytest.raises(ValueError):
        store.set("COM_OF_LOSS_T", math.nan)
    with pytest.raises(KeyError):
        store.set("NOT_A_PARAM", 1)


# ---- offboard setpoints ----

ZERO3 = (0.0, 0.0, 0.0)


@pytest.mark.parametrize("frame", [7, 9, 12, 0, 3])
def test_unsupported_frames_are_refused_with_px4s_text(frame):
    result = offboard.parse(frame, 1991, ZERO3, (1.0, 0, 0), ZERO3, 0.0, 0.0, 0.0)
    assert isinstance(result, offboard.Refusal)
    assert result.statustext == (
        f"SET_POSITION_TARGET_LOCAL_NED coordinate frame {frame} unsupported"
    )


def test_body_ned_rotates_velocity_by_heading_only():
    """As measured on PX4: at yaw ~97 deg, body vx = 2 -> local (vx -0.24 N, vy +1.98 E)."""
    yaw = math.radians(97.0)
    sp = offboard.parse(8, 1991, ZERO3, (2.0, 0.0, -0.5), ZERO3, 0.0, 0.1, yaw)
    assert isinstance(sp, offboard.OffboardSetpoint)
    east, north, up = sp.velocity
    assert north == pytest.approx(2.0 * math.cos(yaw))
    assert east == pytest.approx(2.0 * math.sin(yaw))
    assert up == 0.5  # vz stays NED-down, just flipped to ENU-up
    assert sp.yaw_rate == -0.1  # NED yaw rate (clockwise) -> ENU (counter-clockwise)
    assert math.isnan(sp.yaw)  # ignored by mask 1991
    right = offboard.parse(8, 1991, ZERO3, (0.0, 1.0, 0.0), ZERO3, 0.0, 0.0, yaw)
    assert right.velocity[1] == pytest.approx(-math.sin(yaw))  # body right -> local -north


def test_local_position_mask_and_ignored_fields():
    sp = offboard.parse(1, 3064, (1.0, 2.0, -3.0), (9.0, 9.0, 9.0), ZERO3, 0.5, 9.0, 0.0)
    assert sp.position == (2.0, 1.0, 3.0)
    assert all(math.isnan(v) for v in sp.velocity)
    assert sp.yaw == pytest.approx(math.pi / 2 - 0.5)
    assert math.isnan(sp.yaw_rate)
    mixed = offboard.parse(8, 1987, (0, 0, -4.0), (1.0, 0.0, 0.0), ZERO3, 0.0, 0.2, 0.0)
    assert mixed.position[2] == 4.0 and math.isnan(mixed.position[0])
    assert mixed.velocity[1] == pytest.approx(1.0)  # forward at yaw 0 (north) = north


def test_nan_fields_are_not_controlled_and_counted():
    sp = offboard.parse(1, 1991, ZERO3, (math.nan, math.inf, 0.0), ZERO3, 0.0, 0.0, 0.0)
    assert sp.non_finite == 2
    assert math.isnan(sp.velocity[0]) and math.isnan(sp.velocity[1])
    all_ignored = offboard.parse(1, 0xFFF, ZERO3, ZERO3, ZERO3, 0.0, 0.0, 0.0)
    assert isinstance(all_ignored, offboard.Refusal) and all_ignored.statustext is None


# ---- commander (time injected) ----


def ground() -> QuadState:
    return QuadState()


def flying(z: float = 5.0, x: float = 0.0) -> QuadState:
    return QuadState(x=x, z=z, on_ground=False)


def velocity_sp(vz_up: float = 0.0) -> offboard.OffboardSetpoint:
    sp = offboard.parse(1, 1991, ZERO3, (0.0, 0.0, -vz_up), ZERO3, 0.0, 0.0, 0.0)
    assert isinstance(sp, offboard.OffboardSetpoint)
    return sp


def test_offboard_mode_accepted_disarmed_but_arming_refused_without_stream():
    cmd = Commander(params.ParamStore(), ground())
    assert cmd.set_mode(Mode.OFFBOARD, 0.0, ground()) == mavlink.MAV_RESULT_ACCEPTED
    assert cmd.nav_mode is Mode.OFFBOARD
    assert cmd.arm(0.1, ground()) == mavlink.MAV_RESULT_TEMPORARILY_REJECTED
    assert [t.text for t in cmd.drain_texts()] == [ARM_DENIED]
    assert not cmd.armed
    for i in range(5):
        cmd.on_setpoint(velocity_sp(), 0.2 + 0.05 * i)
    assert cmd.arm(0.5, ground()) == mavlink.MAV_RESULT_ACCEPTED
    assert cmd.armed


def test_arming_rules_for_other_modes():
    cmd = Commander(params.ParamStore(), ground())
    assert (
        cmd.set_mode(Mode.POSCTL, 0.0, ground()) == mavlink.MAV_RESULT_ACCEPTED
    )  # disarmed: always accepted
    assert cmd.arm(0.0, ground()) == mavlink.MAV_RESULT_TEMPORARILY_REJECTED  # needs RC
    assert cmd.arm(0.0, ground(), force=True) == mavlink.MAV_RESULT_ACCEPTED
    cmd2 = Commander(params.ParamStore(), ground())
    assert cmd2.nav_mode is Mode.LOITER  # boots in Hold
    assert cmd2.arm(0.0, ground()) == mavlink.MAV_RESULT_ACCEPTED
    # armed: switching to a mode that cannot run is refused
    assert cmd2.set_mode(Mode.OFFBOARD, 0.5, ground()) == mavlink.MAV_RESULT_TEMPORARILY_REJECTED
    assert cmd2.set_mode(Mode.POSCTL, 0.5, ground()) == mavlink.MAV_RESULT_TEMPORARILY_REJECTED
    texts = [t.text for t in cmd2.drain_texts()]
    assert "Switching to Offboard is currently not available" in texts


def test_preflight_auto_disarm_after_com_disarm_prflt():
    cmd = Commander(params.ParamStore(), ground())
    assert cmd.arm(0.0, ground()) == mavlink.MAV_RESULT_ACCEPTED
    t = 0.0
    while cmd.armed and t < 20.0:
        t += 0.01
        cmd.update(t, ground())
    assert t == pytest.approx(10.0, abs=0.02)
    assert "Disarmed by auto preflight disarming" in [x.text for x in cmd.drain_texts()]


def test_disarm_refused_in_the_air_unless_forced():
    cmd = Commander(params.ParamStore(), ground())
    cmd.arm(0.0, ground())
    cmd.update(1.0, flying())  # take-off detected
    assert not cmd.landed
    assert cmd.disarm(1.1, flying()) == mavlink.MAV_RESULT_TEMPORARILY_REJECTED
    assert cmd.armed
    assert cmd.disarm(1.2, flying(), force=True) == mavlink.MAV_RESULT_ACCEPTED


def streaming_flight(cmd: Commander, until: float, t: float = 0.0, period: float = 0.05):
    """Stream setpoints every ``period`` s until ``until``, vehicle flying at 5 m."""
    while t < until:
        t = round(t + DT, 6)
        if round(t / period, 6).is_integer():
            cmd.on_setpoint(velocity_sp(), t)
        cmd.update(t, flying())
    return t


def test_offboard_loss_failsafe_after_com_of_loss_t_and_unlatched_return():
    cmd = Commander(params.ParamStore(), ground())
    cmd.on_setpoint(velocity_sp(), 0.0)
    cmd.set_mode(Mode.OFFBOARD, 0.0, ground())
    cmd.arm(0.0, ground())
    t = streaming_flight(cmd, 3.0)
    assert cmd.nav_mode is Mode.OFFBOARD and not cmd.landed
    last = cmd.setpoint_at
    cmd.drain_texts()
    while cmd.nav_mode is Mode.OFFBOARD and t < last + 3.0:  # stream stopped
        t += DT
        cmd.update(t, flying())
    assert t - last == pytest.approx(1.0, abs=2 * DT)  # COM_OF_LOSS_T
    assert cmd.nav_mode is Mode.RTL  # COM_OBL_RC_ACT 0 needs RC -> NAV_RCL_ACT 2 = Return
    assert cmd.user_mode is Mode.OFFBOARD  # still what the user wants
    assert cmd.failsafe
    assert "Failsafe activated" in [x.text for x in cmd.drain_texts()]
    cmd.update(t + 0.5, flying())
    resumed = t + 0.5
    cmd.on_setpoint(velocity_sp(), resumed)
    cmd.update(resumed + DT, flying())
    assert cmd.nav_mode is Mode.OFFBOARD  # back within one step, no mode command
    assert not cmd.failsafe


def test_gaps_shorter_than_com_of_loss_t_keep_offboard():
    cmd = Commander(params.ParamStore(), ground())
    cmd.on_setpoint(velocity_sp(), 0.0)
    cmd.set_mode(Mode.OFFBOARD, 0.0, ground())
    cmd.arm(0.0, ground())
    streaming_flight(cmd, 8.0, period=0.8)  # 1.25 Hz: PX4 keeps OFFBOARD
    assert cmd.nav_mode is Mode.OFFBOARD and not cmd.failsafe


@pytest.mark.parametrize(
    ("obl", "rcl", "expected"),
    [
        (0, 2, Mode.RTL),
        (0, 3, Mode.LAND),
        (0, 1, Mode.LOITER),
        (4, 2, Mode.LAND),
        (5, 2, Mode.LOITER),
    ],
)
def test_failsafe_action_follows_params(obl, rcl, expected):
    store = params.ParamStore({"COM_OBL_RC_ACT": obl, "NAV_RCL_ACT": rcl})
    cmd = Commander(store, ground())
    cmd.on_setpoint(velocity_sp(), 0.0)
    cmd.set_mode(Mode.OFFBOARD, 0.0, ground())
    cmd.arm(0.0, ground())
    t = streaming_flight(cmd, 2.0)
    cmd.update(t + 1.5, flying())
    assert cmd.nav_mode is expected


def test_rtl_far_from_home_climbs_first_close_to_home_lands():
    far = Commander(params.ParamStore(), ground())
    far.arm(0.0, ground())
    far.update(1.0, flying(z=5.0, x=12.0))
    far.set_mode(Mode.RTL, 1.0, flying(z=5.0, x=12.0))
    far.update(1.01, flying(z=5.0, x=12.0))
    assert far.target.position[2] == pytest.approx(30.0)  # RTL_RETURN_ALT
    assert far.landed_state is LandedState.IN_AIR
    near = Commander(params.ParamStore(), ground())
    near.arm(0.0, ground())
    near.update(1.0, flying(z=5.0, x=3.0))
    near.set_mode(Mode.RTL, 1.0, flying(z=5.0, x=3.0))
    near.update(1.01, flying(z=5.0, x=3.0))
    assert near.target.velocity[2] < 0  # descending straight away
    assert near.landed_state is LandedState.LANDING
    assert "RTL: land at destination" in [t.text for t in near.drain_texts()]


def test_landing_detection_and_disarm_then_user_mode_restored():
    cmd = Commander(params.ParamStore(), ground())
    cmd.on_setpoint(velocity_sp(), 0.0)
    cmd.set_mode(Mode.OFFBOARD, 0.0, ground())
    cmd.arm(0.0, ground())
    t = streaming_flight(cmd, 2.0)
    assert cmd.set_mode(Mode.LAND, t, flying()) == mavlink.MAV_RESULT_ACCEPTED
    cmd.update(t + 0.01, flying(z=2.0))
    assert cmd.landed_state is LandedState.LANDING
    touchdown = t + 1.0
    t = touchdown
    while cmd.armed and t < touchdown + 10:
        t += 0.01
        cmd.update(t, ground())
    texts = [x.text for x in cmd.drain_texts()]
    assert "Landing detected" in texts and "Disarmed by landing" in texts
    assert t - touchdown == pytest.approx(1.0 + 2.0, abs=0.03)  # LNDMC_TRIG_TIME + DISARM_LAND
    assert cmd.nav_mode is Mode.OFFBOARD  # the intended mode again, as PX4 reports it


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
