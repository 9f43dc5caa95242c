"""The PX4-like vehicle: MAVLink messages in, MAVLink messages out, physics in between.

``Autopilot`` is pure (no sockets, no clock): the caller advances simulated time with
:meth:`Autopilot.step`, hands it every decoded MAVLink message with :meth:`Autopilot.handle`
(which returns the immediate replies for that link), and collects the telemetry, status texts
and parameter lists due on each link with :meth:`Autopilot.poll`. Links are named (``onboard``,
``gcs``); STATUSTEXT goes only to links where a MAV_TYPE_GCS heartbeat was seen in the last
few seconds, as PX4 does.

One handler per MAVLink message PX4 answers, beside the state it changes; physics, the
commander, the parameters and the messages PX4 sends (:mod:`.messages`) are their own modules.
"""

from __future__ import annotations

import logging
import math
from collections import deque
from dataclasses import dataclass, field
from functools import partial

from pymavlink.dialects.v20 import common as mavlink

from dronewrapper_sim import frames
from dronewrapper_sim.battery import Battery, motor_current
from dronewrapper_sim.dynamics import GRAVITY, QuadParams, QuadState, WindModel, step
from dronewrapper_sim.px4 import messages, modes, offboard, telemetry
from dronewrapper_sim.px4.commander import FORCE_MAGIC, Commander, StatusText
from dronewrapper_sim.px4.flight_control import Gains, PositionController
from dronewrapper_sim.px4.geofence import Geofence
from dronewrapper_sim.px4.mission import RALLY, MissionRunner, MissionStore
from dronewrapper_sim.px4.params import ParamStore

log = logging.getLogger("sim.autopilot")

GCS_HEARTBEAT_TIMEOUT_S = 3.0
PARAMS_PER_POLL = 20


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
        self._builders = {msgid: partial(build, self) for msgid, build in messages.BUILDERS.items()}

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
            self.controller.gains = Gains.from_params(
                self.params, GRAVITY, self.quad.max_thrust_accel
            )
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
        ack = messages.command_ack(mavlink.MAV_CMD_DO_SET_MODE, result, msg)
        return [ack, messages.command_ack(mavlink.MAV_CMD_DO_SET_MODE, result, msg)]

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
            name = messages.param_name(msg.param_id)
        if name is None or name not in self.params:
            return []
        return [self._param_value(name)]

    def _on_param_request_list(self, link: LinkState, msg) -> None:
        if self._for_us(msg.target_system):
            link.param_queue.extend(range(len(self.params)))

    def _on_param_set(self, link: LinkState, msg) -> list:
        if not self._for_us(msg.target_system):
            return []
        name = messages.param_name(msg.param_id)
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
                messages.command_ack(command, mavlink.MAV_RESULT_ACCEPTED, msg),
                messages.command_ack(command, result, msg),
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
            replies.append(messages.home_position(self))
            result = mavlink.MAV_RESULT_ACCEPTED
        else:
            result = mavlink.MAV_RESULT_UNSUPPORTED
        return [messages.command_ack(command, result, msg), *replies]

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
        """STATUSTEXT message(s) for ``text`` (chunked texts get the next non-zero id)."""
        if messages.needs_chunks(text):
            self._statustext_id = self._statustext_id % 65535 + 1
        return messages.statustext(text, self._statustext_id)

    def _param_value(self, name: str) -> mavlink.MAVLink_message:
        return messages.param_value(self.params, name)

    # ---- the local frame ----

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
