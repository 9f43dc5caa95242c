"""The bridge process: a Tello (SDK 2.0 over UDP) <-> MAVROS-equivalent Zenoh keys (README.md).

Threads: replies (command socket -> :class:`ReplyMatcher`), state (state strings -> telemetry
keys), control at ``rc_rate_hz`` (failsafe, ``rc`` sticks, keep-alive, link supervision,
periodic State), video (datagrams -> decoder -> newest frame) and its publisher, plus the
Node's service workers (commands wait for the Tello's reply).

Size: about 800 lines, the debt of this file: its logic still sits beside its I/O. It needs the
split bridge_mavlink had (a pure core taking replies, state strings and time; a thin node).
"""

from __future__ import annotations

import logging
import math
import re
import threading
import time

import msgspec

from dronewrapper.images import bgr_to_image, bgr_to_jpeg
from dronewrapper.msgs import registry
from dronewrapper.msgs.mavros import (
    LANDED_STATE_IN_AIR,
    LANDED_STATE_LANDING,
    LANDED_STATE_ON_GROUND,
    LANDED_STATE_TAKEOFF,
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
from dronewrapper.msgs.std import Header
from dronewrapper.runtime import Node, Ratekeeper, ServiceError
from dronewrapper.security.guard import CommandGuard
from dronewrapper.security.wifi import open_wifi_warning
from dronewrapper_bridge_tello.failsafe import LAND, Failsafe, FailsafeConfig, Tick
from dronewrapper_bridge_tello.link import TelloAddress, TelloLink
from dronewrapper_bridge_tello.replies import Pending, ReplyMatcher, is_ok
from dronewrapper_bridge_tello.state import StateError, parse_state
from dronewrapper_bridge_tello.sticks import (
    STOP,
    SetpointError,
    StickScale,
    body_velocity,
    rc_command,
    sticks_from_flu,
    validate,
)
from dronewrapper_bridge_tello.telemetry import Telemetry
from dronewrapper_bridge_tello.video import FrameAssembler, H264Decoder, NewestFrame

log = logging.getLogger("bridge_tello")

MAV_RESULT_ACCEPTED = 0
MAV_RESULT_DENIED = 2
MAV_RESULT_UNSUPPORTED = 3
RESULT_NO_REPLY = -1
SEVERITY_WARNING = 4
SEVERITY_INFO = 6

SDK_MODES = ("OFFBOARD", "GUIDED", "SDK")
HOVER_MODES = ("AUTO.LOITER", "HOLD", "LOITER", "POSCTL", "BRAKE")
LAND_MODES = ("AUTO.LAND", "LAND")
EMERGENCY_MODES = ("EMERGENCY",)
ALL_MODES = SDK_MODES + HOVER_MODES + LAND_MODES + EMERGENCY_MODES

# param id -> (read command, settable with "<command> <value>" in [lo, hi] or None)
PARAMS: dict[str, tuple[str, tuple[str, float, float] | None]] = {
    "SPEED": ("speed?", ("speed", 10.0, 100.0)),  # cm/s of the move commands
    "BATTERY": ("battery?", None),  # %
    "FLIGHT_TIME": ("time?", None),  # s of motor time
    "HEIGHT": ("height?", None),  # dm
    "TOF": ("tof?", None),  # mm
    "BARO": ("baro?", None),  # m
    "WIFI_SNR": ("wifi?", None),
    "SDK_VERSION": ("sdk?", None),
}
_NUMBER = re.compile(r"-?\d+(?:\.\d+)?")


class Config(msgspec.Struct, kw_only=True, forbid_unknown_fields=True):
    """bridge_tello configuration (units in the names' docs; see README.md)."""

    tello_address: str = "192.168.10.1"  # the Tello (a simulated one: 127.0.0.1)
    command_port: int = 8889
    local_address: str = "0.0.0.0"  # where our three sockets bind
    local_command_port: int = 0  # 0: any
    state_port: int = 8890
    video_port: int = 11111
    video: bool = True  # streamon and publish cam_frontal/image_raw
    compressed: bool = False  # also publish JPEG on image_raw/compressed (else only on request)
    jpeg_quality: int = 80
    video_chunk: int = 1460  # bytes of a full video datagram (a shorter one ends a frame)
    velocity_frame: str = "reference"  # reference | body_frd: the frame of vgx, vgy, vgz
    reference_yaw_deg: float = 0.0  # ENU yaw of the Tello's power-on heading (0: local +x)
    velocity_unit: float = 0.1  # m/s per vg* unit (the Tello sends dm/s)
    height_source: str = "h"  # h | tof
    tof_ground_cm: float = 10.0  # tof reading on the ground
    rc_rate_hz: float = 20.0  # rc stream while commanded
    setpoint_timeout: float = 0.5  # s: setpoints expire -> rc 0 0 0 0 (hover)
    commander_lost_timeout: float = 5.0  # s without setpoint while flying -> action
    commander_lost_action: str = "land"  # land | hold
    keepalive_s: float = 3.0  # s without any command while flying -> rc 0 0 0 0
    command_timeout: float = 1.0  # s to wait for the reply to a quick command
    command_attempts: int = 3
    takeoff_timeout: float = 20.0  # s: the Tello replies ok once the take-off is over
    land_timeout: float = 20.0
    move_timeout: float = 15.0  # s: up/down after take-off
    link_timeout: float = 1.5  # s without a state string -> disconnected
    reconnect_s: float = 1.0  # s between 'command' attempts while disconnected
    state_rate_hz: float = 2.0  # periodic State (also on change)
    extended_state_rate_hz: float = 4.0
    battery_rate_hz: float = 1.0
    command_lease: bool = False  # obey one commander at a time (security.lease)
    command_lease_ttl_s: float = 10.0  # s: a silent holder loses the lease
    scale: StickScale = msgspec.field(default_factory=StickScale)

    def __post_init__(self) -> None:
        self.failsafe_config()  # raises ValueError naming a bad timeout or action
        if not 20.0 <= self.rc_rate_hz <= 50.0:
            raise ValueError(f"rc_rate_hz must be in [20, 50], got {self.rc_rate_hz}")
        if self.velocity_frame not in ("reference", "body_frd"):
            raise ValueError(
                f"velocity_frame must be reference or body_frd, got {self.velocity_frame!r}"
            )
        if not (math.isfinite(self.reference_yaw_deg) and abs(self.reference_yaw_deg) <= 360):
            raise ValueError("reference_yaw_deg must be in [-360, 360]")
        if self.height_source not in ("h", "tof"):
            raise ValueError(f"height_source must be h or tof, got {self.height_source!r}")
        if self.command_attempts < 1:
            raise ValueError("command_attempts must be >= 1")
        for name in ("state_rate_hz", "extended_state_rate_hz", "battery_rate_hz"):
            if not getattr(self, name) > 0:
                raise ValueError(f"{name} must be > 0")
        if not self.command_lease_ttl_s > 0:
            raise ValueError("command_lease_ttl_s must be > 0")
        if not 1 <= self.jpeg_quality <= 100:
            raise ValueError("jpeg_quality must be in [1, 100]")

    def failsafe_config(self) -> FailsafeConfig:
        """The failsafe's settings, from this config's flat keys (validated there)."""
        return FailsafeConfig(
            setpoint_timeout=self.setpoint_timeout,
            commander_lost_timeout=self.commander_lost_timeout,
            commander_lost_action=self.commander_lost_action,
            keepalive_s=self.keepalive_s,
        )


def _number(text: str) -> float | None:
    match = _NUMBER.search(text)
    return float(match.group()) if match else None


class Bridge:
    """Everything the bridge does, wired to one Node and one Tello."""

    def __init__(self, node: Node, config: Config) -> None:
        self.node = node
        self.config = config
        self.scale = config.scale
        self.guard = CommandGuard(
            enabled=config.command_lease,
            ttl_s=config.command_lease_ttl_s,
            on_change=lambda: self.publish_state(force=True),
        )
        self.failsafe = Failsafe(config.failsafe_config())
        self.telemetry = Telemetry(
            velocity_frame=config.velocity_frame,
            reference_yaw=math.radians(config.reference_yaw_deg),
            velocity_unit=config.velocity_unit,
            height_source=config.height_source,
            tof_ground_cm=config.tof_ground_cm,
        )
        self.matcher = ReplyMatcher()
        self.link = TelloLink(
            TelloAddress(
                tello_address=config.tello_address,
                command_port=config.command_port,
                local_address=config.local_address,
                local_command_port=config.local_command_port,
                state_port=config.state_port,
                video_port=config.video_port,
            ),
            video=config.video,
        )
        self._lock = threading.RLock()  # telemetry, failsafe, state
        self._reply_cond = threading.Condition()
        self._cmd_lock = threading.Lock()
        self.connected = False
        self.sdk_mode = False
        self.streaming = False
        self._last_state_at = -math.inf
        self._last_reconnect = -math.inf
        self._reconnecting = False
        self._landing_thread: threading.Thread | None = None
        self._last_state_key: tuple | None = None
        self._last_state_pub = -math.inf
        self._last_ext_pub = -math.inf
        self._last_ext_value = -1
        self._last_battery_pub = -math.inf
        self.malformed_states = 0
        self.states_received = 0
        self.rc_sent = 0
        self.rejected_setpoints = 0
        self._last_reject_log = -math.inf
        self.last_sticks = STOP
        self.assembler = FrameAssembler(chunk=config.video_chunk)
        self.decoder = H264Decoder()
        self.newest = NewestFrame()
        self.frames_published = 0

        self.pub_state = node.publisher(registry.STATE)
        self.pub_ext = node.publisher(registry.EXTENDED_STATE)
        self.pub_pose = node.publisher(registry.LOCAL_POSE)
        self.pub_vbody = node.publisher(registry.VELOCITY_BODY)
        self.pub_vlocal = node.publisher(registry.VELOCITY_LOCAL)
        self.pub_battery = node.publisher(registry.BATTERY)
        self.pub_text = node.publisher(registry.STATUSTEXT)
        self.pub_image = node.publisher(registry.IMAGE_RAW, camera="cam_frontal")
        self.pub_jpeg = node.publisher(registry.IMAGE_COMPRESSED, camera="cam_frontal")

    # ------------------------------------------------------------------ lifecycle

    def start(self) -> list[threading.Thread]:
        """Subscribe, serve, and start the loops (returns the threads)."""
        self.node.subscribe(registry.SETPOINT_RAW_LOCAL, self.on_setpoint)
        self.node.serve(registry.ARMING, self.handle_arming)
        self.node.serve(registry.TAKEOFF, self.handle_takeoff)
        self.node.serve(registry.LAND, self.handle_land)
        self.node.serve(registry.SET_MODE, self.handle_set_mode)
        self.node.serve(registry.PARAM_GET, self.handle_param_get)
        self.node.serve(registry.PARAM_SET, self.handle_param_set)
        self.guard.serve(self.node)
        loops = [
            (self._reply_loop, "tello-replies"),
            (self._state_loop, "tello-state"),
            (self._control_loop, "tello-control"),
        ]
        if self.config.video:
            loops += [(self._video_loop, "tello-video"), (self._image_loop, "tello-images")]
        threads = [threading.Thread(target=f, name=n, daemon=True) for f, n in loops]
        for thread in threads:
            thread.start()
        self.publish_state(force=True)
        return threads

    def _jpeg_wanted(self) -> bool:
        """JPEG when configured, or while a subscriber matches image_raw/compressed."""
        if self.config.compressed:
            return True
        try:
            return bool(self.pub_jpeg._pub.matching_status.matching)
        except Exception:
            return False

    # ------------------------------------------------------------------ commands

    def command(
        self, text: str, *, timeout: float | None = None, attempts: int | None = None
    ) -> str | None:
        """Send ``text`` and wait for its reply (retries); returns the reply or None."""
        pending = Pending(
            text,
            timeout=timeout or self.config.command_timeout,
            attempts=attempts or self.config.command_attempts,
        )
        with self._cmd_lock, self._reply_cond:
            while not self.node.stop_event.is_set():
                now = time.monotonic()
                if pending.due(now):
                    self.matcher.sent(pending, now)
                    self._send(text, now)
                if pending.finished(now):
                    break
                self._reply_cond.wait(max(0.005, pending.wake_at(now) - now))
            if pending.sent > 1 or pending.reply is None:
                # give stray replies to the other sends their time, then forget them
                settle = time.monotonic() + min(0.3, self.config.command_timeout)
                while time.monotonic() < settle and self.matcher.waiting():
                    self._reply_cond.wait(0.05)
            self.matcher.forget(pending)
        if pending.reply is None:
            log.warning("%r: no reply after %d attempt(s)", text, pending.sent)
        elif not is_ok(pending.reply) and not text.endswith("?"):
            log.warning("%r -> %r", text, pending.reply)
        return pending.reply

    def _send(self, text: str, now: float) -> None:
        try:
            self.link.send(text)
        except OSError as exc:
            log.warning("cannot send %r: %s", text, exc)
            return
        with self._lock:
            self.failsafe.on_sent(now)

    def _reply_loop(self) -> None:
        stop = self.node.stop_event
        while not stop.is_set():
            try:
                data, _ = self.link.command.recvfrom(2048)
            except TimeoutError:
                continue
            except OSError:
                if stop.wait(0.2):
                    return
                continue
            text = data.decode("utf-8", "replace").strip()
            with self._reply_cond:
                answered = self.matcher.on_reply(text, time.monotonic())
                self._reply_cond.notify_all()
            if answered is None:
                log.debug("reply %r matched no command", text)

    # ------------------------------------------------------------------ state

    def _state_loop(self) -> None:
        stop = self.node.stop_event
        while not stop.is_set():
            try:
                data, _ = self.link.state.recvfrom(2048)
            except TimeoutError:
                continue
            except OSError:
                if stop.wait(0.2):
                    return
                continue
            try:
                self.handle_state(data, time.time(), time.monotonic())
            except Exception:
                self.node.callback_errors["state"] += 1
                log.exception("error handling a state string")

    def handle_state(self, data: bytes, stamp: float, now: float) -> None:
        """One state datagram (``stamp`` wall s, ``now`` monotonic s)."""
        try:
            state = parse_state(data)
        except StateError as exc:
            self.malformed_states += 1
            if self.malformed_states <= 3 or self.malformed_states % 100 == 0:
                log.warning("malformed state string (%d so far): %s", self.malformed_states, exc)
            return
        with self._lock:
            self.states_received += 1
            self._last_state_at = now
            reconnected = not self.connected
            self.connected = True
            self.telemetry.on_state(state, now)
            self.failsafe.on_flying(self.telemetry.landed.flying)
            pose, local, body = self.telemetry.messages(stamp)
        if reconnected:
            log.info("Tello connected (state strings arriving)")
        self.pub_pose.put(pose)
        self.pub_vlocal.put(local)
        self.pub_vbody.put(body)
        self._periodic(now, stamp)

    def _periodic(self, now: float, stamp: float) -> None:
        landed = self.telemetry.landed.state
        if landed != self._last_ext_value or now - self._last_ext_pub >= (
            1.0 / self.config.extended_state_rate_hz
        ):
            self._last_ext_value, self._last_ext_pub = landed, now
            self.pub_ext.put(ExtendedState(header=Header(stamp=stamp), landed_state=landed))
        if now - self._last_battery_pub >= 1.0 / self.config.battery_rate_hz:
            self._last_battery_pub = now
            self.pub_battery.put(self.telemetry.battery_message(stamp))
        self.publish_state()

    def state_message(self) -> State:
        """The State the bridge publishes now."""
        flying = self.telemetry.landed.flying
        return State(
            header=Header(stamp=time.time()),
            connected=self.connected,
            armed=flying,
            guided=self.connected and self.sdk_mode,
            manual_input=False,
            mode="SDK" if self.sdk_mode else "",
            system_status=4 if flying else 3,
            autopilot="tello",
            failsafe=self.failsafe.state,
            commander=self.guard.holder(),
        )

    def publish_state(self, *, force: bool = False) -> None:
        msg = self.state_message()
        key = (msg.connected, msg.armed, msg.guided, msg.mode, msg.failsafe, msg.commander)
        now = time.monotonic()
        if (
            force
            or key != self._last_state_key
            or now - self._last_state_pub >= (1.0 / self.config.state_rate_hz)
        ):
            self._last_state_key, self._last_state_pub = key, now
            self.pub_state.put(msg)

    def _text(self, severity: int, text: str) -> None:
        self.pub_text.put(
            StatusText(
                header=Header(stamp=time.time(), frame_id="bridge"), severity=severity, text=text
            )
        )

    # ------------------------------------------------------------------ setpoints and control

    def on_setpoint(self, target: PositionTarget) -> None:
        """A PositionTarget from a commander: validated, then flown by the control loop."""
        if not self.guard.admit_setpoint():
            return
        try:
            kind = validate(target, self.scale)
        except SetpointError as exc:
            self.rejected_setpoints += 1
            now = time.monotonic()
            if now - self._last_reject_log >= 2.0:
                self._last_reject_log = now
                log.warning("setpoint refused (%d so far): %s", self.rejected_setpoints, exc)
            return
        with self._lock:
            self.failsafe.on_setpoint(target, kind, time.monotonic())

    def _control_loop(self) -> None:
        rate = Ratekeeper(self.config.rc_rate_hz, stop=self.node.stop_event)
        while rate.sleep():
            now = time.monotonic()
            try:
                self._control_tick(now)
            except Exception:
                self.node.callback_errors["control"] += 1
                log.exception("control loop error")

    def _control_tick(self, now: float) -> None:
        with self._lock:
            if self.connected and now - self._last_state_at > self.config.link_timeout:
                self.connected = False
                self.sdk_mode = False
                log.warning(
                    "Tello link lost: no state string for %.1f s", now - self._last_state_at
                )
            tick = self.failsafe.tick(now)
            landed = self.telemetry.landed.state
            sticks = None
            if tick.fly is not None:
                target, kind = tick.fly
                position = self.telemetry.position_enu or (0.0, 0.0, 0.0)
                vx, vy, vz, yaw_rate = body_velocity(
                    target, kind, position, self.telemetry.yaw_enu, self.scale
                )
                sticks = sticks_from_flu(vx, vy, vz, yaw_rate, self.scale)
            elif tick.stop:
                sticks = STOP
        self._report(tick)
        maneuvering = landed in (LANDED_STATE_TAKEOFF, LANDED_STATE_LANDING)
        if sticks is not None and not maneuvering and landed != LANDED_STATE_ON_GROUND:
            self._send(rc_command(sticks), now)
            self.last_sticks = sticks
            self.rc_sent += 1
        if tick.request == LAND:
            self._start_failsafe_land()
        if (not self.connected or not self.sdk_mode) and now - self._last_reconnect >= (
            self.config.reconnect_s
        ):
            self._last_reconnect = now
            if not self._reconnecting:
                self._reconnecting = True
                threading.Thread(
                    target=self._enter_sdk_mode, name="tello-connect", daemon=True
                ).start()
        self.publish_state()

    def _report(self, tick: Tick) -> None:
        for t in tick.transitions:
            level = logging.WARNING if t.new else logging.INFO
            log.log(level, "failsafe %r -> %r: %s", t.old, t.new, t.reason)
            self._text(
                SEVERITY_WARNING if t.new else SEVERITY_INFO,
                f"bridge: failsafe {t.new or 'none'}: {t.reason}",
            )
        if tick.transitions:
            self.publish_state(force=True)

    def _enter_sdk_mode(self) -> None:
        """``command`` until ``ok`` (SDK mode), then ``streamon`` for the video."""
        try:
            reply = self.command("command", attempts=1)
            if reply is None or not is_ok(reply):
                return
            if not self.sdk_mode:
                log.info("Tello in SDK mode")
            self.sdk_mode = True
            if self.config.video:
                reply = self.command("streamon")
                self.streaming = reply is not None and is_ok(reply)
            self.publish_state(force=True)
        finally:
            self._reconnecting = False

    def _start_failsafe_land(self) -> None:
        if self._landing_thread is not None and self._landing_thread.is_alive():
            return

        def land() -> None:
            reply = self._land()
            if reply is not None and is_ok(reply):
                log.warning("failsafe land: done")
            else:
                log.error("failsafe land: %s", reply or "no reply")

        self._landing_thread = threading.Thread(
            target=land, name="tello-failsafe-land", daemon=True
        )
        self._landing_thread.start()

    # ------------------------------------------------------------------ video

    def _video_loop(self) -> None:
        stop = self.node.stop_event
        sock = self.link.video
        assert sock is not None
        while not stop.is_set():
            try:
                data = sock.recv(65535)
            except TimeoutError:
                continue
            except OSError:
                if stop.wait(0.2):
                    return
                continue
            stamp = time.time()
            for frame in self.assembler.feed(data):
                for decoded in self.decoder.decode(frame):
                    self.newest.put(decoded, stamp)

    def _image_loop(self) -> None:
        stop = self.node.stop_event
        seq = 0
        while not stop.is_set():
            item = self.newest.take(0.2)
            if item is None:
                continue
            frame, stamp = item
            try:
                image = frame.to_ndarray(format="bgr24")
            except Exception:
                self.decoder.counts.corrupt += 1
                continue
            self.pub_image.put(bgr_to_image(image, stamp, "cam_frontal", seq))  # a view: no copy
            if self._jpeg_wanted():
                jpeg = bgr_to_jpeg(image, stamp, "cam_frontal", seq, self.config.jpeg_quality)
                self.pub_jpeg.put(jpeg)
            seq += 1
            self.frames_published += 1

    # ------------------------------------------------------------------ services

    def _require_connected(self) -> None:
        if not self.connected:
            raise ServiceError("the Tello is not connected (no state string)", "unavailable")

    @staticmethod
    def _result(reply: str | None, what: str) -> tuple[int, str]:
        if reply is None:
            return RESULT_NO_REPLY, f"{what}: no reply from the Tello"
        if is_ok(reply):
            return MAV_RESULT_ACCEPTED, f"{what} accepted"
        return MAV_RESULT_DENIED, f"{what} refused by the Tello: {reply}"

    def handle_arming(self, request: CommandBool) -> CommandBoolResult:
        """A Tello has no arming. arm: enter SDK mode (``command``); the motors start with
        take-off. disarm: accepted on the ground (motors are off), refused in flight."""
        self.guard.admit_command("arming")
        self._require_connected()
        if not request.value:
            if self.telemetry.landed.flying:
                return CommandBoolResult(
                    success=False,
                    result=MAV_RESULT_DENIED,
                    message="a flying Tello cannot disarm: land (or set_mode EMERGENCY)",
                )
            return CommandBoolResult(
                success=True, result=0, message="a Tello has no arming: motors are off"
            )
        reply = self.command("command")
        result, message = self._result(reply, "command (SDK mode)")
        if result == 0:
            self.sdk_mode = True
            message = "a Tello has no arming: SDK mode confirmed, the motors start with take-off"
        return CommandBoolResult(success=result == 0, result=result, message=message)

    def handle_takeoff(self, request: CommandTOL) -> CommandTOLResult:
        """``takeoff`` (waits for the Tello's ok, which comes once it hovers, ~1 m), then
        ``up``/``down`` to ``altitude`` m above the take-off point when one is given."""
        self.guard.admit_command("takeoff")
        self._require_connected()
        height = request.altitude
        if not math.isnan(height) and not (math.isfinite(height) and 0.0 < height <= 30.0):
            raise ValueError(f"altitude must be in (0, 30] m or NaN, got {height!r}")
        if self.telemetry.landed.state == LANDED_STATE_IN_AIR:
            return CommandTOLResult(success=True, result=0, message="already flying")
        with self._lock:
            self.telemetry.reset_position()
            self.telemetry.landed.on_takeoff_sent()
            self.failsafe.on_takeoff_or_land()
        self.publish_state(force=True)
        reply = self.command("takeoff", timeout=self.config.takeoff_timeout, attempts=1)
        result, message = self._result(reply, "takeoff")
        if reply is None and (self.telemetry.position_enu or (0, 0, 0))[2] > 0.3:
            result, message = 0, "takeoff: reply lost, but the Tello is in the air"
        with self._lock:
            self.telemetry.landed.on_takeoff_done(result == 0)
        self.publish_state(force=True)
        if result != 0 or math.isnan(height):
            return CommandTOLResult(success=result == 0, result=result, message=message)
        z = self._settled_height()
        error_cm = (height - z) * 100.0
        log.info("take-off done at %.2f m; %.2f m asked", z, height)
        # the SDK's moves are 20-500 cm: correct only errors beyond 8 cm (a 20 cm move for a
        # smaller error would overshoot by more than it corrects)
        if abs(error_cm) > 8.0:
            verb = "up" if error_cm > 0 else "down"
            cm = round(min(500.0, max(20.0, abs(error_cm))))
            reply = self.command(f"{verb} {cm}", timeout=self.config.move_timeout, attempts=1)
            move_result, move_message = self._result(reply, f"{verb} {cm}")
            message += f"; {move_message}"
            if move_result != 0:
                return CommandTOLResult(success=False, result=move_result, message=message)
        return CommandTOLResult(success=True, result=0, message=message)

    def _settled_height(self, timeout: float = 3.0) -> float:
        """The height (m) once the climb has stopped: the take-off ``ok`` may come while the
        Tello still rises the last centimetres. Settled = two state strings in a row with
        |vz| < 0.1 m/s; gives up after ``timeout`` s."""
        deadline = time.monotonic() + timeout
        calm, seen = 0, self.states_received
        while time.monotonic() < deadline and calm < 2 and not self.node.stop_event.is_set():
            time.sleep(0.02)
            if self.states_received != seen:
                seen = self.states_received
                calm = calm + 1 if abs(self.telemetry.velocity[2]) < 0.1 else 0
        return (self.telemetry.position_enu or (0.0, 0.0, 0.0))[2]

    def _land(self) -> str | None:
        with self._lock:
            self.telemetry.landed.on_land_sent()
            self.failsafe.on_takeoff_or_land()
        self.publish_state(force=True)
        reply = self.command("land", timeout=self.config.land_timeout, attempts=1)
        with self._lock:
            self.telemetry.landed.on_land_done(reply is not None and is_ok(reply))
        self.publish_state(force=True)
        return reply

    def handle_land(self, request: CommandTOL) -> CommandTOLResult:
        """``land`` here (waits for the Tello's ok, given once on the ground)."""
        self.guard.admit_command("land")
        self._require_connected()
        for name, value, bound in (
            ("latitude", request.latitude, 90.0),
            ("longitude", request.longitude, 180.0),
        ):
            if not math.isnan(value) and not (math.isfinite(value) and abs(value) <= bound):
                raise ValueError(f"{name} must be within ±{bound:g} degrees or NaN, got {value!r}")
        if self.telemetry.landed.state == LANDED_STATE_ON_GROUND:
            return CommandTOLResult(success=True, result=0, message="already on the ground")
        result, message = self._result(self._land(), "land")
        return CommandTOLResult(success=result == 0, result=result, message=message)

    def handle_set_mode(self, request: SetMode) -> SetModeResult:
        """Modes mapped onto Tello commands: OFFBOARD/GUIDED/SDK -> ``command``;
        AUTO.LOITER/HOLD/LOITER/POSCTL/BRAKE -> ``stop`` (hover); AUTO.LAND/LAND -> ``land``;
        EMERGENCY -> ``emergency`` (motors off at once: it falls)."""
        self.guard.admit_command("set_mode")
        self._require_connected()
        mode = request.custom_mode.strip().upper() if isinstance(request.custom_mode, str) else ""
        if mode not in ALL_MODES:
            raise ValueError(
                f"custom_mode {request.custom_mode[:40]!r} is not a Tello mode; "
                f"valid: {', '.join(ALL_MODES)}"
            )
        if mode in SDK_MODES:
            reply = self.command("command")
            if reply is not None and is_ok(reply):
                self.sdk_mode = True
        elif mode in HOVER_MODES:
            with self._lock:
                self.failsafe.on_takeoff_or_land()
            reply = self.command("stop")
        elif mode in LAND_MODES:
            if self.telemetry.landed.state == LANDED_STATE_ON_GROUND:
                return SetModeResult(mode_sent=True, result=0, message="already on the ground")
            reply = self._land()
        else:
            reply = self.command("emergency", attempts=1)
            with self._lock:
                self.telemetry.landed.on_emergency()
        result, message = self._result(
            reply, f"{mode} ({'emergency' if mode in EMERGENCY_MODES else 'mapped'})"
        )
        return SetModeResult(mode_sent=result == 0, result=result, message=message)

    def _param_id(self, param_id: str) -> str:
        if not isinstance(param_id, str) or param_id.upper() not in PARAMS:
            shown = param_id[:40] if isinstance(param_id, str) else param_id
            raise ValueError(
                f"param_id {shown!r} is not a Tello parameter; known: {', '.join(PARAMS)}"
            )
        return param_id.upper()

    def handle_param_get(self, request: ParamGet) -> ParamGetResult:
        """Read commands (``speed?``, ``battery?`` ...) as parameters (numbers only)."""
        self._require_connected()
        param_id = self._param_id(request.param_id)
        reply = self.command(PARAMS[param_id][0])
        if reply is None:
            return ParamGetResult(success=False, message=f"{param_id}: no reply from the Tello")
        value = _number(reply)
        if value is None:
            return ParamGetResult(success=False, message=f"{param_id}: the Tello said {reply!r}")
        return ParamGetResult(success=True, value=ParamValue.of(value), message=reply)

    def handle_param_set(self, request: ParamSet) -> ParamSetResult:
        """Only SPEED (cm/s, ``speed x``, 10..100) can be written."""
        self.guard.admit_command("param_set")
        self._require_connected()
        param_id = self._param_id(request.param_id)
        setter = PARAMS[param_id][1]
        if setter is None:
            return ParamSetResult(success=False, message=f"{param_id} is read-only on a Tello")
        value = float(request.value.as_number())
        verb, low, high = setter
        if not (math.isfinite(value) and low <= value <= high):
            raise ValueError(
                f"value: {param_id} (real or integer) must be in [{low:g}, {high:g}], got {value!r}"
            )
        reply = self.command(f"{verb} {round(value)}")
        result, message = self._result(reply, f"{verb} {round(value)}")
        return ParamSetResult(
            success=result == 0, value=ParamValue.of(float(round(value))), message=message
        )


def run(node: Node, config: Config) -> int:
    """The service body: open the sockets, start the bridge, announce readiness, run."""
    try:
        bridge = Bridge(node, config)
    except OSError as exc:
        log.error("cannot open the Tello sockets on %s: %s", config.local_address, exc)
        return 1
    threads = bridge.start()
    node.announce()
    warning = open_wifi_warning()  # a Tello's Wi-Fi is open until a password is set
    if warning:
        log.warning("%s", warning)
    log.info(
        "bridge_tello ready: Tello %s:%d, listening on %s (namespace %s)",
        config.tello_address,
        config.command_port,
        config.local_address,
        node.ns,
    )
    node.spin()
    for thread in threads:
        thread.join(timeout=2.0)
    bridge.link.close()
    return 0


__all__ = ["Bridge", "Config", "run"]
