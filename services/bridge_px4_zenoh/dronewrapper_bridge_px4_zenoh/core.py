"""The PX4 Zenoh bridge without I/O: PX4's uORB samples and tokens and Zenoh requests in, what
to write to PX4 and publish out.

:class:`Px4ZenohCore` holds what the bridge knows (the firmware's message versions, PX4's
status, position, attitude, landed state, battery, the failsafe, pending commands) and is pure:
no sockets, no threads, no clock. Every entry point takes the time (``now`` monotonic s,
``stamp`` wall-clock s for headers) and queues its effects in an :class:`Outbox`: px4_msgs
values for PX4's ``/fmu/in`` topics (the node encodes and writes them on the key the firmware
announced) and samples for the MAVROS-equivalent keys. Decoding happens here too (CDR is
pure), after the version check: a sample or token whose type hash is not the bridge's is never
decoded, and the mismatch is reported once per topic, naming topic and both hashes. PX4's
high-rate topics (:data:`COALESCED`) are not fed sample by sample: the node puts their raw
samples in :attr:`Px4ZenohCore.inbox` (:mod:`.newest`) and :meth:`Px4ZenohCore.tick` decodes
the newest of each, so the bridge decodes at its stream rate whatever PX4's rate; the others
(status, landed state, command acks: a few Hz) go through :meth:`Px4ZenohCore.on_data`.

The rules are bridge_base's (commander lease, late setpoints, refusals published; the
guided-mode failsafe: stream, hold, priming, commander lost, never fighting the pilot, fed and
acted on by :class:`~dronewrapper_bridge_base.guided_core.GuidedCore`) and the
SDK's (setpoint validation; the envelope, :mod:`.envelope_rules`); the service calls are
operations (:mod:`.operations`, :mod:`.flight`).
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass, field
from typing import Any

import msgspec

from dronewrapper.msgs import registry
from dronewrapper.msgs.mavros import (
    SEVERITY_ERROR,
    SEVERITY_WARNING,
    PositionTarget,
    SetMode,
    StatusText,
)
from dronewrapper.msgs.registry import Topic
from dronewrapper.msgs.std import Header
from dronewrapper.runtime import ServiceError
from dronewrapper_bridge_base.envelope_state import EnvelopeState
from dronewrapper_bridge_base.frames import yaw_ned_to_enu
from dronewrapper_bridge_base.guided_core import GuidedCore
from dronewrapper_bridge_base.guided_failsafe import hold_target
from dronewrapper_bridge_base.odometry import Headers
from dronewrapper_bridge_base.setpoint_envelope import refuse_setpoint
from dronewrapper_bridge_base.setpoint_limits import Kind, kind_of
from dronewrapper_bridge_px4_zenoh import envelope_rules as rules
from dronewrapper_bridge_px4_zenoh import operations as ops
from dronewrapper_bridge_px4_zenoh import telemetry as tm
from dronewrapper_bridge_px4_zenoh import topics as t
from dronewrapper_bridge_px4_zenoh import trajectory, watch
from dronewrapper_bridge_px4_zenoh.config import Config
from dronewrapper_bridge_px4_zenoh.newest import NewestSamples
from dronewrapper_bridge_px4_zenoh.versions import VersionMismatch, Versions
from dronewrapper_ros2_codec import cdr
from dronewrapper_ros2_codec.names import Endpoint

log = logging.getLogger("bridge_px4_zenoh")

STREAM_GAP_S = 0.5  # s without a setpoint written: the stream has stopped (priming restarts)
ENTERED_HOLD_S = 1.5  # s a status showing the mode an accepted command left is taken as stale
# (and, whenever it arrives, one PX4 stamped before the command's ack: held on the way)
COALESCED: tuple[t.Px4Topic, ...] = (t.ATTITUDE, t.LOCAL_POSITION, t.GLOBAL_POSITION, t.BATTERY)
"""PX4's high-rate topics, decoded at the tick from :attr:`Px4ZenohCore.inbox`, in this order
(a pose needs the attitude)."""


@dataclass
class Outbox:
    """What the node must do after a core call.

    Attributes:
        writes: (PX4 topic, px4_msgs value) to encode and write to PX4, in order.
        samples: (registry topic, message) to publish on the MAVROS-equivalent keys.
        errors: names of dropped inputs to count (the node's ``callback_errors``).
    """

    writes: list[tuple[t.Px4Topic, dict[str, Any]]] = field(default_factory=list)
    samples: list[tuple[Topic, Any]] = field(default_factory=list)
    errors: list[str] = field(default_factory=list)


class Px4ZenohCore(GuidedCore):
    """The bridge's logic and state (see module docstring); ``now`` is where its time starts."""

    def __init__(self, config: Config, now: float = 0.0) -> None:
        super().__init__(config, now, Outbox, log)
        self.config: Config = config
        self.versions = Versions(config.domain)
        self.envelope = EnvelopeState(config.envelope)
        self.autopilot = tm.AUTOPILOT
        self.target_system = config.target_system  # 0 until vehicle_status names it
        self.target_component = config.target_component
        self.status: dict[str, Any] | None = None  # the latest VehicleStatus
        self.q_enu_flu: tuple[float, float, float, float] | None = None
        self.headers = Headers()  # pose and velocity headers, numbered per kind
        self.position_enu: tuple[float, float, float] | None = None
        self.yaw_enu = 0.0
        self.acks: list[tuple[float, int, int]] = []  # (when, command, result), newest last
        self.inbox = NewestSamples()  # COALESCED topics' newest raw samples (thread-safe)
        self.samples_received = 0  # samples decoded
        self.last_sample_at = -math.inf
        self._reported: set[str] = set()  # topics whose mismatch was reported
        self._entered = ("", "", -math.inf, 0)  # (mode entered, left, until when, ack's PX4 us)
        self.last_ack_us = 0  # PX4's stamp of its newest vehicle_command_ack (us since boot)
        self._last_pose_pub = -math.inf
        self._last_global_pub = -math.inf
        self._last_send = -math.inf
        self._stream_since = -math.inf

    # ------------------------------------------------------------------ plumbing

    def write(self, topic: t.Px4Topic, value: dict[str, Any]) -> None:
        """Queue ``value`` for PX4's ``topic`` (refused while the firmware's version of it is
        not the bridge's: the mismatch was reported)."""
        mismatch = self.versions.mismatches.get(topic.name)
        if mismatch is not None:
            self._report(mismatch)
            return
        self.out.writes.append((topic, value))

    def require_connected(self) -> str:
        """The autopilot kind; ServiceError while PX4 sends nothing."""
        if not self.connected:
            raise ServiceError("PX4 is not connected (no sample on its Zenoh keys)", "unavailable")
        return self.autopilot

    def bridge_text(self, text: str, severity: int = SEVERITY_WARNING) -> None:
        """Log and publish a text of the bridge's own (StatusText, frame_id ``bridge``)."""
        log.warning("%s", text)
        header = Header(stamp=self.stamp, frame_id="bridge")
        msg = StatusText(header=header, severity=severity, text=f"bridge: {text}")
        self.publish(registry.STATUSTEXT, msg)

    def _report(self, mismatch: VersionMismatch) -> None:
        if mismatch.topic not in self._reported:
            self._reported.add(mismatch.topic)
            self.bridge_text(str(mismatch), SEVERITY_ERROR)

    # ------------------------------------------------------------------ PX4's side

    def on_token(self, endpoint: Endpoint, now: float, stamp: float) -> None:
        """One of PX4's liveliness tokens (a publisher or subscriber with its type hash)."""
        self._at(now, stamp)
        mismatch = self.versions.learn(endpoint)
        if mismatch is not None:
            self._report(mismatch)

    def on_data(self, key: str, payload: bytes, now: float, stamp: float) -> None:
        """One sample on PX4's ``/fmu/out`` keys: checked against the bridge's version of its
        type, decoded, handled."""
        self._at(now, stamp)
        self._on_raw(key, payload)
        if self.operations:
            self.advance(now, stamp)

    def _on_raw(self, key: str, payload: bytes) -> None:
        parsed = t.parse_key(key)
        if parsed is None or parsed.domain != self.config.domain:
            return
        topic = t.BY_NAME.get(parsed.topic)
        if topic is None or topic.direction != t.OUT:
            return
        mismatch = self.versions.check(topic.name, parsed.type_name, parsed.type_hash)
        if mismatch is not None:
            self._report(mismatch)
            self.out.errors.append("version")
            return
        try:
            value = cdr.decode(topic.type_name, payload)
        except cdr.CdrError as exc:
            self.out.errors.append(topic.name)
            log.debug("undecodable %s: %s", topic.name, exc)
            return
        self.samples_received += 1
        self.last_sample_at = self.now
        if not self.connected:
            self.connected = True
            log.info("PX4 connected (samples on its Zenoh keys)")
        self.on_value(topic, value)

    def _drain(self) -> None:
        """Decode the newest inbox sample of each coalesced topic (global position and battery
        only when one is due for publication: PX4 SIH sends each at ~100 Hz)."""
        newest = self.inbox.take()
        for topic in COALESCED:
            raw = newest.get(topic.name)
            if raw is None:
                continue
            if (topic is t.GLOBAL_POSITION and not self._global_due()) or (
                topic is t.BATTERY and not self._battery_due()
            ):
                self.last_sample_at = self.now  # PX4 is there; the sample is not needed
                continue
            self._on_raw(raw.key, raw.payload)

    def _global_due(self) -> bool:
        max_hz = self.config.global_position_max_hz
        return max_hz <= 0 or self.now - self._last_global_pub >= 0.9 / max_hz

    def _battery_due(self) -> bool:
        """A battery sample is needed: none yet, or this tick publishes it (:meth:`_periodic`)."""
        period = 1.0 / self.config.battery_rate_hz
        return self.battery is None or self.now - self._last_battery_pub >= period

    def on_value(self, topic: t.Px4Topic, value: dict[str, Any]) -> None:
        """A decoded sample of ``topic`` (time already set)."""
        if topic is t.VEHICLE_STATUS:
            self.status = value
            if not self.config.target_system:
                self.target_system = int(value["system_id"])
            if not self.config.target_component:
                self.target_component = int(value["component_id"])
            self._show_vehicle()
        elif topic is t.ATTITUDE:
            q = tm.attitude_enu_flu(value)
            if q is not None:
                self.q_enu_flu = q
        elif topic is t.LOCAL_POSITION:
            self._on_local_position(value)
        elif topic is t.GLOBAL_POSITION:
            if self._global_due():
                self._last_global_pub = self.now
                self.publish(registry.GLOBAL_POSITION, tm.global_position(value, self.stamp))
        elif topic is t.BATTERY:
            self.battery = tm.battery(value, self.stamp)
        elif topic is t.LAND_DETECTED:
            ext = tm.extended_state(value, self.stamp)
            if ext.landed_state != self.ext.landed_state:
                self.ext = ext
                self._last_ext_pub = self.now
                self.publish(registry.EXTENDED_STATE, ext)
                self.update_failsafe_vehicle()
            self.ext = ext
        elif topic is t.COMMAND_ACK:
            self.acks.append((self.now, int(value["command"]), int(value["result"])))
            self.last_ack_us = int(value["timestamp"])
            del self.acks[:-16]

    def _on_local_position(self, value: dict[str, Any]) -> None:
        if value["xy_global"] and value["z_global"] and self.envelope.home_geo is None:
            # home is PX4's local origin (envelope_rules): local ENU (0, 0, 0)
            self.envelope.home_geo = (value["ref_lat"], value["ref_lon"], value["ref_alt"])
            rules.publish_home(self)
        q = self.q_enu_flu
        if q is None:
            return
        position = tm.local_position(value)
        if position is None:
            return
        self.position_enu = position
        if math.isfinite(value["heading"]):
            self.yaw_enu = yaw_ned_to_enu(value["heading"])
        max_hz = self.config.pose_max_hz
        if max_hz > 0 and self.now - self._last_pose_pub < 0.9 / max_hz:
            return
        self._last_pose_pub = self.now
        velocity = tm.local_velocity(value)
        pose, velocities = tm.local_odometry(self.headers, position, q, velocity, self.stamp)
        self.publish(registry.LOCAL_POSE, pose)
        if velocities is not None:
            self.publish(registry.VELOCITY_LOCAL, velocities[0])
            self.publish(registry.VELOCITY_BODY, velocities[1])

    def _show_vehicle(self) -> None:
        if self.status is None:
            return
        state = tm.state(self.status, connected=True, failsafe="", commander="")
        mode, left, until, acked_us = self._entered
        older = int(self.status["timestamp"]) < acked_us  # PX4's clock: published before the ack
        if state.mode == left and (older or self.now < until):  # sent before PX4 took it
            state = msgspec.structs.replace(state, mode=mode, guided=mode == "OFFBOARD")
        elif state.mode == mode:
            self._entered = ("", "", -math.inf, 0)  # confirmed
        self.heartbeat_state = state
        self.update_failsafe_vehicle()
        self.publish_state()

    def refuse_envelope(self, target: PositionTarget, kind: Kind) -> Any:
        return refuse_setpoint(self.envelope, target, kind, self.now, self.bridge_text)

    def failsafe_steps(self, request: str) -> Any:
        return ops.failsafe_action(self, request)

    def mode_entered(self, mode: str) -> None:
        """PX4 accepted a command that puts it in ``mode``: known now (vehicle_status, ~2 Hz,
        confirms or corrects it)."""
        hb = self.heartbeat_state
        if hb is None or hb.mode == mode:
            return
        # a vehicle_status still showing the mode left is older than the ack: kept out for
        # ENTERED_HOLD_S, and whenever it arrives if PX4 stamped it before the ack (a status
        # held on the way would otherwise have the failsafe stream OFFBOARD back on, and a
        # return refused as "left AUTO.RTL for OFFBOARD")
        self._entered = (mode, hb.mode, self.now + ENTERED_HOLD_S, self.last_ack_us)
        self.heartbeat_state = msgspec.structs.replace(hb, mode=mode, guided=mode == "OFFBOARD")
        self.update_failsafe_vehicle()
        self.publish_state()

    # ------------------------------------------------------------------ state publication

    def breach_state(self) -> str:
        return self.envelope.breach_state()

    def hold_here(self) -> None:
        """A cancel's hold: the bridge's own position hold where the aircraft is, in OFFBOARD
        (asked for if PX4 is not in it)."""
        pose = self.pose()
        if pose is None:
            return
        self.failsafe.hold_at(hold_target(*pose))
        if self.heartbeat_state is None or self.heartbeat_state.mode != "OFFBOARD":
            steps = ops.set_mode(self, SetMode(custom_mode="OFFBOARD"))
            self.start(steps, self.now, self.stamp, background=True)

    # ------------------------------------------------------------------ the stream tick

    def tick(self, now: float, stamp: float) -> None:
        """The stream loop's tick (>= 20 Hz): the failsafe's stream and actions, link
        supervision, the envelope, periodic samples, operations; first the newest samples of
        PX4's high-rate topics (:meth:`_drain`)."""
        self._at(now, stamp)
        self._drain()
        if self.connected and now - self.last_sample_at > self.config.link_timeout:
            self.connected = False
            log.warning("no sample from PX4 for %.1f s: disconnected", now - self.last_sample_at)
        tick = self.failsafe.tick(now, self.pose())
        if now - self._last_send < 0.5 / self.config.stream_rate_hz:
            tick.send = None  # just written by the setpoint's arrival
        self._act(tick, send=self.connected)
        self.show_commander()
        watch.tick(self)
        breach = rules.tick(self)
        if breach:
            self.start(ops.breach_action(self, breach), now, stamp, background=True)
        self.publish_periodic()
        self.advance(now, stamp)

    # ------------------------------------------------------------------ setpoints

    def pose(self) -> tuple[tuple[float, float, float], float] | None:
        """(position ENU m, yaw ENU rad) now, None before the first local position."""
        if self.position_enu is None:
            return None
        return (self.position_enu, self.yaw_enu)

    def _send_setpoint(self, target: PositionTarget) -> None:
        """Write an admitted ``target`` (validated where it entered, or the bridge's own)."""
        kind = kind_of(target)
        self.write(t.OFFBOARD_MODE, trajectory.control_mode(kind))
        self.write(t.TRAJECTORY, trajectory.trajectory_setpoint(target, kind, self.yaw_enu))
        self.setpoints_sent += 1
        if self.now - self._last_send > STREAM_GAP_S:
            self._stream_since = self.now
            if self.failsafe.armed and self.failsafe.mode == "OFFBOARD":
                gap = self.now - self._last_send
                log.warning("setpoint stream resumed after %.2f s, armed in OFFBOARD", gap)
        self._last_send = self.now

    def streamed_for(self, now: float) -> float:
        """Seconds the bridge has been streaming setpoints without a gap (0 if not now)."""
        if now - self._last_send > STREAM_GAP_S:
            return 0.0
        return now - self._stream_since
