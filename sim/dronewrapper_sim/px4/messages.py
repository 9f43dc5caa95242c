"""The MAVLink messages PX4 sends, built from the simulated vehicle's state.

One function per telemetry stream (HEARTBEAT, ATTITUDE, ...), each reading a :class:`Vehicle`
(the autopilot, seen through the attributes these functions read) and converting the
simulator's local ENU / FLU state to MAVLink's NED / FRD. :data:`BUILDERS` maps each
message id the autopilot streams or answers to its builder. Times: ``time_boot_ms`` is the
vehicle's simulated time (ms), ``time_usec`` the same in us.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Protocol

from pymavlink.dialects.v20 import common as mavlink

from dronewrapper.rotations import quat_from_rpy
from dronewrapper_sim import frames
from dronewrapper_sim.battery import Battery
from dronewrapper_sim.dynamics import QuadParams, QuadState
from dronewrapper_sim.px4 import offboard, telemetry
from dronewrapper_sim.px4.commander import Commander, StatusText
from dronewrapper_sim.px4.flight_control import PositionController
from dronewrapper_sim.px4.params import ParamStore

BASE_MODE = (  # 29, as PX4 SITL reports it
    mavlink.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED
    | mavlink.MAV_MODE_FLAG_STABILIZE_ENABLED
    | mavlink.MAV_MODE_FLAG_GUIDED_ENABLED
    | mavlink.MAV_MODE_FLAG_AUTO_ENABLED
)
STATUSTEXT_LEN = 50
PX4_VERSION = (1, 17, 0)

_SENSORS = (
    1
    | 2
    | 4
    | 8
    | 32  # gyro, accel, mag, baro, GPS
    | 1024
    | 2048
    | 4096
    | 8192
    | 16384
    | 32768  # rate, attitude, yaw, z, xy control, motors
    | (1 << 21)
    | (1 << 25)
    | (1 << 28)  # AHRS, battery, pre-arm check
)
_CAPABILITIES = (
    1
    | 2
    | 4
    | 8
    | 16  # mission float, param float, mission int, command int, param bytewise
    | 64
    | 128
    | 256
    | 1024  # set attitude/local/global target, ftp-less; mission fence
    | 8192
    | 16384  # MAVLink 2, mission rally
)


class Home(Protocol):
    """Where the local frame sits: its origin's altitude (m AMSL)."""

    @property
    def home_alt_m(self) -> float: ...


class Vehicle(Protocol):
    """What the builders read of the autopilot."""

    @property
    def time_s(self) -> float: ...  # simulated time (s)
    @property
    def sysid(self) -> int: ...
    @property
    def config(self) -> Home: ...
    @property
    def state(self) -> QuadState: ...  # local ENU, FLU body
    @property
    def commander(self) -> Commander: ...
    @property
    def controller(self) -> PositionController: ...
    @property
    def battery(self) -> Battery: ...
    @property
    def quad(self) -> QuadParams: ...
    @property
    def wind_enu(self) -> tuple[float, float, float]: ...  # m/s

    def geodetic(self, x: float, y: float) -> tuple[float, float]: ...


def _boot_ms(v: Vehicle) -> int:
    return int(v.time_s * 1000) & 0xFFFFFFFF


def _usec(v: Vehicle) -> int:
    return int(v.time_s * 1e6)


def heartbeat(v: Vehicle) -> mavlink.MAVLink_message:
    cmd = v.commander
    base = BASE_MODE | (mavlink.MAV_MODE_FLAG_SAFETY_ARMED if cmd.armed else 0)
    status = mavlink.MAV_STATE_ACTIVE if cmd.armed else mavlink.MAV_STATE_STANDBY
    if cmd.failsafe:
        status = mavlink.MAV_STATE_CRITICAL
    return mavlink.MAVLink_heartbeat_message(
        mavlink.MAV_TYPE_QUADROTOR,
        mavlink.MAV_AUTOPILOT_PX4,
        base,
        cmd.nav_mode.custom_mode,
        status,
        3,
    )


def sys_status(v: Vehicle) -> mavlink.MAVLink_message:
    b = v.battery
    return mavlink.MAVLink_sys_status_message(
        _SENSORS,
        _SENSORS,
        _SENSORS,
        150,
        int(b.voltage * 1000),
        int(b.current_a * 100),
        round(b.remaining * 100),
        0,
        0,
        0,
        0,
        0,
        0,
    )


def battery_status(v: Vehicle) -> mavlink.MAVLink_message:
    b = v.battery
    cell_mv = int(b.cell_voltage() * 1000)
    voltages = [cell_mv] * b.cells + [65535] * (10 - b.cells)
    return mavlink.MAVLink_battery_status_message(
        0,
        0,
        1,
        32767,
        voltages[:10],
        int(b.current_a * 100),
        int(b.consumed_mah),
        -1,
        round(b.remaining * 100),
        0,
        1,
    )


def _euler_ned(v: Vehicle) -> tuple[float, float, float]:
    s = v.state
    return frames.euler_flu_enu_to_frd_ned(s.roll, s.pitch, s.yaw)


def attitude(v: Vehicle) -> mavlink.MAVLink_message:
    s = v.state
    roll, pitch, yaw = _euler_ned(v)
    p, q, r = frames.rates_flu_to_frd(s.p, s.q, s.r)
    return mavlink.MAVLink_attitude_message(_boot_ms(v), roll, pitch, yaw, p, q, r)


def attitude_quaternion(v: Vehicle) -> mavlink.MAVLink_message:
    s = v.state
    x, y, z, w = quat_from_rpy(*_euler_ned(v))
    p, q, r = frames.rates_flu_to_frd(s.p, s.q, s.r)
    return mavlink.MAVLink_attitude_quaternion_message(
        _boot_ms(v), w, x, y, z, p, q, r, [0.0, 0.0, 0.0, 0.0]
    )


def local_position_ned(v: Vehicle) -> mavlink.MAVLink_message:
    s = v.state
    n, e, d = frames.enu_to_ned(s.x, s.y, s.z)
    vn, ve, vd = frames.enu_to_ned(s.vx, s.vy, s.vz)
    return mavlink.MAVLink_local_position_ned_message(_boot_ms(v), n, e, d, vn, ve, vd)


def global_position_int(v: Vehicle) -> mavlink.MAVLink_message:
    s = v.state
    lat, lon = v.geodetic(s.x, s.y)
    vn, ve, vd = frames.enu_to_ned(s.vx, s.vy, s.vz)
    hdg = round(math.degrees(frames.yaw_enu_to_ned(s.yaw)) * 100) % 36000
    return mavlink.MAVLink_global_position_int_message(
        _boot_ms(v),
        round(lat * 1e7),
        round(lon * 1e7),
        round((v.config.home_alt_m + s.z) * 1000),
        round((s.z - v.commander.home[2]) * 1000),
        round(vn * 100),
        round(ve * 100),
        round(vd * 100),
        hdg,
    )


def gps_raw_int(v: Vehicle) -> mavlink.MAVLink_message:
    s = v.state
    lat, lon = v.geodetic(s.x, s.y)
    speed = math.hypot(s.vx, s.vy)
    cog = round(math.degrees(math.atan2(s.vx, s.vy)) * 100) % 36000 if speed > 0.2 else 0
    alt_mm = round((v.config.home_alt_m + s.z) * 1000)
    return mavlink.MAVLink_gps_raw_int_message(
        _usec(v),
        3,
        round(lat * 1e7),
        round(lon * 1e7),
        alt_mm,
        70,
        100,
        round(speed * 100),
        cog,
        12,
        alt_mm,
        500,
        800,
        200,
        0,
    )


def position_target(v: Vehicle) -> mavlink.MAVLink_message:
    target = v.commander.target
    mask = 0
    pos_ned = frames.enu_to_ned(*target.position)
    for i, bit in enumerate(offboard.IGNORE_POSITION):
        if not math.isfinite(pos_ned[i]):
            mask |= bit
    vel_ned = frames.enu_to_ned(*v.controller.velocity_setpoint)
    mask |= sum(offboard.IGNORE_ACCELERATION)
    yaw = frames.yaw_enu_to_ned(target.yaw) if math.isfinite(target.yaw) else math.nan
    if not math.isfinite(yaw):
        mask |= mavlink.POSITION_TARGET_TYPEMASK_YAW_IGNORE
    yaw_rate = -target.yaw_rate if math.isfinite(target.yaw_rate) else math.nan
    if not math.isfinite(yaw_rate):
        mask |= mavlink.POSITION_TARGET_TYPEMASK_YAW_RATE_IGNORE
    return mavlink.MAVLink_position_target_local_ned_message(
        _boot_ms(v),
        mavlink.MAV_FRAME_LOCAL_NED,
        mask,
        *pos_ned,
        *vel_ned,
        math.nan,
        math.nan,
        math.nan,
        yaw,
        yaw_rate,
    )


def vfr_hud(v: Vehicle) -> mavlink.MAVLink_message:
    s = v.state
    w = v.wind_enu
    heading = round(math.degrees(frames.yaw_enu_to_ned(s.yaw))) % 360
    throttle = round(100 * s.thrust / v.quad.max_thrust_accel)
    airspeed = math.hypot(s.vx - w[0], s.vy - w[1])
    return mavlink.MAVLink_vfr_hud_message(
        airspeed,
        math.hypot(s.vx, s.vy),
        heading,
        throttle,
        v.config.home_alt_m + s.z,
        s.vz,
    )


def altitude(v: Vehicle) -> mavlink.MAVLink_message:
    s = v.state
    amsl = v.config.home_alt_m + s.z
    return mavlink.MAVLink_altitude_message(
        _usec(v), amsl, amsl, s.z, s.z - v.commander.home[2], math.nan, s.z
    )


def home_position(v: Vehicle) -> mavlink.MAVLink_message:
    hx, hy, hz = v.commander.home
    lat, lon = v.geodetic(hx, hy)
    n, e, d = frames.enu_to_ned(hx, hy, hz)
    yaw = frames.yaw_enu_to_ned(v.commander.home_yaw)
    q = [math.cos(yaw / 2), 0.0, 0.0, math.sin(yaw / 2)]
    return mavlink.MAVLink_home_position_message(
        round(lat * 1e7),
        round(lon * 1e7),
        round((v.config.home_alt_m + hz) * 1000),
        n,
        e,
        d,
        q,
        0.0,
        0.0,
        0.0,
        _usec(v),
    )


def extended_sys_state(v: Vehicle) -> mavlink.MAVLink_message:
    return mavlink.MAVLink_extended_sys_state_message(0, int(v.commander.landed_state))


def autopilot_version(v: Vehicle) -> mavlink.MAVLink_message:
    major, minor, patch = PX4_VERSION
    version = major << 24 | minor << 16 | patch << 8
    return mavlink.MAVLink_autopilot_version_message(
        _CAPABILITIES,
        version,
        0,
        0,
        0,
        [0] * 8,
        [0] * 8,
        [0] * 8,
        0,
        0,
        v.sysid,
    )


def statustext(text: StatusText, chunk_id: int) -> list[mavlink.MAVLink_message]:
    """STATUSTEXT message(s) for ``text``: PX4 ends texts with a tab; a text over 50 bytes
    goes in chunks that share ``chunk_id`` (non-zero), else one message with id 0."""
    raw = (text.text + "\t").encode("utf-8")
    if len(raw) <= STATUSTEXT_LEN:
        return [mavlink.MAVLink_statustext_message(text.severity, raw, 0, 0)]
    chunks = [raw[i : i + STATUSTEXT_LEN] for i in range(0, len(raw), STATUSTEXT_LEN)]
    return [
        mavlink.MAVLink_statustext_message(text.severity, chunk, chunk_id, i)
        for i, chunk in enumerate(chunks)
    ]


def needs_chunks(text: StatusText) -> bool:
    """Whether :func:`statustext` sends ``text`` in several chunks (then with an id)."""
    return len((text.text + "\t").encode("utf-8")) > STATUSTEXT_LEN


def param_value(params: ParamStore, name: str) -> mavlink.MAVLink_message:
    """PARAM_VALUE of parameter ``name``."""
    return mavlink.MAVLink_param_value_message(
        name.encode("ascii"),
        params.wire_value(name),
        params.type_of(name),
        len(params),
        params.index(name),
    )


def param_name(raw: str | bytes) -> str:
    """A parameter's name from a message's ``param_id`` (NUL-padded, 16 bytes at most)."""
    if isinstance(raw, bytes):
        raw = raw.decode("ascii", "replace")
    return raw.split("\x00", 1)[0]


def command_ack(command: int, result: int, msg: mavlink.MAVLink_message) -> mavlink.MAVLink_message:
    """COMMAND_ACK of ``command`` with ``result``, addressed to the sender of ``msg``."""
    return mavlink.MAVLink_command_ack_message(
        command, result, 0, 0, msg.get_srcSystem(), msg.get_srcComponent()
    )


BUILDERS: dict[int, Callable[[Vehicle], mavlink.MAVLink_message]] = {
    telemetry.HEARTBEAT: heartbeat,
    telemetry.SYS_STATUS: sys_status,
    telemetry.GPS_RAW_INT: gps_raw_int,
    telemetry.ATTITUDE: attitude,
    telemetry.ATTITUDE_QUATERNION: attitude_quaternion,
    telemetry.LOCAL_POSITION_NED: local_position_ned,
    telemetry.GLOBAL_POSITION_INT: global_position_int,
    telemetry.POSITION_TARGET_LOCAL_NED: position_target,
    telemetry.VFR_HUD: vfr_hud,
    telemetry.ALTITUDE: altitude,
    telemetry.BATTERY_STATUS: battery_status,
    telemetry.HOME_POSITION: home_position,
    telemetry.EXTENDED_SYS_STATE: extended_sys_state,
    telemetry.AUTOPILOT_VERSION: autopilot_version,
}
"""Message id -> its builder."""
