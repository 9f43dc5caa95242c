"""The bridge process: MAVLink autopilot <-> MAVROS-equivalent Zenoh keys (see README.md).

Threads: a receive loop (MAVLink -> telemetry keys, acks, params), a stream loop at
``stream_rate_hz`` (failsafe decisions, setpoint forwarding, GCS heartbeat, periodic state
publication, link supervision), Zenoh callbacks (setpoints are validated and forwarded at once)
and the Node's service workers (commands wait for their COMMAND_ACK).
"""

from __future__ import annotations

import collections
import logging
import math
import sys
import threading
import time
from typing import Any, ClassVar

import msgspec

from dronewrapper.msgs import registry
from dronewrapper.msgs.mavros import (
    LANDED_STATE_IN_AIR,
    SEVERITY_WARNING,
    CommandBool,
    CommandBoolResult,
    CommandTOL,
    CommandTOLResult,
    ExtendedState,
    ParamGet,
    ParamGetResult,
    ParamSet,
    ParamSetResult,
    ParamValue,
    PositionTarget,
    SetMode,
    SetModeResult,
    State,
    StatusText,
)
from dronewrapper.msgs.sensor import BatteryState
from dronewrapper.msgs.std import Header
from dronewrapper.runtime import Node, Ratekeeper, ServiceError
from dronewrapper.security.guard import CommandGuard
from dronewrapper_bridge_mavlink import commands as cmds
from dronewrapper_bridge_mavlink import param_values
from dronewrapper_bridge_mavlink.failsafe import Failsafe, FailsafeConfig, Tick, is_airborne
from dronewrapper_bridge_mavlink.frames import yaw_enu_to_ned
from dronewrapper_bridge_mavlink.freshness import Freshness, boot_ms_of
from dronewrapper_bridge_mavlink.gcs import GcsForwarder, is_loopback, parse_gcs_url
from dronewrapper_bridge_mavlink.link import MavLink, mavutil, network_exposure
from dronewrapper_bridge_mavlink.link_gap import gap_report
from dronewrapper_bridge_mavlink.modes import (
    AUTOPILOT_ARDUPILOT,
    AUTOPILOT_PX4,
    GUIDED_MODE,
    HOLD_MODE,
    LAND_MODE,
    RETURN_MODE,
    canonical_mode,
    is_guided,
    set_mode_params,
)
from dronewrapper_bridge_mavlink.setpoints import Limits, SetpointError, to_local_ned, validate
from dronewrapper_bridge_mavlink.sources import AutopilotSources
from dronewrapper_bridge_mavlink.telemetry import (
    StatusTextAssembler,
    Telemetry,
    battery_from_battery_status,
    battery_from_sys_status,
    extended_state,
    is_autopilot_heartbeat,
    non_finite_field,
    state_from_heartbeat,
)

log = logging.getLogger("bridge_mavlink")

MAV_TYPE_GCS = 6
MAV_AUTOPILOT_INVALID = 8
MAV_STATE_ACTIVE = 4

DEFAULT_MESSAGE_RATES = {
    "LOCAL_POSITION_NED": 50.0,
    "ATTITUDE_QUATERNION": 50.0,
    "GLOBAL_POSITION_INT": 10.0,
    "EXTENDED_SYS_STATE": 5.0,
    "SYS_STATUS": 2.0,
    "BATTERY_STATUS": 1.0,
    "GPS_RAW_INT": 2.0,
    "HOME_POSITION": 0.5,
}


class LimitsConfig(msgspec.Struct, kw_only=True, forbid_unknown_fields=True):
    """Setpoint bounds (see setpoints.Limits): m, m/s, rad/s."""

    max_distance: float = 10_000.0
    min_altitude: float = -1_000.0
    max_altitude: float = 10_000.0
    max_horizontal_speed: float = 20.0
    max_vertical_speed: float = 10.0
    max_yaw_rate: float = 2.0 * math.pi
    mixed_altitude_gain: float = 1.0
    mixed_max_climb: float = 1.5


class Config(msgspec.Struct, kw_only=True, forbid_unknown_fields=True):
    """bridge_mavlink configuration (units in the names' docs; see README.md)."""

    connection: str = "udpin:127.0.0.1:14540"  # pymavlink URL; loopback unless set otherwise
    baud: int = 57600  # serial only
    source_system: int = 255  # our MAVLink system id
    source_component: int = 191  # our MAVLink component id (onboard computer; QGC is 190)
    heartbeat_type: int = MAV_TYPE_GCS  # MAV_TYPE of our heartbeat (GCS: PX4 sends STATUSTEXT)
    target_system: int = 0  # autopilot system id; 0 = the first autopilot heard
    target_component: int = 1
    heartbeat_timeout: float = 3.0  # s without heartbeat -> State.connected false
    stream_rate_hz: float = 30.0  # own setpoint stream rate while commanded
    offboard_prime_s: float = 1.2  # s of streaming before asking for OFFBOARD
    final_ack_timeout: float = 1.0  # s to wait for PX4's second (real) DO_SET_MODE ack
    mode_confirm_timeout: float = 2.5  # s for HEARTBEAT to show a mode acked only once
    setpoint_timeout: float = 0.5  # s: velocity commands expire -> hold
    commander_lost_timeout: float = 5.0  # s: no setpoint while airborne -> action
    commander_lost_action: str = "land"  # hold | land | return
    command_attempts: int = 5  # sends of a COMMAND_LONG before giving up
    command_ack_timeout: float = 0.6  # s to wait for each COMMAND_ACK
    param_attempts: int = 5
    param_timeout: float = 0.6  # s per PARAM_REQUEST_READ / PARAM_SET attempt
    reason_wait: float = 0.5  # s to wait for a STATUSTEXT explaining a refusal
    state_rate_hz: float = 2.0  # periodic State (also on change)
    extended_state_rate_hz: float = 4.0  # periodic ExtendedState (also on change)
    battery_rate_hz: float = 2.0
    global_position_max_hz: float = 10.0
    message_rates: dict[str, float] = msgspec.field(
        default_factory=lambda: dict(DEFAULT_MESSAGE_RATES)
    )  # Hz asked with SET_MESSAGE_INTERVAL
    limits: LimitsConfig = msgspec.field(default_factory=LimitsConfig)
    command_lease: bool = False  # obey one commander at a time (security.lease)
    command_lease_ttl_s: float = 10.0  # s: a silent holder loses the lease
    signing_key_file: str = ""  # MAVLink 2 signing key (dronewrapper keys mavlink); "" = off
    gcs_url: str = ""  # udp:HOST:PORT of a ground station (QGC 14550) to forward MAVLink to
    gcs_over_zenoh: bool = False  # also forward on {ns}/mavlink/* (dronewrapper mavlink-forward)

    def __post_init__(self) -> None:
        if self.commander_lost_action not in ("hold", "land", "return"):
            raise ValueError(
                f"commander_lost_action must be hold, land or return, "
                f"got {self.commander_lost_action!r}"
            )
        if not 0 < self.setpoint_timeout < self.commander_lost_timeout:
            raise ValueError("need 0 < setpoint_timeout < commander_lost_timeout")
        if self.stream_rate_hz < 20.0:
            raise ValueError(f"stream_rate_hz must be >= 20 (contract), got {self.stream_rate_hz}")
        for name in ("state_rate_hz", "extended_state_rate_hz", "battery_rate_hz"):
            if not getattr(self, name) > 0:
                raise ValueError(f"{name} must be > 0")
        if self.command_attempts < 1 or self.param_attempts < 1:
            raise ValueError("command_attempts and param_attempts must be >= 1")
        if self.gcs_url:
            parse_gcs_url(self.gcs_url)  # raises ValueError naming the expected form
        for name in ("final_ack_timeout", "mode_confirm_timeout"):
            if not 0 < getattr(self, name) <= 30:
                raise ValueError(f"{name} must be in (0, 30] s, got {getattr(self, name)!r}")


class Bridge:
    """Everything the bridge does, wired to one Node and one MAVLink link."""

    def __init__(self, node: Node, config: Config, link: MavLink | None = None) -> None:
        self.node = node
        self.config = config
        self.gcs: GcsForwarder | None = None  # ground-station forwarding, made at start()
        self.link = link or MavLink(
            config.connection,
            baud=config.baud,
            source_system=config.source_system,
            source_component=config.source_component,
            signing_key_file=config.signing_key_file,
        )
        self.guard = CommandGuard(
            enabled=config.command_lease,
            ttl_s=config.command_lease_ttl_s,
            on_change=lambda: self.publish_state(force=True),
        )
        self.limits = Limits(**msgspec.structs.asdict(config.limits))
        self.failsafe = Failsafe(
            FailsafeConfig(
                setpoint_timeout=config.setpoint_timeout,
                commander_lost_timeout=config.commander_lost_timeout,
                commander_lost_action=config.commander_lost_action,
            )
        )
        self.telemetry = Telemetry()
        self.freshness = Freshness()
        self.sources = AutopilotSources()
        self.statustexts = StatusTextAssembler()
        self.acks = cmds.AckRouter()
        self._lock = threading.RLock()  # telemetry, failsafe, state
        self._ack_cond = threading.Condition()
        self._cmd_lock = threading.Lock()
        self._param_cond = threading.Condition()
        self._params: dict[str, tuple[float, int, float]] = {}  # id -> (raw, type, monotonic)
        self._recent_texts: collections.deque[tuple[float, StatusText]] = collections.deque(
            maxlen=32
        )
        self.autopilot = ""
        self.target_system = config.target_system
        self.target_component = config.target_component
        self.connected = False
        self._last_heartbeat = -math.inf
        self._heartbeat_state: State | None = None
        self._ext = ExtendedState()
        self._battery: BatteryState | None = None
        self._last_state_key: tuple | None = None
        self._last_state_pub = -math.inf
        self._last_ext_pub = -math.inf
        self._last_battery_pub = -math.inf
        self._last_global_pub = -math.inf
        self._last_send = -math.inf
        self._stream_since = -math.inf
        self._rates_round = 0
        self._next_rates = math.inf
        self.rejected_setpoints = 0
        self._last_reject_log = -math.inf
        self.setpoints_sent = 0
        self.messages_received = 0

        self.pub_state = node.publisher(registry.STATE)
        self.pub_ext = node.publisher(registry.EXTENDED_STATE)
        self.pub_pose = node.publisher(registry.LOCAL_POSE)
        self.pub_vbody = node.publisher(registry.VELOCITY_BODY)
        self.pub_vlocal = node.publisher(registry.VELOCITY_LOCAL)
        self.pub_global = node.publisher(registry.GLOBAL_POSITION)
        self.pub_battery = node.publisher(registry.BATTERY)
        self.pub_text = node.publisher(registry.STATUSTEXT)

    # ------------------------------------------------------------------ lifecycle

    def start(self) -> list[threading.Thread]:
        """Open the link, subscribe, serve, and start the loops (returns the threads)."""
        self._open_link()
        self.node.subscribe(registry.SETPOINT_RAW_LOCAL, self.on_setpoint)
        self.node.serve(registry.ARMING, self.handle_arming)
        self.node.serve(registry.TAKEOFF, self.handle_takeoff)
        self.node.serve(registry.LAND, self.handle_land)
        self.node.serve(registry.SET_MODE, self.handle_set_mode)
        self.node.serve(registry.PARAM_GET, self.handle_param_get)
        self.node.serve(registry.PARAM_SET, self.handle_param_set)
        self.guard.serve(self.node)
        threads = [
            threading.Thread(target=self._receive_loop, name="mavlink-rx", daemon=True),
            threading.Thread(target=self._stream_loop, name="stream", daemon=True),
        ]
        self.gcs = self._make_gcs_forwarder()
        if self.gcs is not None:
            threads.append(
                threading.Thread(
                    target=self.gcs.run, args=(self.node.stop_event,), name="gcs", daemon=True
                )
            )
        for thread in threads:
            thread.start()
        self.publish_state(force=True)
        return threads

    def _make_gcs_forwarder(self) -> GcsForwarder | None:
        """The ground-station forwarder of ``gcs_url`` / ``gcs_over_zenoh``, or None."""
        address = parse_gcs_url(self.config.gcs_url) if self.config.gcs_url else None
        if address is None and not self.config.gcs_over_zenoh:
            return None
        publish = None
        if self.config.gcs_over_zenoh:
            publisher = self.node.publisher(registry.MAVLINK_FROM_AUTOPILOT)
            publish = publisher.put
        forwarder = GcsForwarder(self.link.write_raw, address, publish)
        if self.config.gcs_over_zenoh:
            self.node.subscribe(registry.MAVLINK_TO_AUTOPILOT, forwarder.from_zenoh)
        if address is not None and not is_loopback(address[0]):
            log.warning(
                "forwarding the autopilot's MAVLink to %s beyond loopback: anyone there can "
                "command the autopilot unless MAVLink signing is on",
                self.config.gcs_url,
            )
        log.info(
            "ground-station forwarding: %s%s",
            self.config.gcs_url or "no UDP",
            ", and over Zenoh" if self.config.gcs_over_zenoh else "",
        )
        return forwarder

    def _open_link(self) -> bool:
        try:
            self.link.open()
        except (OSError, ValueError) as exc:
            log.warning("cannot open %s: %s (retrying)", self.config.connection, exc)
            self.link.close()
            return False
        log.info("MAVLink link open on %s", self.config.connection)
        return True

    # ------------------------------------------------------------------ receive side

    def _receive_loop(self) -> None:
        stop = self.node.stop_event
        while not stop.is_set():
            if not self.link.is_open:
                if not self._open_link():
                    stop.wait(1.0)
                continue
            try:
                msg = self.link.recv(0.1)
            except (OSError, ValueError) as exc:  # serial unplugged, socket error ...
                log.warning("link error on %s: %s; reopening", self.config.connection, exc)
                self.link.close()
                stop.wait(1.0)
                continue
            if msg is None:
                continue
            if self.gcs is not None and msg.get_type() != "BAD_DATA":
                self.gcs.from_autopilot(bytes(msg.get_msgbuf()))
            try:
                self.handle_mavlink(msg, time.time(), time.monotonic(), self.link.last_source)
            except Exception:
                self.node.callback_errors["mavlink"] += 1
                log.exception("error handling %s", msg.get_type())

    def handle_mavlink(self, msg: Any, stamp: float, now: float, source: Any = None) -> None:
        """Dispatch one received MAVLink message (``stamp`` wall s, ``now`` monotonic s,
        ``source`` the UDP address it came from, None when unknown)."""
        kind = msg.get_type()
        if kind == "BAD_DATA":
            return
        self.messages_received += 1
        if not self._admit(msg, kind, source, now):
            return
        if kind == "HEARTBEAT":
            with self._lock:
                was_connected, before = self.connected, self._heartbeat_state
                lost_at = self._last_heartbeat
            self._on_heartbeat(msg, stamp, now)
            if not was_connected and self.connected:
                self._report_link_gap(before, now - lost_at, now)
            return
        if self.target_system and msg.get_srcSystem() != self.target_system:
            return
        handler = self._HANDLERS.get(kind)
        if handler is not None:
            handler(self, msg, stamp, now)

    def _admit(self, msg: Any, kind: str, source: Any, now: float) -> bool:
        """False for a message to drop: from a second autopilot with the same system id, a
        duplicated datagram, or one older than what was already used (seq / time_boot_ms)."""
        system = msg.get_srcSystem()
        verdict = self.sources.check(source, system, now)
        if verdict.flag:
            self._bridge_text(verdict.flag, now)
        if not verdict.accept:
            return False
        if source is not None and system == self.target_system:
            self.link.peer = self.sources.owner(system)
        fresh = self.freshness.check(
            source,
            system,
            msg.get_srcComponent(),
            msg.get_seq(),
            kind,
            boot_ms_of(msg),
            now,
            bytes(msg.get_msgbuf() or b""),
        )
        if not fresh.new:
            log.debug("dropped %s: %s", kind, fresh.reason)
            return False
        bad_field = non_finite_field(kind, msg)
        if bad_field is not None:
            self.node.callback_errors["mavlink non-finite"] += 1
            log.debug("dropped %s", bad_field)
            return False
        return True

    def _report_link_gap(self, before: State | None, gap_s: float, now: float) -> None:
        """After a link gap, report what the autopilot changed meanwhile (a failsafe)."""
        with self._lock:
            after = self._heartbeat_state
        if after is None:
            return
        report = gap_report(before, after, gap_s)
        if report is not None:
            self._bridge_text(report, now)

    def _bridge_text(self, text: str, now: float) -> None:
        """Log and publish a warning of the bridge's own (STATUSTEXT, frame_id ``bridge``)."""
        log.warning("%s", text)
        self._publish_text(
            StatusText(
                header=Header(stamp=time.time(), frame_id="bridge"),
                severity=SEVERITY_WARNING,
                text=f"bridge: {text}",
            ),
            now,
        )

    def _on_heartbeat(self, msg: Any, stamp: float, now: float) -> None:
        if not is_autopilot_heartbeat(msg):
            return
        if self.target_system and msg.get_srcSystem() != self.target_system:
            return
        with self._lock:
            if not self.target_system:
                self.target_system = msg.get_srcSystem()
                self.target_component = msg.get_srcComponent()
            self._last_heartbeat = now
            state = state_from_heartbeat(msg, stamp, failsafe=self.failsafe.state)
            if state.autopilot != self.autopilot:
                self.autopilot = state.autopilot
                log.info(
                    "autopilot %s (system %d, component %d)",
                    self.autopilot,
                    self.target_system,
                    self.target_component,
                )
            reconnected = not self.connected
            self.connected = True
            self._heartbeat_state = state
            self._update_failsafe_vehicle(now)
        if reconnected:
            log.info("connected to the autopilot (mode %s)", state.mode)
            self._rates_round = 0
            self._next_rates = now
        self.publish_state()

    def _update_failsafe_vehicle(self, now: float) -> None:
        hb = self._heartbeat_state
        if hb is None:
            return
        airborne = is_airborne(self._ext.landed_state, hb.armed)
        self.failsafe.on_vehicle(mode=hb.mode, armed=hb.armed, airborne=airborne, now=now)
        self._report(self.failsafe.tick(now, self._pose()), now, send=False)

    def _on_attitude(self, msg: Any, stamp: float, now: float) -> None:
        with self._lock:
            self.telemetry.on_attitude(msg)

    def _on_attitude_quaternion(self, msg: Any, stamp: float, now: float) -> None:
        with self._lock:
            self.telemetry.on_attitude_quaternion(msg)

    def _on_local_position(self, msg: Any, stamp: float, now: float) -> None:
        with self._lock:
            pose, local, body = self.telemetry.on_local_position(msg, stamp)
        self.pub_pose.put(pose)
        self.pub_vlocal.put(local)
        self.pub_vbody.put(body)

    def _on_global_position(self, msg: Any, stamp: float, now: float) -> None:
        with self._lock:
            fix = self.telemetry.on_global_position(msg, stamp)
        max_hz = self.config.global_position_max_hz
        if fix is not None and (max_hz <= 0 or now - self._last_global_pub >= 0.9 / max_hz):
            self._last_global_pub = now
            self.pub_global.put(fix)

    def _on_gps_raw(self, msg: Any, stamp: float, now: float) -> None:
        self.telemetry.on_gps_raw(msg)

    def _on_home_position(self, msg: Any, stamp: float, now: float) -> None:
        self.telemetry.on_home_position(msg)

    def _on_extended_sys_state(self, msg: Any, stamp: float, now: float) -> None:
        ext = extended_state(msg, stamp)
        with self._lock:
            changed = (ext.landed_state, ext.vtol_state) != (
                self._ext.landed_state,
                self._ext.vtol_state,
            )
            self._ext = ext
            if changed:
                self._update_failsafe_vehicle(now)
        if changed:
            self._last_ext_pub = now
            self.pub_ext.put(ext)

    def _on_sys_status(self, msg: Any, stamp: float, now: float) -> None:
        battery = battery_from_sys_status(msg, stamp)
        if (
            self._battery is None
            or math.isnan(self._battery.percentage)
            or (not math.isnan(battery.percentage))
        ):
            self._battery = battery

    def _on_battery_status(self, msg: Any, stamp: float, now: float) -> None:
        if msg.id == 0:
            self._battery = battery_from_battery_status(msg, stamp)

    def _on_statustext(self, msg: Any, stamp: float, now: float) -> None:
        for text in self.statustexts.add(msg, stamp, now):
            self._publish_text(text, now)

    def _publish_text(self, text: StatusText, now: float) -> None:
        if not text.header.stamp:
            text.header.stamp = time.time()
        self._recent_texts.append((now, text))
        log.info("autopilot says [%d]: %s", text.severity, text.text)
        self.pub_text.put(text)

    def _on_command_ack(self, msg: Any, stamp: float, now: float) -> None:
        target = (getattr(msg, "target_system", 0), getattr(msg, "target_component", 0))
        ours = (self.config.source_system, self.config.source_component)
        if target != (0, 0) and target != ours:
            return  # the answer to a ground station's command (forwarded), not to ours
        with self._ack_cond:
            outcome = self.acks.on_ack(int(msg.command), int(msg.result), now)
            self._ack_cond.notify_all()
        log.debug(
            "COMMAND_ACK %s %s (%s)",
            cmds.command_name(msg.command),
            cmds.result_name(msg.result),
            outcome,
        )

    def _on_param_value(self, msg: Any, stamp: float, now: float) -> None:
        param_id = msg.param_id
        if isinstance(param_id, bytes | bytearray):
            param_id = bytes(param_id).decode("ascii", "replace")
        param_id = param_id.split("\x00", 1)[0]
        with self._param_cond:
            self._params[param_id] = (float(msg.param_value), int(msg.param_type), now)
            self._param_cond.notify_all()

    _HANDLERS: ClassVar[dict[str, Any]] = {
        "ATTITUDE": _on_attitude,
        "ATTITUDE_QUATERNION": _on_attitude_quaternion,
        "LOCAL_POSITION_NED": _on_local_position,
        "GLOBAL_POSITION_INT": _on_global_position,
        "GPS_RAW_INT": _on_gps_raw,
        "HOME_POSITION": _on_home_position,
        "EXTENDED_SYS_STATE": _on_extended_sys_state,
        "SYS_STATUS": _on_sys_status,
        "BATTERY_STATUS": _on_battery_status,
        "STATUSTEXT": _on_statustext,
        "COMMAND_ACK": _on_command_ack,
        "PARAM_VALUE": _on_param_value,
    }

    # ------------------------------------------------------------------ state publication

    def current_state(self) -> State:
        """State as published now (connected, mode, armed, failsafe ...)."""
        with self._lock:
            hb = self._heartbeat_state
            state = msgspec.structs.replace(hb) if hb is not None else State()
            state.header = Header.now()
            state.connected = self.connected
            state.failsafe = self.failsafe.state
            state.commander = self.guard.holder()
            return state

    def publish_state(self, *, force: bool = False) -> None:
        """Publish State if it changed (or ``force``, or the periodic time has come)."""
        state = self.current_state()
        key = (
            state.connected,
            state.armed,
            state.guided,
            state.manual_input,
            state.mode,
            state.system_status,
            state.autopilot,
            state.failsafe,
            state.commander,
        )
        now = time.monotonic()
        with self._lock:
            due = now - self._last_state_pub >= 1.0 / self.config.state_rate_hz
            if not (force or due or key != self._last_state_key):
                return
            self._last_state_key = key
            self._last_state_pub = now
        self.pub_state.put(state)

    def _periodic(self, now: float) -> None:
        if self.connected and now - self._last_heartbeat > self.config.heartbeat_timeout:
            with self._lock:
                self.connected = False
            log.warning(
                "no heartbeat for %.1f s: autopilot disconnected", now - self._last_heartbeat
            )
        self.publish_state()
        if now - self._last_ext_pub >= 1.0 / self.config.extended_state_rate_hz:
            self._last_ext_pub = now
            ext = msgspec.structs.replace(self._ext, header=Header.now())
            self.pub_ext.put(ext)
        if (
            self._battery is not None
            and now - self._last_battery_pub >= 1.0 / self.config.battery_rate_hz
        ):
            self._last_battery_pub = now
            self.pub_battery.put(msgspec.structs.replace(self._battery, header=Header.now()))
        for text in self.statustexts.flush(now, stamp=time.time()):
            self._publish_text(text, now)
        if now >= self._next_rates and self.connected:
            self._request_message_rates()
            self._rates_round += 1
            self._next_rates = now + 2.0 if self._rates_round < 3 else math.inf

    def _request_message_rates(self) -> None:
        """Ask for the message rates we need (fire and forget: re-sent 3 times)."""
        mavlink = self.link
        for name, hz in self.config.message_rates.items():
            msg_id = getattr(mavutil.mavlink, f"MAVLINK_MSG_ID_{name}", None)
            if msg_id is None or hz <= 0:
                continue
            mavlink.send(
                "command_long",
                self.target_system or 1,
                self.target_component,
                cmds.MAV_CMD_SET_MESSAGE_INTERVAL,
                0,
                float(msg_id),
                1e6 / hz,
                0,
                0,
                0,
                0,
                0,
            )

    # ------------------------------------------------------------------ setpoints

    def on_setpoint(self, target: PositionTarget) -> None:
        """A PositionTarget from a commander: validate, remember, forward at once."""
        if not self.guard.admit_setpoint():
            return
        now = time.monotonic()
        try:
            kind = validate(target, self.limits)
        except SetpointError as exc:
            self.rejected_setpoints += 1
            if now - self._last_reject_log >= 2.0:
                self._last_reject_log = now
                log.warning("setpoint refused (%d so far): %s", self.rejected_setpoints, exc)
            return
        with self._lock:
            self.failsafe.on_setpoint(target, kind, now)
            tick = self.failsafe.tick(now, self._pose())
        self._report(tick, now, send=True)

    def _pose(self) -> tuple[tuple[float, float, float], float] | None:
        position = self.telemetry.position_enu
        if position is None:
            return None
        return (position, self.telemetry.yaw_enu)

    def _report(self, tick: Tick, now: float, *, send: bool) -> None:
        """Act on a failsafe tick: log and publish transitions, send, issue requests."""
        for transition in tick.transitions:
            log.warning("failsafe %r -> %r: %s", transition.old, transition.new, transition.reason)
        for event in tick.events:
            log.warning("%s", event)
            self._publish_text(
                StatusText(
                    header=Header(stamp=time.time(), frame_id="bridge"),
                    severity=SEVERITY_WARNING,
                    text=f"bridge: {event}",
                ),
                now,
            )
        if tick.transitions:
            self.publish_state()
        if send and tick.send is not None:
            self._send_setpoint(tick.send, now)
        if tick.request:
            threading.Thread(
                target=self._failsafe_request, args=(tick.request,), daemon=True
            ).start()

    def _send_setpoint(self, target: PositionTarget, now: float) -> None:
        with self._lock:
            yaw = self.telemetry.yaw_enu
            position = self.telemetry.position_enu
            z = position[2] if position is not None else 0.0
            autopilot = self.autopilot or AUTOPILOT_PX4
        try:
            ned = to_local_ned(
                target, autopilot=autopilot, yaw_enu=yaw, z_enu=z, limits=self.limits
            )
        except SetpointError as exc:  # cannot happen for validated targets; never crash
            log.error("setpoint conversion failed: %s", exc)
            return
        sent = self.link.send(
            "set_position_target_local_ned",
            self.link.time_boot_ms(),
            self.target_system or 1,
            self.target_component,
            ned.coordinate_frame,
            ned.type_mask,
            ned.x,
            ned.y,
            ned.z,
            ned.vx,
            ned.vy,
            ned.vz,
            0.0,
            0.0,
            0.0,
            ned.yaw,
            ned.yaw_rate,
        )
        if sent:
            self.setpoints_sent += 1
            if now - self._last_send > 0.5:
                self._stream_since = now
            self._last_send = now

    def streamed_for(self, now: float) -> float:
        """Seconds the bridge has been streaming setpoints without a gap (0 if not now)."""
        if now - self._last_send > 0.5:
            return 0.0
        return now - self._stream_since

    def _failsafe_request(self, action: str) -> None:
        autopilot = self.autopilot or AUTOPILOT_PX4
        mode = LAND_MODE[autopilot] if action == "land" else RETURN_MODE[autopilot]
        self.failsafe_mode_requested(mode)
        if action == "land":
            result, message = self.command(
                cmds.MAV_CMD_NAV_LAND, 0, 0, 0, math.nan, math.nan, math.nan, math.nan
            )
        else:
            result, message = self.command(cmds.MAV_CMD_NAV_RETURN_TO_LAUNCH)
        if result == cmds.MAV_RESULT_ACCEPTED:
            self._mode_entered(mode)
            log.warning("failsafe %s: accepted by the autopilot", action)
        else:
            log.error("failsafe %s refused: %s", action, message)

    def failsafe_mode_requested(self, mode: str) -> None:
        with self._lock:
            self.failsafe.on_mode_requested(mode, time.monotonic())

    def _stream_loop(self) -> None:
        rate = Ratekeeper(self.config.stream_rate_hz, stop=self.node.stop_event)
        period = 1.0 / self.config.stream_rate_hz
        next_heartbeat = 0.0
        while rate.sleep():
            now = time.monotonic()
            try:
                if now >= next_heartbeat:
                    next_heartbeat = now + 1.0
                    self.link.send(
                        "heartbeat",
                        self.config.heartbeat_type,
                        MAV_AUTOPILOT_INVALID,
                        0,
                        0,
                        MAV_STATE_ACTIVE,
                    )
                with self._lock:
                    tick = self.failsafe.tick(now, self._pose())
                if now - self._last_send < 0.5 * period:
                    tick.send = None  # just forwarded by the subscriber
                self._report(tick, now, send=self.connected)
                self._periodic(now)
            except Exception:
                self.node.callback_errors["stream"] += 1
                log.exception("stream loop error")

    # ------------------------------------------------------------------ commands

    def _require_connected(self) -> str:
        if not self.connected:
            raise ServiceError("the autopilot is not connected (no heartbeat)", "unavailable")
        return self.autopilot or AUTOPILOT_PX4

    def command(self, command: int, *params: float, attempts: int | None = None) -> tuple[int, str]:
        """Send a COMMAND_LONG and wait for its ack; returns (MAV_RESULT, explanation)."""
        pending, message = self.command_exchange(command, *params, attempts=attempts)
        return pending.result, message

    def command_exchange(
        self,
        command: int,
        *params: float,
        attempts: int | None = None,
        expected_acks: int = 1,
    ) -> tuple[cmds.PendingCommand, str]:
        """Send a COMMAND_LONG and wait for its final ack (the second of ``expected_acks`` = 2,
        see commands.py); returns the finished command and an explanation (the autopilot's
        STATUSTEXT reason for a refusal)."""
        pending = cmds.PendingCommand(
            cmds.command_long(command, *params),
            attempts=attempts or self.config.command_attempts,
            ack_timeout=self.config.command_ack_timeout,
            expected_acks=expected_acks,
            final_ack_timeout=self.config.final_ack_timeout,
        )
        name = cmds.command_name(command)
        with self._cmd_lock:
            with self._ack_cond:
                quiet = self.acks.quiet_until(command) - time.monotonic()
            if quiet > 0:
                time.sleep(quiet)
            started = time.monotonic()
            with self._ack_cond:
                self.acks.register(pending)
                try:
                    while not self.node.stop_event.is_set():
                        now = time.monotonic()
                        msg = pending.due(now)
                        if msg is not None:
                            self.link.send(
                                "command_long",
                                self.target_system or 1,
                                self.target_component,
                                msg.command,
                                msg.confirmation,
                                *msg.params,
                            )
                        if pending.finished(now):
                            break
                        self._ack_cond.wait(max(0.005, pending.wake_at(now) - now))
                finally:
                    self.acks.release(pending, time.monotonic())
        result = pending.result
        if result == cmds.MAV_RESULT_ACCEPTED:
            return pending, f"{name} accepted"
        if result == cmds.RESULT_NO_ACK:
            return pending, f"{name}: no COMMAND_ACK after {pending.sent} attempt(s)"
        reason = self._reason_since(started)
        text = f"{name} refused: {cmds.result_name(result)}"
        return pending, f"{text} ({reason})" if reason else text

    def _reason_since(self, started: float) -> str:
        deadline = time.monotonic() + self.config.reason_wait
        while True:
            texts = [
                t.text
                for at, t in list(self._recent_texts)
                if at >= started - 0.05
                and t.severity <= SEVERITY_WARNING
                and t.header.frame_id != "bridge"
            ]
            if texts or time.monotonic() >= deadline:
                return "; ".join(texts)
            time.sleep(0.02)

    def handle_arming(self, request: CommandBool) -> CommandBoolResult:
        """ARMING: MAV_CMD_COMPONENT_ARM_DISARM; the reply carries the real ack."""
        self.guard.admit_command("arming")
        self._require_connected()
        result, message = self.command(
            cmds.MAV_CMD_COMPONENT_ARM_DISARM, 1.0 if request.value else 0.0
        )
        return CommandBoolResult(success=result == 0, result=result, message=message)

    def handle_takeoff(self, request: CommandTOL) -> CommandTOLResult:
        """TAKEOFF: MAV_CMD_NAV_TAKEOFF to ``altitude`` m above the take-off point."""
        self.guard.admit_command("takeoff")
        autopilot = self._require_connected()
        height = request.altitude
        if not math.isnan(height) and not (math.isfinite(height) and 0.0 < height <= 1000.0):
            raise ValueError(f"altitude must be in (0, 1000] m or NaN, got {height!r}")
        yaw = request.yaw
        if not (math.isnan(yaw) or math.isfinite(yaw)):
            raise ValueError(f"yaw must be finite or NaN, got {yaw!r}")
        if self._ext.landed_state == LANDED_STATE_IN_AIR:
            return CommandTOLResult(success=True, result=0, message="already flying")
        yaw_deg = math.nan if math.isnan(yaw) else math.degrees(yaw_enu_to_ned(yaw))
        if autopilot == AUTOPILOT_ARDUPILOT:
            altitude = height if not math.isnan(height) else 2.5
        else:
            altitude = (
                self.telemetry.takeoff_altitude_amsl(height) if not math.isnan(height) else math.nan
            )
        with self._lock:
            now = time.monotonic()
            self.failsafe.on_mode_requested("AUTO.TAKEOFF", now)
            self.failsafe.on_mode_requested(HOLD_MODE[autopilot], now)
            self.failsafe.on_takeoff_requested(now)  # no priming, no hold into the climb
        result, message = self.command(
            cmds.MAV_CMD_NAV_TAKEOFF, request.min_pitch, 0, 0, yaw_deg, math.nan, math.nan, altitude
        )
        if result == cmds.MAV_RESULT_ACCEPTED and autopilot == AUTOPILOT_PX4:
            self._mode_entered("AUTO.TAKEOFF")  # ArduCopter climbs in GUIDED itself
        if not math.isnan(height) and math.isnan(altitude):
            message += " (no home altitude known: the autopilot's default take-off altitude)"
        return CommandTOLResult(success=result == 0, result=result, message=message)

    def handle_land(self, request: CommandTOL) -> CommandTOLResult:
        """LAND: MAV_CMD_NAV_LAND here (NaN lat/lon: current position, no GPS needed)."""
        self.guard.admit_command("land")
        autopilot = self._require_connected()
        lat, lon = request.latitude, request.longitude
        for name, value, bound in (("latitude", lat, 90.0), ("longitude", lon, 180.0)):
            if not math.isnan(value) and not (math.isfinite(value) and abs(value) <= bound):
                raise ValueError(f"{name} must be within ±{bound:g} degrees or NaN, got {value!r}")
        self.failsafe_mode_requested(LAND_MODE[autopilot])
        result, message = self.command(cmds.MAV_CMD_NAV_LAND, 0, 0, 0, math.nan, lat, lon, math.nan)
        if result == cmds.MAV_RESULT_ACCEPTED:
            self._mode_entered(LAND_MODE[autopilot])  # not ~1 s later from the heartbeat
        return CommandTOLResult(success=result == 0, result=result, message=message)

    def handle_set_mode(self, request: SetMode) -> SetModeResult:
        """SET_MODE by name; replies once the autopilot has really entered or refused it.

        PX4: OFFBOARD is preceded by > offboard_prime_s of streaming (priming); DO_SET_MODE is
        acknowledged twice and the second ack (the commander's) is the answer, a refusal with
        PX4's STATUSTEXT reason; with no second ack the mode must show in HEARTBEAT within
        mode_confirm_timeout. ArduPilot: one ack, and ACCEPTED means the mode is entered; no
        priming (a hold at the ground would override its take-off). An entered mode is known
        at once (failsafe, State), not at the next 1 Hz heartbeat.
        """
        self.guard.admit_command("set_mode")
        autopilot = self._require_connected()
        params = set_mode_params(autopilot, request.custom_mode)  # ValueError lists valid modes
        px4 = autopilot == AUTOPILOT_PX4
        primed = px4 and params.name == GUIDED_MODE[AUTOPILOT_PX4]
        if primed:
            self._prime_stream()
        self.failsafe_mode_requested(params.name)
        pending, message = self.command_exchange(
            cmds.MAV_CMD_DO_SET_MODE,
            params.param1,
            params.param2,
            params.param3,
            expected_acks=2 if px4 else 1,
        )
        result = pending.result
        if result == cmds.MAV_RESULT_ACCEPTED and not pending.confirmed:
            seen = self._wait_for_mode(params.name, self.config.mode_confirm_timeout)
            if seen == params.name:
                message += " (confirmed by HEARTBEAT)"
            else:
                result = cmds.MAV_RESULT_FAILED
                message = (
                    f"DO_SET_MODE {params.name}: acknowledged once, but the autopilot is still "
                    f"in {seen or 'an unknown mode'} after {self.config.mode_confirm_timeout:g} s"
                )
        if result == cmds.MAV_RESULT_ACCEPTED:
            self._mode_entered(params.name)
        with self._lock:  # the stream goes on only if the bridge holds OFFBOARD now
            self.failsafe.end_priming(time.monotonic(), engage=primed and result == 0)
        return SetModeResult(mode_sent=result == 0, result=result, message=message)

    def _wait_for_mode(self, mode: str, timeout: float) -> str:
        """Wait up to ``timeout`` s for HEARTBEAT to show ``mode``; returns the mode shown."""
        deadline = time.monotonic() + timeout
        while True:
            with self._lock:
                shown = self._heartbeat_state.mode if self._heartbeat_state else ""
            if shown == mode or time.monotonic() >= deadline or self.node.stop_event.is_set():
                return shown
            time.sleep(0.02)

    def _mode_entered(self, mode: str) -> None:
        """The autopilot accepted a command that puts it in ``mode``: the failsafe and State
        know it now (the next HEARTBEAT, up to 1 s later, confirms or corrects it)."""
        now = time.monotonic()
        with self._lock:
            hb = self._heartbeat_state
            if hb is None or hb.mode == mode:
                return
            self._heartbeat_state = msgspec.structs.replace(hb, mode=mode, guided=is_guided(mode))
            self._update_failsafe_vehicle(now)
        log.info("mode %s (from the accepted command)", mode)
        self.publish_state()

    def _prime_stream(self) -> None:
        need = self.config.offboard_prime_s
        now = time.monotonic()
        if self.streamed_for(now) >= need:
            return
        with self._lock:
            if self._pose() is None and self.failsafe.fresh_target(now) is None:
                raise ServiceError(
                    "cannot enter OFFBOARD: no local position to hold and no setpoint stream",
                    "refused",
                )
            self.failsafe.start_priming(now, need + 2.0)
        deadline = now + need + 2.0
        while self.streamed_for(time.monotonic()) < need:
            if time.monotonic() >= deadline or self.node.stop_event.is_set():
                raise ServiceError("could not stream setpoints before OFFBOARD", "refused")
            time.sleep(0.02)

    # ------------------------------------------------------------------ params

    def _check_param_id(self, param_id: str) -> str:
        if (
            not isinstance(param_id, str)
            or not param_id
            or len(param_id) > 16
            or not (param_id.isascii() and param_id.isprintable())
        ):
            raise ValueError(f"param_id must be 1-16 printable ASCII characters, got {param_id!r}")
        return param_id

    def _param_decode(self, raw: float, param_type: int) -> ParamValue:
        return param_values.decode_param(raw, param_type, bytewise=self._param_bytewise())

    def _param_bytewise(self) -> bool:
        """PX4 sends integer parameters as their bytes; ArduPilot as float values."""
        return self.autopilot != AUTOPILOT_ARDUPILOT

    def _param_exchange(self, param_id: str, send: Any) -> tuple[float, int] | None:
        """Send (with retries) until a PARAM_VALUE for ``param_id`` newer than the send."""
        for _ in range(self.config.param_attempts):
            sent_at = time.monotonic()
            send()
            deadline = sent_at + self.config.param_timeout
            with self._param_cond:
                while True:
                    entry = self._params.get(param_id)
                    if entry is not None and entry[2] >= sent_at:
                        return entry[0], entry[1]
                    remaining = deadline - time.monotonic()
                    if remaining <= 0 or self.node.stop_event.is_set():
                        break
                    self._param_cond.wait(remaining)
        return None

    def _param_read(self, param_id: str) -> tuple[float, int] | None:
        encoded = param_id.encode("ascii")
        return self._param_exchange(
            param_id,
            lambda: self.link.send(
                "param_request_read", self.target_system or 1, self.target_component, encoded, -1
            ),
        )

    def handle_param_get(self, request: ParamGet) -> ParamGetResult:
        """PARAM_GET: PARAM_REQUEST_READ; integers are reinterpreted from the float bits."""
        self._require_connected()
        param_id = self._check_param_id(request.param_id)
        got = self._param_read(param_id)
        if got is None:
            return ParamGetResult(success=False, message=f"{param_id}: no PARAM_VALUE (unknown?)")
        return ParamGetResult(success=True, value=self._param_decode(*got), message="ok")

    def handle_param_set(self, request: ParamSet) -> ParamSetResult:
        """PARAM_SET: write, then report the value the autopilot echoes.

        The value is checked against the parameter's type first (float32 range, integer
        ranges, exactness); a value that does not fit is a bad request naming the field.
        """
        self.guard.admit_command("param_set")
        self._require_connected()
        param_id = self._check_param_id(request.param_id)
        param_values.requested_number(param_id, request.value)  # refuse before any I/O
        with self._param_cond:
            known = self._params.get(param_id)
        if known is None:
            known_read = self._param_read(param_id)
            if known_read is None:
                return ParamSetResult(success=False, message=f"{param_id}: unknown parameter")
            param_type = known_read[1]
        else:
            param_type = known[1]
        raw = param_values.encode_param(
            param_id, request.value, param_type, bytewise=self._param_bytewise()
        )
        encoded = param_id.encode("ascii")
        got = self._param_exchange(
            param_id,
            lambda: self.link.send(
                "param_set",
                self.target_system or 1,
                self.target_component,
                encoded,
                raw,
                param_type,
            ),
        )
        if got is None:
            return ParamSetResult(success=False, message=f"{param_id}: no PARAM_VALUE echo")
        echoed = self._param_decode(*got)
        requested = self._param_decode(raw, param_type)
        same = echoed.integer == requested.integer and (
            echoed.real == requested.real
            or abs(echoed.real - requested.real) <= 1e-6 * max(1.0, abs(requested.real))
        )
        message = "ok" if same else "the autopilot kept a different value"
        return ParamSetResult(success=same, value=echoed, message=message)


def run(node: Node, config: Config) -> int:
    """The service body: start the bridge, announce readiness, run until stopped."""
    # The receive loop parses hundreds of MAVLink messages/s in Python; a 1 ms GIL switch
    # interval (default 5 ms) keeps a setpoint arriving meanwhile from waiting behind it.
    sys.setswitchinterval(0.001)
    try:
        bridge = Bridge(node, config)
    except ValueError as exc:  # e.g. an unknown commander_lost_action
        log.error("bad config: %s", exc)
        return 2
    exposure = network_exposure(config.connection)
    if exposure is not None:
        log.warning("autopilot link beyond loopback (a deliberate setting): %s", exposure)
    threads = bridge.start()
    node.announce()
    log.info("bridge_mavlink ready on %s (namespace %s)", config.connection, node.ns)
    node.spin()
    for thread in threads:
        thread.join(timeout=2.0)
    bridge.link.close()
    if bridge.gcs is not None:
        bridge.gcs.close()
    return 0


__all__ = ["Bridge", "Config", "canonical_mode", "run"]
