"""The bridge without I/O: MAVLink messages and Zenoh requests in, what to send and publish out.

:class:`BridgeCore` holds everything the bridge knows (the autopilot's connection, mode and
landed state, telemetry, the failsafe, pending commands and parameter reads) and is pure: no
sockets, no threads, no clock. Every entry point takes the time (``now`` monotonic s,
``stamp`` wall-clock s for headers) and queues its effects in an :class:`Outbox` that the node
takes with :meth:`BridgeCore.take` and executes (MAVLink sends, Zenoh samples). Which messages
may be used and the telemetry handlers are in ``receive``; the service calls that wait for
acknowledgements are operations (``operations``, ``flight``, ``parameters``) the core advances
as messages and time arrive; the node only waits on them. The sim's autopilot
(sim/dronewrapper_sim/px4/autopilot.py) is built the same way.

What both PX4-capable bridges share (the failsafe fed and acted on, setpoints screened, State
published) is :class:`~dronewrapper_bridge_base.guided_core.GuidedCore`; what stands alone
(receive, telemetry, operations, missions, parameters) is in its own module, each seeing the
core only through the small protocol it states (``receive.ReceivePort``,
``operations.OperationPort``, ``missions.MissionPort`` ...), or taking the parts it uses.
"""

from __future__ import annotations

import collections
import logging
import math
from collections.abc import Callable
from typing import Any, ClassVar

import msgspec
from pymavlink.dialects.v20 import common as mavlink

from dronewrapper.msgs import registry
from dronewrapper.msgs.mavros import (
    SEVERITY_WARNING,
    PositionTarget,
    SetMode,
)
from dronewrapper.msgs.mavros import StatusText as StatusTextMsg
from dronewrapper.msgs.std import Header
from dronewrapper.runtime import ServiceError
from dronewrapper_bridge_base.guided_core import GuidedCore
from dronewrapper_bridge_base.setpoint_envelope import refuse_setpoint
from dronewrapper_bridge_base.setpoint_limits import Kind
from dronewrapper_bridge_mavlink import missions, receive, watch
from dronewrapper_bridge_mavlink import operations as ops
from dronewrapper_bridge_mavlink.command_exchange import Commands
from dronewrapper_bridge_mavlink.config import Config
from dronewrapper_bridge_mavlink.freshness import Freshness
from dronewrapper_bridge_mavlink.keepalive import KeepAlive
from dronewrapper_bridge_mavlink.link_budget import fit_rates, is_serial_url
from dronewrapper_bridge_mavlink.link_gap import gap_report
from dronewrapper_bridge_mavlink.mission_state import MissionState
from dronewrapper_bridge_mavlink.modes import AUTOPILOT_PX4, GUIDED_MODE, is_guided
from dronewrapper_bridge_mavlink.operations import failsafe_action
from dronewrapper_bridge_mavlink.outgoing import (
    CommandLong,
    Heartbeat,
    Outbox,
    Send,
    SetPositionTargetLocalNed,
)
from dronewrapper_bridge_mavlink.parameters import Parameters
from dronewrapper_bridge_mavlink.setpoints import hold_target, to_local_ned
from dronewrapper_bridge_mavlink.sources import AutopilotSources
from dronewrapper_bridge_mavlink.streams import StreamRequests
from dronewrapper_bridge_mavlink.telemetry import (
    StatusTextAssembler,
    Telemetry,
    battery_from_battery_status,
    battery_from_sys_status,
    extended_state,
    is_autopilot_heartbeat,
    state_from_heartbeat,
)
from dronewrapper_bridge_mavlink.transfers import Transfers

log = logging.getLogger("bridge_mavlink")


class BridgeCore(GuidedCore):
    """The bridge's logic and state (see module docstring); ``now`` is where its time starts."""

    def __init__(self, config: Config, now: float = 0.0) -> None:
        super().__init__(config, now, Outbox, log)
        self.config: Config = config
        self.telemetry = Telemetry()
        self.freshness = Freshness()
        self.sources = AutopilotSources()
        self.statustexts = StatusTextAssembler()
        self.commands = Commands(self, config)
        self.missions = MissionState(config.envelope)
        self.parameters = Parameters(
            self, attempts=config.param_attempts, timeout=config.param_timeout
        )
        self.transfers = Transfers(self)
        serial = is_serial_url(config.connection)
        self.budget = fit_rates(
            config.message_rates,
            config.baud if serial else None,
            signed=bool(config.signing_key_file),
            share=config.link_share,
        )
        self.streams = StreamRequests(
            self.budget.rates,
            config.unused_streams + (config.serial_unused_streams if serial else []),
            forwarding=bool(config.gcs_url) or config.gcs_over_zenoh,
        )
        self.recent_texts: collections.deque[tuple[float, StatusTextMsg]] = collections.deque(
            maxlen=32
        )
        self.target_system = config.target_system
        self.target_component = config.target_component
        self.messages_received = 0
        self._t0 = now
        self.last_heartbeat = -math.inf
        self._next_heartbeat_out = -math.inf
        self.last_global_pub = -math.inf
        self.keepalive = KeepAlive(config.setpoint_keepalive_s, 0.5 / config.stream_rate_hz)
        self.rates_round = 0
        self.next_rates = math.inf

    # ------------------------------------------------------------------ plumbing

    def send(self, message: Send) -> None:
        """Queue a MAVLink message for the autopilot (the link encodes it)."""
        self.out.sends.append(message)

    def dropped(self, what: str) -> None:
        """Count a dropped input under ``what`` (the node's ``callback_errors``)."""
        self.out.errors.append(what)

    def target(self) -> tuple[int, int]:
        """The autopilot's (system, component) to address (system 1 before it is heard)."""
        return self.target_system or 1, self.target_component

    def require_connected(self) -> str:
        """The autopilot kind; ServiceError when no heartbeat is heard."""
        if not self.connected:
            raise ServiceError("the autopilot is not connected (no heartbeat)", "unavailable")
        return self.autopilot or AUTOPILOT_PX4

    # ------------------------------------------------------------------ receive side

    def on_mavlink(self, msg: Any, source: Any, now: float, stamp: float) -> None:
        """One received MAVLink message (``source`` its UDP address, None when unknown)."""
        self._at(now, stamp)
        kind = msg.get_type()
        if kind == "BAD_DATA":
            return
        self.messages_received += 1
        verdict = receive.admission(self, msg, kind, source)
        if verdict.flag:
            self.bridge_text(verdict.flag)
        if verdict.peer is not None:
            self.out.peers.append(verdict.peer)
        if verdict.error:
            self.dropped(verdict.error)
        if not verdict.accept:
            return
        if kind == "HEARTBEAT":
            self._on_heartbeat(msg)
        elif not self.target_system or msg.get_srcSystem() == self.target_system:
            own = self._OWN_HANDLERS.get(kind)
            handler = self._HANDLERS.get(kind)
            if own is not None:
                own(self, msg)
            elif handler is not None:
                handler(self, msg)
        if self.operations:
            self.advance(now, stamp)

    def _on_heartbeat(self, msg: Any) -> None:
        if not is_autopilot_heartbeat(msg):
            return
        if self.target_system and msg.get_srcSystem() != self.target_system:
            return
        if not self.target_system:
            self.target_system = msg.get_srcSystem()
            self.target_component = msg.get_srcComponent()
        before, lost_for = self.heartbeat_state, self.now - self.last_heartbeat
        self.last_heartbeat = self.now
        state = state_from_heartbeat(msg, self.stamp, failsafe=self.failsafe.state)
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
        self.heartbeat_state = state
        self.update_failsafe_vehicle()
        if reconnected:
            log.info("connected to the autopilot (mode %s)", state.mode)
            self.rates_round = 0
            self.next_rates = self.now
            if before is not None:  # after a link gap: what the autopilot changed meanwhile
                report = gap_report(before, state, lost_for)
                if report is not None:
                    self.bridge_text(report)
        self.publish_state()

    def _on_extended_sys_state(self, msg: Any) -> None:
        ext = extended_state(msg, self.stamp)
        changed = (ext.landed_state, ext.vtol_state) != (
            self.ext.landed_state,
            self.ext.vtol_state,
        )
        self.ext = ext
        if changed:
            self.update_failsafe_vehicle()
            self._last_ext_pub = self.now
            self.publish(registry.EXTENDED_STATE, ext)

    def _on_global_position_int(self, msg: Any) -> None:
        fix = self.telemetry.on_global_position(msg, self.stamp)
        max_hz = self.config.global_position_max_hz
        if fix is not None and (max_hz <= 0 or self.now - self.last_global_pub >= 0.9 / max_hz):
            self.last_global_pub = self.now
            self.publish(registry.GLOBAL_POSITION, fix)

    def _on_sys_status(self, msg: Any) -> None:
        battery = battery_from_sys_status(msg, self.stamp)
        known = self.battery is not None and not math.isnan(self.battery.percentage)
        if not known or not math.isnan(battery.percentage):
            self.battery = battery

    def _on_battery_status(self, msg: Any) -> None:
        if msg.id == 0:
            self.battery = battery_from_battery_status(msg, self.stamp)

    _OWN_HANDLERS: ClassVar[dict[str, Callable[[BridgeCore, Any], None]]] = {
        "EXTENDED_SYS_STATE": _on_extended_sys_state,
        "GLOBAL_POSITION_INT": _on_global_position_int,
        "SYS_STATUS": _on_sys_status,
        "BATTERY_STATUS": _on_battery_status,
    }
    _HANDLERS: ClassVar[dict[str, Callable[[BridgeCore, Any], None]]] = {
        **receive.HANDLERS,  # telemetry, acks, parameters
        **missions.HANDLERS,  # the mission protocol, home
    }

    @classmethod
    def read_messages(cls) -> frozenset[str]:
        """The MAVLink messages the core reads; the link decodes only these."""
        return frozenset({"HEARTBEAT", *cls._OWN_HANDLERS, *cls._HANDLERS})

    def bridge_text(self, text: str) -> None:
        """Log and publish a warning of the bridge's own (STATUSTEXT, frame_id ``bridge``)."""
        log.warning("%s", text)
        self.publish_text(
            StatusTextMsg(
                header=Header(stamp=self.stamp, frame_id="bridge"),
                severity=SEVERITY_WARNING,
                text=f"bridge: {text}",
            )
        )

    def publish_text(self, text: StatusTextMsg) -> None:
        if not text.header.stamp:
            text = msgspec.structs.replace(text, header=Header(stamp=self.stamp))
        self.recent_texts.append((self.now, text))
        log.info("autopilot says [%d]: %s", text.severity, text.text)
        self.publish(registry.STATUSTEXT, text)

    def refuse_envelope(self, target: PositionTarget, kind: Kind) -> Any:
        return refuse_setpoint(self.missions, target, kind, self.now, self.bridge_text)

    def failsafe_steps(self, request: str) -> Any:
        return failsafe_action(self, request)

    def on_command_ack(self, msg: Any, now: float, stamp: float) -> None:
        """A COMMAND_ACK, bypassing admission (tests of the ack routing)."""
        self._at(now, stamp)
        receive.on_command_ack(self, msg)
        self.advance(now, stamp)

    # ------------------------------------------------------------------ state publication

    def breach_state(self) -> str:
        return self.missions.breach_state()

    def hold_here(self) -> None:
        """A cancel's hold: the bridge's own position hold where the aircraft is, in the
        autopilot's guided mode (PX4 OFFBOARD, ArduPilot GUIDED), asked for if not in it."""
        pose = self.pose()
        if pose is None:
            return
        position, yaw = pose
        self.failsafe.hold_at(hold_target(position, yaw))
        mode = GUIDED_MODE[self.autopilot or AUTOPILOT_PX4]
        state = self.heartbeat_state
        if state is None or state.mode != mode:
            steps = ops.set_mode(self, SetMode(custom_mode=mode))
            self.start(steps, self.now, self.stamp, background=True)

    def mode_entered(self, mode: str) -> None:
        """The autopilot accepted a command that puts it in ``mode``: the failsafe and State
        know it now (the next HEARTBEAT, up to 1 s later, confirms or corrects it)."""
        hb = self.heartbeat_state
        if hb is None or hb.mode == mode:
            return
        self.heartbeat_state = msgspec.structs.replace(hb, mode=mode, guided=is_guided(mode))
        self.update_failsafe_vehicle()
        log.info("mode %s (from the accepted command)", mode)
        self.publish_state()

    # ------------------------------------------------------------------ the stream tick

    def tick(self, now: float, stamp: float) -> None:
        """The stream loop's tick (>= 20 Hz): our heartbeat, the failsafe's stream and actions,
        connection supervision, periodic samples, message-rate requests, operations."""
        self._at(now, stamp)
        if now >= self._next_heartbeat_out:
            self._next_heartbeat_out = now + 1.0
            self.send(
                Heartbeat(
                    type=self.config.heartbeat_type,
                    autopilot=mavlink.MAV_AUTOPILOT_INVALID,
                    base_mode=0,
                    custom_mode=0,
                    system_status=mavlink.MAV_STATE_ACTIVE,
                )
            )
        tick = self.failsafe.tick(now, self.pose())
        fresh = tick.send is not None and tick.send is self.failsafe.fresh_target(now)
        if tick.send is not None and not self.keepalive.due(tick.send, now, fresh=fresh):
            tick.send = None  # a fresh setpoint forwarded within the keep-alive period
        self._act(tick, send=self.connected)
        self.show_commander()
        missions.tick(self)
        watch.tick(self)
        self._periodic()
        self.advance(now, stamp)

    def _periodic(self) -> None:
        now = self.now
        if self.connected and now - self.last_heartbeat > self.config.heartbeat_timeout:
            self.connected = False
            log.warning(
                "no heartbeat for %.1f s: autopilot disconnected", now - self.last_heartbeat
            )
        self.publish_periodic()
        for text in self.statustexts.flush(now, stamp=self.stamp):
            self.publish_text(text)
        if now >= self.next_rates and self.connected:
            self._request_message_intervals(self.streams.round(now))
            self.rates_round += 1
            self.next_rates = now + 2.0 if self.rates_round < 3 else math.inf
        if self.connected:
            self._request_message_intervals(self.streams.due(now))

    def _request_message_intervals(self, requests: list[tuple[int, float]]) -> None:
        """Send SET_MESSAGE_INTERVAL for each (message id, interval µs) (fire and forget: the
        rounds are re-sent 3 times, see :mod:`~dronewrapper_bridge_mavlink.streams`)."""
        command = mavlink.MAV_CMD_SET_MESSAGE_INTERVAL
        for msg_id, interval_us in requests:
            params = (float(msg_id), interval_us, 0.0, 0.0, 0.0, 0.0, 0.0)
            self.send(CommandLong(*self.target(), command, 0, params))

    # ------------------------------------------------------------------ setpoints

    def pose(self) -> tuple[tuple[float, float, float], float] | None:
        """(position ENU m, yaw ENU rad) now, None before the first local position."""
        position = self.telemetry.position_enu
        if position is None:
            return None
        return (position, self.telemetry.yaw_enu)

    def _send_setpoint(self, target: PositionTarget) -> None:
        """Send an admitted ``target`` (validated where it entered, or the bridge's own)."""
        position = self.telemetry.position_enu
        ned = to_local_ned(
            target,
            autopilot=self.autopilot or AUTOPILOT_PX4,
            yaw_enu=self.telemetry.yaw_enu,
            z_enu=position[2] if position is not None else 0.0,
            limits=self.limits,
        )
        boot_ms = int((self.now - self._t0) * 1000) & 0xFFFFFFFF  # our time_boot_ms
        self.send(SetPositionTargetLocalNed(*self.target(), boot_ms, ned))
        self.setpoints_sent += 1
        self.keepalive.sent(target, self.now)

    def streamed_for(self, now: float) -> float:
        """Seconds the bridge has been streaming setpoints without a gap (0 if not now)."""
        return self.keepalive.streamed_for(now)
