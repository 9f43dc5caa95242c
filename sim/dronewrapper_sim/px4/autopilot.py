"""The PX4-like vehicle: MAVLink messages in, MAVLink messages out, physics in between.

``Autopilot`` is pure (no sockets, no clock): the caller advances simulated time with
:meth:`Autopilot.step`, hands it every decoded MAVLink message with :meth:`Autopilot.handle`
(which returns the immediate replies for that link), and collects the telemetry, status texts
and parameter lists due on each link with :meth:`Autopilot.poll`. Links are named (``onboard``,
``gcs``); STATUSTEXT goes only to links where a MAV_TYPE_GCS heartbeat was seen in the last
few seconds, as PX4 does.

One handler per MAVLink message PX4 answers, beside the state it changes; physics, the
commander and the parameters are their own modules.
"""

from __future__ import annotations

import logging
import math
from collections import deque
from dataclasses import dataclass, field

from pymavlink.dialects.v20 import common as mavlink

from dronewrapper.rotations import quat_from_rpy
from dronewrapper_sim import frames
from dronewrapper_sim.battery import Battery, motor_current
from dronewrapper_sim.dynamics import GRAVITY, QuadParams, QuadState, WindModel, step
from dronewrapper_sim.px4 import modes, offboard, telemetry
from dronewrapper_sim.px4.commander import FORCE_MAGIC, Commander, StatusText
from dronewrapper_sim.px4.flight_control import Gains, PositionController
from dronewrapper_sim.px4.geofence import Geofence
from dronewrapper_sim.px4.mission import RALLY, MissionRunner, MissionStore
from dronewrapper_sim.px4.params import ParamStore

log = logging.getLogger("sim.autopilot")

BASE_MODE = (  # 29, as PX4 SITL reports it
    mavlink.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED
    | mavlink.MAV_MODE_FLAG_STABILIZE_ENABLED
    | mavlink.MAV_MODE_FLAG_GUIDED_ENABLED
    | mavlink.MAV_MODE_FLAG_AUTO_ENABLED
)
GCS_HEARTBEAT_TIMEOUT_S = 3.0
PARAMS_PER_POLL = 20
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


@dataclass
class AutopilotConfig:
    """What identifies and places one simulated vehicle.

    Attributes:
        sysid: MAVLink system id (1 + instance).
        home_lat_deg, home_lon_deg, home_alt_m: WGS-84 position (deg, m AMSL) of the local
            frame's origin (the scenario's home).
        start_x, start_y, start_yaw: start pose on the ground, local ENU (m, rad).
        wind_east, wind_north, wind_gust: wind (m/s) and gust strength (m/s, std).
        seed: random seed (gusts).
        params: parameter overrides (PX4 names).
    """

    sysid: int = 1
    home_lat_deg: float = 47.397742
    home_lon_deg: float = 8.545594
    home_alt_m: float = 488.0
    start_x: float = 0.0
    start_y: float = 0.0
    start_yaw: float = 0.0
    wind_east: float = 0.0
    wind_north: float = 0.0
    wind_gust: float = 0.0
    seed: int = 0
    params: dict[str, float] = field(default_factory=dict)


@dataclass
class LinkState:
    """What the autopilot knows about one MAVLink link."""

    name: str
    scheduler: telemetry.StreamScheduler
    gcs_heartbeat_at: float = -math.inf
    param_queue: deque[int] = field(default_factory=deque)
    outbox: list[mavlink.MAVLink_message] = field(default_factory=list)


def _param_name(raw: str | bytes) -> str:
    if isinstance(raw, bytes):
        raw = raw.decode("ascii", "replace")
    return raw.split("\x00", 1)[0]


class Autopilot:
    """A PX4-like multicopter with its physics (see module doc)."""

    def __init__(
        self,
        config: AutopilotConfig | None = None,
        link_rates: dict[str, dict[int, float]] | None = None,
        quad: QuadParams | None = None,
    ) -> None:
        self.config = config or AutopilotConfig()
        cfg = self.config
        self.sysid = cfg.sysid
        self.params = ParamStore({"MAV_SYS_ID": cfg.sysid, **cfg.params})
        self.quad = quad or QuadParams()
        self.state = QuadState(x=cfg.start_x, y=cfg.start_y, yaw=cfg.start_yaw)
        self.commander = Commander(self.params, self.state)
        self.missions = MissionStore(cfg.sysid)  # mission.py: missions, fence, AUTO.MISSION
        self.commander.mission = MissionRunner(
            self.missions,
            self.local_of,
            lambda: self.commander.home,
            self._acceptance_radius,
            origin_amsl=cfg.home_alt_m,
            max_speed=lambda: self.params["MPC_XY_VEL_MAX"],
        )
        self.commander.geofence = Geofence(self.missions, self.local_of)
        self.commander.rally_points = lambda: [
            self.local_of(item.x / 1e7, item.y / 1e7) for item in self.missions.lists[RALLY]
        ]
        self.controller = PositionController()
        self.battery = Battery(
            cells=int(self.params["BAT1_N_CELLS"]), capacity_mah=self.params["BAT1_CAPACITY"]
        )
        self.wind = WindModel(cfg.wind_east, cfg.wind_north, cfg.wind_gust, seed=cfg.seed)
        self.wind_enu = (0.0, 0.0, 0.0)
        self.time_s = 0.0
        self.steps = 0
        self.rejected_setpoints = 0
        self.nonfinite_setpoints = 0
        self.crashes = 0
        self._gains_version = -1
        default_rates = {"onboard": telemetry.ONBOARD_RATES, "gcs": telemetry.GCS_RATES}
        rates = default_rates if link_rates is None else link_rates  # {}: no links at all
        self.links = {
            name: LinkState(name, telemetry.StreamScheduler(r)) for name, r in rates.items()
        }
        self._statustext_id = 0
        self._builders = {
            telemetry.HEARTBEAT: self.msg_heartbeat,
            telemetry.SYS_STATUS: self._msg_sys_status,
            telemetry.GPS_RAW_INT: self._msg_gps_raw_int,
            telemetry.ATTITUDE: self._msg_attitude,
            telemetry.ATTITUDE_QUATERNION: self._msg_attitude_quaternion,
            telemetry.LOCAL_POSITION_NED: self._msg_local_position_ned,
            telemetry.GLOBAL_POSITION_INT: self._msg_global_position_int,
            telemetry.POSITION_TARGET_LOCAL_NED: self._msg_position_target,
            telemetry.VFR_HUD: self._msg_vfr_hud,
            telemetry.ALTITUDE: self._msg_altitude,
            telemetry.BATTERY_STATUS: self._msg_battery_status,
            telemetry.HOME_POSITION: self._msg_home_position,
            telemetry.EXTENDED_SYS_STATE: self._msg_extended_sys_state,
            telemetry.AUTOPILOT_VERSION: self._msg_autopilot_version,
        }

    # ---- physics and time ----

    def step(self, dt: float) -> None:
        """Advance simulated time by ``dt`` seconds (one physics step)."""
        now = self.time_s + dt
        self.time_s = now
        self.steps += 1
        cmd = self.commander
        cmd.update(now, self.state)
        if self._gains_version != self.params.version:  # PARAM_SET takes effect at once
            self._gains_version = self.params.version
            self.controller.gains = _gains(self.params, GRAVITY, self.quad.max_thrust_accel)
        control = self.controller.update(cmd.target, self.state, dt)
        self.wind_enu = self.wind.step(dt)
        state = step(self.state, control, self.quad, dt, self.wind_enu)
        total = state.x + state.y + state.z + state.vx + state.vy + state.vz
        if not math.isfinite(total + state.roll + state.pitch + state.yaw + state.thrust):
            state = self._crash(state)
        self.state = state
        self.battery.step(motor_current(cmd.armed, self.state.thrust), dt)

    def _crash(self, state: QuadState) -> QuadState:
        """The physics diverged (absurd parameters): the vehicle falls to the ground where it
        last was, and the motors stop, instead of NaN reaching the telemetry."""
        self.crashes += 1
        log.error("physics diverged (check the MPC_* parameters): vehicle crashed")
        last = self.state
        self.commander.texts.append(StatusText(0, "Vehicle crashed: physics diverged"))
        self.commander.disarm(self.time_s, last, force=True, reason="Disarmed: crash")
        self.controller.reset()
        return QuadState(x=last.x, y=last.y, yaw=last.yaw)

    def reset_to_start(self) -> None:
        """Back at the start pose, on the ground, disarmed, at rest (battery and params stay)."""
        cfg = self.config
        self.commander.disarm(self.time_s, self.state, force=True, reason="Disarmed: reset")
        self.controller.reset()
        self.state = QuadState(x=cfg.start_x, y=cfg.start_y, yaw=cfg.start_yaw)

    @property
    def armed(self) -> bool:
        return self.commander.armed

    @property
    def mode(self) -> modes.Mode:
        """The navigation mode shown in HEARTBEAT."""
        return self.commander.nav_mode

    # ---- incoming messages ----

    def handle(self, link: str, msg: mavlink.MAVLink_message) -> list[mavlink.MAVLink_message]:
        """Process one message received on ``link``; returns the replies for that link."""
        kind = msg.get_type()
        if kind.startswith("MISSION_"):
            return self.missions.handle(msg, self.time_s, link)
        handler = getattr(self, f"_on_{kind.lower()}", None)
        if handler is None:
            return []
        return handler(self.links[link], msg) or []

    def _for_us(self, target_system: int) -> bool:
        return target_system in (0, self.sysid)

    def _on_heartbeat(self, link: LinkState, msg) -> None:
        if msg.type == mavlink.MAV_TYPE_GCS:
            link.gcs_heartbeat_at = self.time_s

    def _on_set_position_target_local_ned(self, link: LinkState, msg) -> None:
        if not self._for_us(msg.target_system):
            return
        sp = offboard.parse(
            msg.coordinate_frame,
            msg.type_mask,
            (msg.x, msg.y, msg.z),
            (msg.vx, msg.vy, msg.vz),
            (msg.afx, msg.afy, msg.afz),
            msg.yaw,
            msg.yaw_rate,
            frames.yaw_enu_to_ned(self.state.yaw),
        )
        if isinstance(sp, offboard.Refusal):
            self.rejected_setpoints += 1
            if sp.statustext:
                self.commander.texts.append(StatusText(2, sp.statustext))
            return
        if sp.non_finite:
            self.nonfinite_setpoints += 1
        self.commander.on_setpoint(sp, self.time_s)

    def _on_timesync(self, link: LinkState, msg) -> list:
        if msg.tc1 != 0:
            return []
        return [mavlink.MAVLink_timesync_message(int(self.time_s * 1e9), msg.ts1)]

    def _on_set_mode(self, link: LinkState, msg) -> list:
        if not self._for_us(msg.target_system):
            return []
        result = self._set_mode_from(msg.base_mode, *modes.decode(msg.custom_mode))
        ack = self._ack(mavlink.MAV_CMD_DO_SET_MODE, result, msg)
        return [ack, self._ack(mavlink.MAV_CMD_DO_SET_MODE, result, msg)]

    def _on_command_long(self, link: LinkState, msg) -> list:
        if not self._for_us(msg.target_system) or msg.target_component not in (0, 1):
            return []
        params = [msg.param1, msg.param2, msg.param3, msg.param4, msg.param5, msg.param6]
        return self._command(link, msg, msg.command, [*params, msg.param7])

    def _on_command_int(self, link: LinkState, msg) -> list:
        if not self._for_us(msg.target_system) or msg.target_component not in (0, 1):
            return []
        params = [msg.param1, msg.param2, msg.param3, msg.param4, msg.x / 1e7, msg.y / 1e7]
        return self._command(link, msg, msg.command, [*params, msg.z])

    def _on_param_request_read(self, link: LinkState, msg) -> list:
        if not self._for_us(msg.target_system):
            return []
        if msg.param_index >= 0:
            name = self.params.name_at(msg.param_index)
        else:
            name = _param_name(msg.param_id)
        if name is None or name not in self.params:
            return []
        return [self._param_value(name)]

    def _on_param_request_list(self, link: LinkState, msg) -> None:
        if self._for_us(msg.target_system):
            link.param_queue.extend(range(len(self.params)))

    def _on_param_set(self, link: LinkState, msg) -> list:
        if not self._for_us(msg.target_system):
            return []
        name = _param_name(msg.param_id)
        if name not in self.params:
            self.commander.texts.append(StatusText(3, f"Parameter {name} unknown"))
            return []
        try:
            self.params.set(name, self.params.from_wire(name, msg.param_value, msg.param_type))
        except ValueError:
            return []
        value = self._param_value(name)
        for other in self.links.values():  # PX4 announces a change on every link
            if other is not link:
                other.outbox.append(value)
        return [value]

    # ---- commands ----

    def _ack(self, command: int, result: int, msg) -> mavlink.MAVLink_message:
        return mavlink.MAVLink_command_ack_message(
            command,
            result,
            0,
            0,
            msg.get_srcSystem(),
            msg.get_srcComponent(),
        )

    def _set_mode_from(self, base_mode: float, main: float, sub: float) -> int:
        if not all(math.isfinite(v) for v in (base_mode, main, sub)):
            return mavlink.MAV_RESULT_DENIED
        if not int(base_mode) & mavlink.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED:
            return mavlink.MAV_RESULT_DENIED
        mode = modes.from_main_sub(int(main), int(sub))
        if mode is None:
            return mavlink.MAV_RESULT_TEMPORARILY_REJECTED
        return self.commander.set_mode(mode, self.time_s, self.state)

    def _command(self, link: LinkState, msg, command: int, p: list[float]) -> list:
        now, state, cmd = self.time_s, self.state, self.commander
        replies: list = []
        if command == mavlink.MAV_CMD_COMPONENT_ARM_DISARM:
            force = math.isfinite(p[1]) and int(p[1]) == FORCE_MAGIC
            if p[0] == 1.0:
                result = cmd.arm(now, state, force)
            elif p[0] == 0.0:
                result = cmd.disarm(now, state, force)
            else:
                result = mavlink.MAV_RESULT_DENIED
        elif command == mavlink.MAV_CMD_DO_SET_MODE:
            # PX4 acks twice: its MAVLink receiver at once with ACCEPTED ("received"), then
            # the commander with the real result (a refusal for a mode it cannot enter)
            result = self._set_mode_from(p[0], p[1], p[2])
            return [
                self._ack(command, mavlink.MAV_RESULT_ACCEPTED, msg),
                self._ack(command, result, msg),
            ]
        elif command == mavlink.MAV_CMD_NAV_TAKEOFF:
            altitude = p[6] - self.config.home_alt_m if math.isfinite(p[6]) else math.nan
            result = cmd.takeoff(now, state, altitude)
        elif command == mavlink.MAV_CMD_NAV_LAND:
            result = cmd.set_mode(modes.Mode.LAND, now, state)
        elif command == mavlink.MAV_CMD_NAV_RETURN_TO_LAUNCH:
            result = cmd.set_mode(modes.Mode.RTL, now, state)
        elif command == mavlink.MAV_CMD_DO_SET_MISSION_CURRENT:
            ok = math.isfinite(p[0]) and self.missions.set_current(int(p[0]))
            result = mavlink.MAV_RESULT_ACCEPTED if ok else mavlink.MAV_RESULT_DENIED
            replies.append(self.missions.current_message())
        elif command == mavlink.MAV_CMD_MISSION_START:
            result = cmd.set_mode(modes.Mode.MISSION, now, state)
        elif command == mavlink.MAV_CMD_SET_MESSAGE_INTERVAL:
            ok = math.isfinite(p[0]) and link.scheduler.set_interval(int(p[0]), p[1], now)
            result = mavlink.MAV_RESULT_ACCEPTED if ok else mavlink.MAV_RESULT_FAILED
        elif command == mavlink.MAV_CMD_GET_MESSAGE_INTERVAL:
            msgid = int(p[0]) if math.isfinite(p[0]) else -1
            interval = link.scheduler.interval_us(msgid)
            replies.append(mavlink.MAVLink_message_interval_message(msgid, interval))
            result = mavlink.MAV_RESULT_ACCEPTED
        elif command in (
            mavlink.MAV_CMD_REQUEST_MESSAGE,
            mavlink.MAV_CMD_REQUEST_AUTOPILOT_CAPABILITIES,
        ):
            msgid = telemetry.AUTOPILOT_VERSION
            if command == mavlink.MAV_CMD_REQUEST_MESSAGE:
                msgid = int(p[0]) if math.isfinite(p[0]) else -1
            builder = self._builders.get(msgid)
            result = mavlink.MAV_RESULT_ACCEPTED if builder else mavlink.MAV_RESULT_DENIED
            if builder:
                replies.append(builder())
        elif command == mavlink.MAV_CMD_GET_HOME_POSITION:
            replies.append(self._msg_home_position())
            result = mavlink.MAV_RESULT_ACCEPTED
        else:
            result = mavlink.MAV_RESULT_UNSUPPORTED
        return [self._ack(command, result, msg), *replies]

    # ---- outgoing ----

    def poll(self, ahead_s: float = 0.0) -> dict[str, list[mavlink.MAVLink_message]]:
        """Everything due now on each link: replies queued earlier, status texts (GCS links
        only), the telemetry streams due within ``ahead_s`` (s) and the next chunk of a
        parameter list."""
        texts = self.commander.drain_texts()
        mission_events = self.commander.mission.drain() if self.commander.mission else []
        out: dict[str, list[mavlink.MAVLink_message]] = {}
        now = self.time_s
        for name, link in self.links.items():
            msgs, link.outbox = link.outbox, []
            if texts and now - link.gcs_heartbeat_at <= GCS_HEARTBEAT_TIMEOUT_S:
                for text in texts:
                    msgs.extend(self.statustext(text))
            msgs.extend(mission_events)
            msgs.extend(self.missions.retry(now, name))
            msgs.extend(self._builders[msgid]() for msgid in link.scheduler.due(now, ahead_s))
            for _ in range(min(PARAMS_PER_POLL, len(link.param_queue))):
                name_at = self.params.name_at(link.param_queue.popleft())
                if name_at is not None:
                    msgs.append(self._param_value(name_at))
            out[name] = msgs
        return out

    def statustext(self, text: StatusText) -> list[mavlink.MAVLink_message]:
        """STATUSTEXT message(s) for ``text`` (PX4 ends texts with a tab; > 50 chars are
        chunked with a common non-zero id)."""
        raw = (text.text + "\t").encode("utf-8")
        if len(raw) <= STATUSTEXT_LEN:
            return [mavlink.MAVLink_statustext_message(text.severity, raw, 0, 0)]
        self._statustext_id = self._statustext_id % 65535 + 1
        chunks = [raw[i : i + STATUSTEXT_LEN] for i in range(0, len(raw), STATUSTEXT_LEN)]
        return [
            mavlink.MAVLink_statustext_message(text.severity, chunk, self._statustext_id, i)
            for i, chunk in enumerate(chunks)
        ]

    def _param_value(self, name: str) -> mavlink.MAVLink_message:
        p = self.params
        return mavlink.MAVLink_param_value_message(
            name.encode("ascii"), p.wire_value(name), p.type_of(name), len(p), p.index(name)
        )

    # ---- telemetry builders ----

    @property
    def _boot_ms(self) -> int:
        return int(self.time_s * 1000) & 0xFFFFFFFF

    @property
    def _usec(self) -> int:
        return int(self.time_s * 1e6)

    def local_of(self, lat: float, lon: float) -> tuple[float, float]:
        """Local ENU (x, y) m of latitude/longitude (deg)."""
        cfg = self.config
        north, east = frames.geodetic_to_offset(lat, lon, cfg.home_lat_deg, cfg.home_lon_deg)
        return east, north

    def _acceptance_radius(self) -> float:
        return self.params["NAV_ACC_RAD"]

    def geodetic(self, x: float, y: float) -> tuple[float, float]:
        """Latitude/longitude (deg) of local ENU point (x, y)."""
        cfg = self.config
        return frames.offset_to_geodetic(y, x, cfg.home_lat_deg, cfg.home_lon_deg)

    def msg_heartbeat(self) -> mavlink.MAVLink_message:
        cmd = self.commander
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

    def _msg_sys_status(self):
        b = self.battery
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

    def _msg_battery_status(self):
        b = self.battery
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

    def _euler_ned(self) -> tuple[float, float, float]:
        s = self.state
        return frames.euler_flu_enu_to_frd_ned(s.roll, s.pitch, s.yaw)

    def _msg_attitude(self):
        s = self.state
        roll, pitch, yaw = self._euler_ned()
        p, q, r = frames.rates_flu_to_frd(s.p, s.q, s.r)
        return mavlink.MAVLink_attitude_message(self._boot_ms, roll, pitch, yaw, p, q, r)

    def _msg_attitude_quaternion(self):
        s = self.state
        x, y, z, w = quat_from_rpy(*self._euler_ned())
        p, q, r = frames.rates_flu_to_frd(s.p, s.q, s.r)
        return mavlink.MAVLink_attitude_quaternion_message(
            self._boot_ms, w, x, y, z, p, q, r, [0.0, 0.0, 0.0, 0.0]
        )

    def _msg_local_position_ned(self):
        s = self.state
        n, e, d = frames.enu_to_ned(s.x, s.y, s.z)
        vn, ve, vd = frames.enu_to_ned(s.vx, s.vy, s.vz)
        return mavlink.MAVLink_local_position_ned_message(self._boot_ms, n, e, d, vn, ve, vd)

    def _msg_global_position_int(self):
        s = self.state
        lat, lon = self.geodetic(s.x, s.y)
        vn, ve, vd = frames.enu_to_ned(s.vx, s.vy, s.vz)
        hdg = round(math.degrees(frames.yaw_enu_to_ned(s.yaw)) * 100) % 36000
        return mavlink.MAVLink_global_position_int_message(
            self._boot_ms,
            round(lat * 1e7),
            round(lon * 1e7),
            round((self.config.home_alt_m + s.z) * 1000),
            round((s.z - self.commander.home[2]) * 1000),
            round(vn * 100),
            round(ve * 100),
            round(vd * 100),
            hdg,
        )

    def _msg_gps_raw_int(self):
        s = self.state
        lat, lon = self.geodetic(s.x, s.y)
        speed = math.hypot(s.vx, s.vy)
        cog = round(math.degrees(math.atan2(s.vx, s.vy)) * 100) % 36000 if speed > 0.2 else 0
        alt_mm = round((self.config.home_alt_m + s.z) * 1000)
        return mavlink.MAVLink_gps_raw_int_message(
            self._usec,
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

    def _msg_position_target(self):
        target = self.commander.target
        mask = 0
        pos_ned = frames.enu_to_ned(*target.position)
        for i, bit in enumerate(offboard.IGNORE_POSITION):
            if not math.isfinite(pos_ned[i]):
                mask |= bit
        vel_ned = frames.enu_to_ned(*self.controller.velocity_setpoint)
        mask |= sum(offboard.IGNORE_ACCELERATION)
        yaw = frames.yaw_enu_to_ned(target.yaw) if math.isfinite(target.yaw) else math.nan
        if not math.isfinite(yaw):
            mask |= mavlink.POSITION_TARGET_TYPEMASK_YAW_IGNORE
        yaw_rate = -target.yaw_rate if math.isfinite(target.yaw_rate) else math.nan
        if not math.isfinite(yaw_rate):
            mask |= mavlink.POSITION_TARGET_TYPEMASK_YAW_RATE_IGNORE
        return mavlink.MAVLink_position_target_local_ned_message(
            self._boot_ms,
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

    def _msg_vfr_hud(self):
        s = self.state
        w = self.wind_enu
        heading = round(math.degrees(frames.yaw_enu_to_ned(s.yaw))) % 360
        throttle = round(100 * s.thrust / self.quad.max_thrust_accel)
        airspeed = math.hypot(s.vx - w[0], s.vy - w[1])
        return mavlink.MAVLink_vfr_hud_message(
            airspeed,
            math.hypot(s.vx, s.vy),
            heading,
            throttle,
            self.config.home_alt_m + s.z,
            s.vz,
        )

    def _msg_altitude(self):
        s = self.state
        amsl = self.config.home_alt_m + s.z
        return mavlink.MAVLink_altitude_message(
            self._usec, amsl, amsl, s.z, s.z - self.commander.home[2], math.nan, s.z
        )

    def _msg_home_position(self):
        hx, hy, hz = self.commander.home
        lat, lon = self.geodetic(hx, hy)
        n, e, d = frames.enu_to_ned(hx, hy, hz)
        yaw = frames.yaw_enu_to_ned(self.commander.home_yaw)
        q = [math.cos(yaw / 2), 0.0, 0.0, math.sin(yaw / 2)]
        return mavlink.MAVLink_home_position_message(
            round(lat * 1e7),
            round(lon * 1e7),
            round((self.config.home_alt_m + hz) * 1000),
            n,
            e,
            d,
            q,
            0.0,
            0.0,
            0.0,
            self._usec,
        )

    def _msg_extended_sys_state(self):
        return mavlink.MAVLink_extended_sys_state_message(0, int(self.commander.landed_state))

    def _msg_autopilot_version(self):
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
            self.sysid,
        )


def _gains(params: ParamStore, hover: float, max_thrust: float) -> Gains:
    return Gains(
        xy_p=params["MPC_XY_P"],
        z_p=params["MPC_Z_P"],
        vel_xy_p=params["MPC_XY_VEL_P_ACC"],
        vel_xy_i=params["MPC_XY_VEL_I_ACC"],
        vel_z_p=params["MPC_Z_VEL_P_ACC"],
        vel_z_i=params["MPC_Z_VEL_I_ACC"],
        yaw_p=params["MPC_YAW_P"],
        max_tilt_rad=math.radians(params["MPC_TILTMAX_AIR"]),
        hover_thrust=hover,
        max_thrust=max_thrust,
    )
