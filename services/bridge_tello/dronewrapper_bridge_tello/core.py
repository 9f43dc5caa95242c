"""The Tello bridge without I/O: replies, state strings, requests in; SDK commands, samples out.

:class:`TelloCore` holds everything the bridge knows (link and SDK mode, telemetry, the
failsafe, the reply FIFO, pending operations) and is pure: no sockets, no threads, no clock.
Every entry point takes the time (``now`` monotonic s, ``stamp`` wall-clock s for headers) and
queues its effects in an :class:`Outbox` (SDK command strings for the Tello's command port,
Zenoh samples) that the node takes with :meth:`TelloCore.take` and executes. Service calls
that wait for the Tello (take-off, land, retried commands) are :mod:`operations` the core
advances as replies, state strings and ticks arrive; the node only waits on them. Shaped like
bridge_mavlink's core.
"""

from __future__ import annotations

import logging
import math

from dronewrapper.envelope import EnvelopeError
from dronewrapper.msgs import registry
from dronewrapper.msgs.mavros import (
    LANDED_STATE_LANDING,
    LANDED_STATE_ON_GROUND,
    LANDED_STATE_TAKEOFF,
    ExtendedState,
    PositionTarget,
    State,
    StatusText,
)
from dronewrapper.msgs.std import Header
from dronewrapper.runtime import ServiceError
from dronewrapper_bridge_base.commander_lease import commander_rules
from dronewrapper_bridge_base.core_driver import PureCore
from dronewrapper_bridge_base.operation import Operation
from dronewrapper_bridge_base.setpoint_limits import Kind
from dronewrapper_bridge_tello import missions
from dronewrapper_bridge_tello import operations as ops
from dronewrapper_bridge_tello.config import Config
from dronewrapper_bridge_tello.failsafe import LAND, Failsafe, Tick
from dronewrapper_bridge_tello.mission_state import TelloMissions
from dronewrapper_bridge_tello.outbox import Outbox
from dronewrapper_bridge_tello.replies import ReplyMatcher, is_ok
from dronewrapper_bridge_tello.state import StateError, parse_state
from dronewrapper_bridge_tello.sticks import (
    STOP,
    Sticks,
    body_velocity,
    rc_command,
    sticks_from_flu,
    validate,
)
from dronewrapper_bridge_tello.telemetry import Telemetry
from dronewrapper_bridge_tello.video_demand import STREAMON, VideoDemand

log = logging.getLogger("bridge_tello")

SEVERITY_WARNING = 4
SEVERITY_INFO = 6


class TelloCore(PureCore):
    """The bridge's logic and state (see module docstring)."""

    def __init__(self, config: Config, now: float = 0.0) -> None:
        super().__init__(now, Outbox, log, **commander_rules(config))
        self.config = config
        self.scale = config.scale
        self.failsafe = Failsafe(config.failsafe_config())
        self.missions = TelloMissions(config.envelope)
        self.telemetry = Telemetry(
            velocity_frame=config.velocity_frame,
            reference_yaw=math.radians(config.reference_yaw_deg),
            velocity_unit=config.velocity_unit,
            height_source=config.height_source,
            tof_ground_cm=config.tof_ground_cm,
        )
        self.matcher = ReplyMatcher()
        self.connected = False
        self.sdk_mode = False
        self.video = VideoDemand(config.video_policy())
        self.malformed_states = 0
        self.states_received = 0
        self.rc_sent = 0
        self.last_sticks: Sticks = STOP
        self._connect_op: Operation | None = None
        self._land_op: Operation | None = None
        self._last_state_at = -math.inf
        self._last_reconnect = -math.inf
        self._last_state_key: tuple | None = None
        self._last_state_pub = -math.inf
        self._last_ext_pub = -math.inf
        self._last_ext_value = -1
        self._last_battery_pub = -math.inf

    # ------------------------------------------------------------------ plumbing

    def send(self, text: str) -> None:
        """Queue an SDK command for the Tello (any command resets its 15 s timer)."""
        self.out.sends.append(text)
        self.failsafe.on_sent(self.now)

    def in_sdk_mode(self) -> None:
        """The Tello answered ``command``: it is in SDK mode."""
        if not self.sdk_mode:
            log.info("Tello in SDK mode")
        self.sdk_mode = True

    @property
    def streaming(self) -> bool:
        """True once the Tello has accepted ``streamon`` (and no ``streamoff`` since)."""
        return self.video.streaming is True

    def restart_video(self) -> None:
        """A ``streamon`` is sent: the video receiver starts a new run (the outbox says it)."""
        self.out.video_restart = True

    def video_answered(self, command: str, reply: str | None) -> None:
        """The Tello's reply (None: none came) to ``streamon``/``streamoff``."""
        accepted = reply is not None and is_ok(reply)
        self.video.on_result(command, accepted, self.now)
        if accepted:
            log.info("video: %s", "streaming" if command == STREAMON else "stream off")
            return
        video, attempts = self.video, self.video.policy.attempts
        why = f"{command} {'refused: ' + reply if reply else 'unanswered'}"
        if video.gave_up:
            self.text(
                SEVERITY_WARNING,
                f"bridge: video: {why} {attempts} times; tried again when the demand changes",
            )
        log.warning("video: %s (%d of %d tries)", why, video.failures, attempts)

    def require_connected(self) -> None:
        """ServiceError when no state string is arriving."""
        if not self.connected:
            raise ServiceError("the Tello is not connected (no state string)", "unavailable")

    # ------------------------------------------------------------------ the Tello's side

    def on_reply(self, text: str, now: float, stamp: float) -> None:
        """One datagram on the command socket (a reply, matched to the command it answers)."""
        self._at(now, stamp)
        if self.matcher.on_reply(text.strip(), now) is None:
            log.debug("reply %r matched no command", text)
        self.advance(now, stamp)

    def on_state(self, data: bytes, now: float, stamp: float) -> None:
        """One state datagram: telemetry samples, landed state, connection."""
        self._at(now, stamp)
        try:
            state = parse_state(data)
        except StateError as exc:
            self.malformed_states += 1
            if self.malformed_states <= 3 or self.malformed_states % 100 == 0:
                log.warning("malformed state string (%d so far): %s", self.malformed_states, exc)
            return
        self.states_received += 1
        self._last_state_at = now
        if not self.connected:
            log.info("Tello connected (state strings arriving)")
        self.connected = True
        self.telemetry.on_state(state, now)
        self.failsafe.on_flying(self.telemetry.landed.flying)
        pose, local, body = self.telemetry.messages(stamp)
        self.publish(registry.LOCAL_POSE, pose)
        self.publish(registry.VELOCITY_LOCAL, local)
        self.publish(registry.VELOCITY_BODY, body)
        self._periodic()
        if self.operations:
            self.advance(now, stamp)

    def _periodic(self) -> None:
        now, landed = self.now, self.telemetry.landed.state
        if landed != self._last_ext_value or now - self._last_ext_pub >= (
            1.0 / self.config.extended_state_rate_hz
        ):
            self._last_ext_value, self._last_ext_pub = landed, now
            self.publish(
                registry.EXTENDED_STATE,
                ExtendedState(header=Header(stamp=self.stamp), landed_state=landed),
            )
        if now - self._last_battery_pub >= 1.0 / self.config.battery_rate_hz:
            self._last_battery_pub = now
            self.publish(registry.BATTERY, self.telemetry.battery_message(self.stamp))
        self.publish_state()

    # ------------------------------------------------------------------ state publication

    def state_message(self) -> State:
        """The State the bridge publishes now."""
        flying = self.telemetry.landed.flying
        return State(
            header=Header(stamp=self.stamp),
            connected=self.connected,
            armed=flying,
            guided=self.connected and self.sdk_mode,
            manual_input=False,
            mode="SDK" if self.sdk_mode else "",
            system_status=4 if flying else 3,
            autopilot="tello",
            failsafe=self.failsafe.state,
            commander=self.commander,
        )

    def hold_here(self) -> None:
        """A cancel's hold: ``stop`` (the Tello hovers where it is, its move abandoned)."""
        self.start(ops.hover(self), self.now, self.stamp, background=True)

    def publish_state(self, *, force: bool = False) -> None:
        """Publish State if it changed (or ``force``, or the periodic time has come)."""
        msg = self.state_message()
        key = (msg.connected, msg.armed, msg.guided, msg.mode, msg.failsafe, msg.commander)
        due = self.now - self._last_state_pub >= 1.0 / self.config.state_rate_hz
        if force or due or key != self._last_state_key:
            self._last_state_key, self._last_state_pub = key, self.now
            self.publish(registry.STATE, msg)

    def text(self, severity: int, text: str) -> None:
        """Publish a StatusText of the bridge's own."""
        header = Header(stamp=self.stamp, frame_id="bridge")
        self.publish(registry.STATUSTEXT, StatusText(header=header, severity=severity, text=text))

    # ------------------------------------------------------------------ setpoints and control

    def check_setpoint(self, target: PositionTarget) -> Kind:
        return validate(target, self.scale)

    def refuse_envelope(self, target: PositionTarget, kind: Kind) -> EnvelopeError | None:
        return missions.refuse_setpoint(self, target, kind)

    def fly_setpoint(self, target: PositionTarget, kind: Kind) -> None:
        """Remembered: the tick flies it."""
        self.failsafe.on_setpoint(target, kind, self.now)

    def tick(self, now: float, stamp: float, *, camera_watched: bool = False) -> None:
        """The control tick (``rc_rate_hz``): link supervision, the failsafe, the sticks or the
        stop, keep-alive, the failsafe's landing, reconnection, periodic State, operations,
        then the video's switch when the command slot is free (``camera_watched``: a
        subscriber matches the camera's keys now)."""
        self._at(now, stamp)
        if self.connected and now - self._last_state_at > self.config.link_timeout:
            self.connected = False
            self.sdk_mode = False
            log.warning("Tello link lost: no state string for %.1f s", now - self._last_state_at)
        tick = self.failsafe.tick(now)
        self._report(tick)
        self.show_commander()
        sticks = self._sticks(tick)
        landed = self.telemetry.landed.state
        maneuvering = landed in (LANDED_STATE_TAKEOFF, LANDED_STATE_LANDING)
        if sticks is not None and not maneuvering and landed != LANDED_STATE_ON_GROUND:
            self.send(rc_command(sticks))
            self.last_sticks = sticks
            self.rc_sent += 1
        if tick.request == LAND and (self._land_op is None or self._land_op.done):
            self._land_op = self.start(ops.failsafe_land(self), now, stamp, background=True)
        if (not self.connected or not self.sdk_mode) and (
            now - self._last_reconnect >= self.config.reconnect_s
        ):
            self._last_reconnect = now
            if self._connect_op is None or self._connect_op.done:
                self._connect_op = self.start(ops.connect(self), now, stamp, background=True)
        missions.tick(self)
        self.publish_state()
        self.advance(now, stamp)
        self._switch_video(camera_watched)

    def _switch_video(self, watched: bool) -> None:
        """Start ``streamon``/``streamoff`` when the demand asks for it. Called after the
        operations have moved on, so a flight command waiting for the slot has taken it."""
        command = self.video.next_command(
            self.now,
            watched=watched,
            connected=self.connected and self.sdk_mode,
            slot_free=not self.command_busy,
        )
        if command is not None:
            self.start(ops.switch_video(self, command), self.now, self.stamp, background=True)

    def _sticks(self, tick: Tick) -> Sticks | None:
        """The sticks of the fresh setpoint, a stop, or None (send nothing)."""
        if tick.fly is not None:
            target, kind = tick.fly
            position = self.telemetry.position_enu or (0.0, 0.0, 0.0)
            vx, vy, vz, yaw_rate = body_velocity(
                target, kind, position, self.telemetry.yaw_enu, self.scale
            )
            return sticks_from_flu(vx, vy, vz, yaw_rate, self.scale)
        return STOP if tick.stop else None

    def _report(self, tick: Tick) -> None:
        for t in tick.transitions:
            level = logging.WARNING if t.new else logging.INFO
            log.log(level, "failsafe %r -> %r: %s", t.old, t.new, t.reason)
            severity = SEVERITY_WARNING if t.new else SEVERITY_INFO
            self.text(severity, f"bridge: failsafe {t.new or 'none'}: {t.reason}")
        if tick.transitions:
            self.publish_state(force=True)
