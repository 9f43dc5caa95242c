"""DroneWrapper: the paper's drone API over Zenoh, for real and simulated aircraft.

    from dronewrapper import DroneWrapper
    from time import sleep

    drone = DroneWrapper()              # namespace "drone", router tcp/127.0.0.1:7447
    drone.takeoff(h=2.5)                # arms, enters OFFBOARD/GUIDED, returns at 2.5 m
    drone.set_cmd_vel(az=1)             # spin at 1 rad/s, re-published at 30 Hz until changed
    sleep(5)
    drone.land()                        # returns on the ground

Frames and units (docs/design.md): local ENU fixed at the take-off point (x east, y north, z up, m);
body FLU (forward, left, up, m/s); angles in radians, yaw counter-clockwise positive.

A DroneWrapper stands on a node (the node contract, :mod:`dronewrapper.runtime.contract`): the
one it is given, or its own (:func:`dronewrapper.connection.open_node`). Its time is the node's
clock. The getters (:class:`dronewrapper.inputs.Getters`) read the newest message already
received (no network round trip) and raise :class:`~dronewrapper.errors.NoData` if none has
arrived yet. Blocking calls take timeouts and raise :class:`~dronewrapper.errors.Timeout`,
:class:`~dronewrapper.errors.CommandRefused` (with the autopilot's reason) or
:class:`~dronewrapper.errors.NotConnected` (:mod:`dronewrapper.connection` says why).
"""

from __future__ import annotations

import atexit
import collections
import getpass
import logging
import os
import socket
import threading
import weakref
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any, TypeVar

import numpy as np

from dronewrapper import connection, flying, images, setpoints, telemetry
from dronewrapper.discovery import default_connect
from dronewrapper.errors import (
    Cancelled,
    CommandRefused,
    InvalidArgument,
    NoData,
    NotConnected,
    Timeout,
)
from dronewrapper.inputs import Getters, Inputs
from dronewrapper.msgs import registry
from dronewrapper.msgs.lease import LeaseRequest
from dronewrapper.msgs.mavros import (
    LANDED_STATE_ON_GROUND,
    MASK_MIXED,
    MASK_POSITION,
    CommandBool,
    ParamGet,
    ParamSet,
    ParamValue,
    PositionTarget,
    SetMode,
    State,
    StatusText,
)
from dronewrapper.msgs.registry import Service, Topic
from dronewrapper.runtime.caller import commander_attachment
from dronewrapper.runtime.contract import NodeApi
from dronewrapper.runtime.errors import ServiceError, ServiceUnavailable
from dronewrapper.runtime.flight import Landing, Takeoff
from dronewrapper.runtime.options import is_local_endpoint
from dronewrapper.streamer import SetpointStreamer

T = TypeVar("T")

log = logging.getLogger("dronewrapper")


def default_commander(identity: str = "") -> str:
    """Our name on the command lease: ``$DRONEWRAPPER_COMMANDER``, the identity's name, or
    ``user@host``."""
    env = os.environ.get("DRONEWRAPPER_COMMANDER")
    if env:
        return env
    if identity:
        return Path(identity).stem if identity.endswith(".crt") else identity
    return f"{getpass.getuser()}@{socket.gethostname()}"


_open_wrappers: weakref.WeakSet[DroneWrapper] = weakref.WeakSet()


@atexit.register
def _close_all() -> None:
    """Close every wrapper still open at interpreter exit (an open Zenoh session can hang it)."""
    for wrapper in list(_open_wrappers):
        wrapper.close()


def _satisfied(value: object) -> bool:
    """Truthiness for wait_for: any numpy array counts as a result (not "ambiguous")."""
    if isinstance(value, np.ndarray):
        return True
    return bool(value)


class DroneWrapper(Getters):
    """One drone, reached through a Zenoh router. Several objects fly several drones.

    Args:
        name: the vehicle namespace (``drone``, ``drone1`` ...); default env
            ``DRONEWRAPPER_NAMESPACE`` or ``drone``.
        connect: the router endpoint, e.g. ``tcp/192.168.1.10:7447`` from a laptop; default env
            ``DRONEWRAPPER_CONNECT`` or ``tcp/127.0.0.1:7447``.
        timeout: seconds to reach the router and find a bridge whose autopilot is connected.
        mode: Zenoh session mode (``client``: everything through the router; ``peer``).
        cameras: the cameras to receive from the start (``frontal``, ``ventral``); ``()``
            receives none; None (default) subscribes to a camera the first time it is read, so
            frames cross the network only for a program that uses them.
        compressed_images: receive JPEG images (``.../image_raw/compressed``; needs OpenCV:
            ``pip install 'dronewrapper[images]'``) instead of raw ones. None (default): JPEG
            when the router is on another machine (raw 640x480 frames need ~220 Mbit/s per
            camera), raw on this one; without OpenCV it falls back to raw with a warning.
        land_on_exit: when used as a context manager, land on exit if flying (also after an
            exception); without it, exiting only stops commanding (the bridge hovers).
        setpoint_rate_hz: rate of the setpoint stream (>= 20 Hz).
        command_timeout: if not None, stop streaming a setpoint that was not renewed for this
            many seconds (a deadman for apps that may hang; the bridge then hovers). None keeps
            the paper's behaviour: stream until changed.
        service_timeout: seconds to wait for the bridge's reply to a service call.
        wait: wait for the bridge (True) or return at once after reaching the router.
        identity: our certificate for a ``tls/`` router (a key-store name or a path to
            NAME.crt, see ``dronewrapper keys``; env ``DRONEWRAPPER_IDENTITY``).
        commander: our name on the command lease (default: the identity's name, or
            ``user@host``); the bridge obeys one commander at a time, see take_command().
        node: the node to stand on (a service's ``Node``, or a ``FakeNode`` on the fake bus);
            not closed by :meth:`close`. None: the wrapper opens its own (``connect``, ``mode``
            and ``identity`` are for that one).

    Raises:
        NotConnected: no router at ``connect``, no bridge in namespace ``name``, or the bridge
            is up but its autopilot is not connected; the message says which.
    """

    def __init__(
        self,
        name: str | None = None,
        connect: str | None = None,
        timeout: float = 10.0,
        *,
        mode: str = "client",
        cameras: Sequence[str] | None = None,
        compressed_images: bool | None = None,
        land_on_exit: bool = False,
        setpoint_rate_hz: float = 30.0,
        command_timeout: float | None = None,
        service_timeout: float = 10.0,
        wait: bool = True,
        identity: str | None = None,
        commander: str | None = None,
        node: NodeApi | None = None,
    ) -> None:
        self.ns = name or os.environ.get("DRONEWRAPPER_NAMESPACE") or registry.DEFAULT_NAMESPACE
        registry.STATE.key(self.ns)  # validates the namespace (one key chunk)
        self.connect = connect or default_connect()
        self.land_on_exit = land_on_exit
        self.service_timeout = service_timeout
        self._closed = False
        self._warned_grounded = False
        identity = identity or os.environ.get("DRONEWRAPPER_IDENTITY", "")
        self.commander = commander or default_commander(identity)
        self._attachment = commander_attachment(self.commander)
        self.compressed_images = self._choose_compression(compressed_images, node, cameras)
        self._own_node = node is None
        if node is None:
            node = connection.open_node(
                self.ns, self.connect, timeout, mode=mode, identity=identity
            )
        self.node: NodeApi = node
        self.clock = node.clock
        deadline = self.clock.monotonic() + timeout
        _open_wrappers.add(self)
        try:
            self.inputs = Inputs(
                node, self.ns, compressed_images=self.compressed_images, cameras=cameras
            )
            self._setpoints = node.publisher(
                registry.SETPOINT_RAW_LOCAL, key=registry.SETPOINT_RAW_LOCAL.key(self.ns)
            )
            self._streamer = SetpointStreamer(
                self._publish_setpoint,
                clock=self.clock,
                rate_hz=setpoint_rate_hz,
                idle_timeout=command_timeout,
                name=f"{self.ns}-setpoints",
            )
            self._matching = self._setpoints.on_matching(self._on_setpoint_matching)
            self._aircraft = flying.WrapperAircraft(
                self.ns,
                state=self.inputs.state,
                extended=self.inputs.extended,
                pose=self.inputs.pose,
                status_texts=self.status_texts,
                set_target=self._command_setpoint,
                stop=self.stop_commanding,
                ask=self._ask,
                wall=self.clock.time,
            )
            if wait:
                self.wait_for_connection(max(0.0, deadline - self.clock.monotonic()))
        except BaseException:
            self.close()
            raise

    def _choose_compression(
        self, compressed: bool | None, node: NodeApi | None, cameras: Sequence[str] | None
    ) -> bool:
        """JPEG or raw frames (see the ``compressed_images`` argument)."""
        if compressed is None:
            remote = node is None and not is_local_endpoint(self.connect)
            compressed = remote and images.has_jpeg_decoder()
            if remote and not compressed:
                log.warning(
                    "the router %s is on another machine but OpenCV is missing, so camera "
                    "frames come raw (~220 Mbit/s each): pip install 'dronewrapper[images]'",
                    self.connect,
                )
        elif compressed and cameras != ():
            images.jpeg_decoder()  # fail now, not at the first frame, if OpenCV is missing
        return compressed

    @property
    def status_texts(self) -> collections.deque[StatusText]:
        """The autopilot's last 20 text messages (newest last)."""
        return self.inputs.status_texts

    @property
    def decode_errors(self) -> collections.Counter[str]:
        """Undecodable samples per key (the node's count)."""
        return self.node.decode_errors

    def subscribe(self, topic: Topic[T], callback: Callable[[T], None], **parts: str) -> Any:
        """Call ``callback(msg)`` for every decodable message on ``topic`` in this drone's
        namespace (``parts`` fill the other key fields, e.g. ``camera="cam_frontal"``).

        The callback may run on a Zenoh thread: keep it short. Undecodable samples are counted
        in ``decode_errors``; an exception in the callback is logged and never ends the
        subscription. ``undeclare()`` the returned subscriber to stop; :meth:`close` does too.
        """
        return self.inputs.subscribe(topic, callback, **parts)

    def _on_setpoint_matching(self, matching: bool) -> None:
        """The bridge's setpoint subscriber became (un)reachable: a link gap (router restart,
        lost Wi-Fi) withholds setpoints, and a command that went stale meanwhile is not resent
        (see runtime.setpoint_stream)."""
        if not self._closed:
            self._streamer.link(matching)

    def _publish_setpoint(self, target: PositionTarget) -> None:
        self._setpoints.put(target, attachment=self._attachment)

    # ------------------------------------------------------------------ lifecycle

    def __enter__(self) -> DroneWrapper:
        return self

    def __exit__(self, exc_type: object, exc: object, tb: object) -> None:
        try:
            self.stop_commanding()
            if self.land_on_exit and self.is_flying():
                try:
                    self.land()
                except Exception:
                    if exc is None:
                        raise
                    log.exception("land on exit failed")
        finally:
            self.close()

    def close(self) -> None:
        """Stop commanding, drop the subscriptions and close the node if it is ours.

        Idempotent; also done at interpreter exit. Does not land: the bridge hovers, then lands
        after its ``commander_lost_timeout``.
        """
        if self._closed:
            return
        self._closed = True
        _open_wrappers.discard(self)
        for part in ("_streamer", "_matching", "inputs", "_setpoints"):
            entity = getattr(self, part, None)
            if entity is not None:
                try:
                    entity.close() if hasattr(entity, "close") else entity.undeclare()
                except Exception as exc:  # a session already closed by its owner
                    log.debug("close %s: %s", part, exc)
        if self._own_node:
            self.node.close()

    def __repr__(self) -> str:
        state = self.inputs.state.value
        link = "closed" if self._closed else ("connected" if self.is_connected() else "waiting")
        mode = f" mode={state.mode} armed={state.armed}" if state else ""
        return f"DroneWrapper(name={self.ns!r}, connect={self.connect!r}, {link}{mode})"

    # ------------------------------------------------------------------ connection

    def is_connected(self) -> bool:
        """True if a fresh State (< 3 s old) says the bridge's autopilot is connected."""
        return connection.connected_state(self.inputs) is not None

    def wait_for_connection(self, timeout: float = 10.0) -> State:
        """Block until the bridge reports its autopilot connected and every telemetry stream the
        getters read (landed state, position, velocities, battery) has arrived; returns the State.

        Raises:
            NotConnected: no bridge, a bridge without an autopilot, or a stream still missing
                after ``timeout`` s (the message names the missing keys).
        """
        return connection.wait_for_connection(self.inputs, self.connect, timeout)

    def _no_reply(self, what: str, key: str, timeout: float) -> Exception:
        return connection.no_reply(self.node, self.ns, self.connect, what, key, timeout)

    # ------------------------------------------------------------------ waiting

    def wait_for(
        self,
        predicate: Callable[[], T],
        timeout: float,
        what: str = "condition",
        *,
        interval: float = 0.02,
    ) -> T:
        """Poll ``predicate()`` until it returns a truthy value, which is returned.

        A numpy array counts as truthy (``wait_for(drone.get_global_position, 5)`` returns the
        first fix); ``NoData`` raised by the predicate counts as "not yet".

        Raises:
            Timeout: still false after ``timeout`` seconds (the message names ``what``).
        """
        deadline = self.clock.monotonic() + timeout
        while True:
            try:
                value = predicate()
            except NoData:
                value = None
            if _satisfied(value):
                return value
            if self.clock.monotonic() >= deadline:
                raise Timeout(f"timed out after {timeout:g} s waiting for {what}")
            self.clock.sleep(interval)

    def wait_for_altitude(
        self, z: float, timeout: float = 30.0, *, tolerance: float = 0.1
    ) -> np.ndarray:
        """Block until the local ENU altitude is within ``tolerance`` m of ``z``; the position.

        Raises:
            Timeout: not there within ``timeout`` seconds (the message gives the altitude).
        """
        z = setpoints.finite("z", z)
        try:
            return self.wait_for(
                lambda: p if abs((p := self.get_position())[2] - z) <= tolerance else None,
                timeout,
                f"altitude {z:.2f} m",
            )
        except Timeout as exc:
            raise Timeout(f"{exc} (now {self._altitude_text()})") from None

    def wait_for_landed_state(self, landed_state: int, timeout: float = 30.0) -> int:
        """Block until :meth:`get_landed_state` equals ``landed_state``; returns it."""
        self.wait_for(
            lambda: self.get_landed_state() == landed_state,
            timeout,
            f"landed state {landed_state}",
        )
        return landed_state

    def wait_for_image(self, camera: str = "frontal", timeout: float = 10.0) -> np.ndarray:
        """Block until ``camera`` delivered a frame; returns the newest one (BGR).

        Raises:
            Timeout: no frame within ``timeout`` s (no camera publishing on the key).
        """
        holder = self.inputs.camera(camera)
        if holder is None:
            return self.get_image(camera)  # raises NoData naming the cameras= argument
        try:
            holder.wait(timeout)
        except TimeoutError:
            raise Timeout(
                f"no image on {holder.name} within {timeout:g} s: is a camera running "
                f"in namespace {self.ns!r}?"
            ) from None
        return self.get_image(camera)

    def _altitude_text(self) -> str:
        pose = self.inputs.pose.value
        return "no position" if pose is None else f"z={pose.pose.position.z:.2f} m"

    # ------------------------------------------------------------------ setpoints

    def set_cmd_pos(
        self,
        x: float = 0.0,
        y: float = 0.0,
        z: float | None = None,
        az: float | None = None,
        *,
        stamp: float | None = None,
    ) -> None:
        """Position control: fly to (x, y, z) local ENU metres facing yaw ``az`` (rad, ENU).

        Left out, ``z`` keeps the altitude (the one being commanded, else the current one) and
        ``az`` keeps the heading, so ``set_cmd_pos(1, 0)`` moves sideways instead of diving to
        the ground and turning east. Re-published at the stream rate until another command or
        :meth:`stop_commanding`. ``stamp`` (seconds since the Unix epoch) is carried in
        ``header.stamp`` (default now).

        Raises:
            InvalidArgument: an argument is not a finite number, or ``az`` is beyond a full turn
                (degrees by mistake); nothing is sent.
            NoData: ``z`` or ``az`` left out before any position arrived.
        """
        stamp = setpoints.check_stamp(stamp, self.clock.time())
        z = self._kept_altitude("set_cmd_pos") if z is None else z
        az = self._kept_yaw("set_cmd_pos") if az is None else az
        target = setpoints.position_target(x, y, z, az, stamp=stamp)
        self._warn_if_grounded("set_cmd_pos")
        self._command_setpoint(target)

    def set_cmd_vel(
        self,
        vx: float = 0.0,
        vy: float = 0.0,
        vz: float = 0.0,
        az: float = 0.0,
        *,
        stamp: float | None = None,
    ) -> None:
        """Velocity control: body FLU velocity (m/s) and yaw rate ``az`` (rad/s, CCW +).

        ``vx`` is forward, ``vy`` left, ``vz`` up on every aircraft. Re-published at the
        stream rate until changed: ``set_cmd_vel(az=1); sleep(5)`` spins for 5 s.

        Raises:
            InvalidArgument: an argument is not a finite number, or ``az`` is beyond a full turn
                per second (degrees by mistake); nothing is sent.
        """
        stamp = setpoints.check_stamp(stamp, self.clock.time())
        target = setpoints.velocity_target(vx, vy, vz, az, stamp=stamp)
        self._warn_if_grounded("set_cmd_vel")
        self._command_setpoint(target)

    def set_cmd_mix(
        self,
        vx: float = 0.0,
        vy: float = 0.0,
        z: float | None = None,
        az: float = 0.0,
        *,
        stamp: float | None = None,
    ) -> None:
        """Mixed control: body FLU vx, vy (m/s), altitude ``z`` (local ENU m), yaw rate (rad/s).

        Left out, ``z`` keeps the altitude (the one being commanded, else the current one).

        Raises:
            InvalidArgument: an argument is not a finite number (nothing is sent).
            NoData: ``z`` left out before any position arrived.
        """
        stamp = setpoints.check_stamp(stamp, self.clock.time())
        z = self._kept_altitude("set_cmd_mix") if z is None else z
        target = setpoints.mixed_target(vx, vy, z, az, stamp=stamp)
        self._warn_if_grounded("set_cmd_mix")
        self._command_setpoint(target)

    def _kept_altitude(self, what: str) -> float:
        """The altitude a setpoint without ``z`` keeps: the commanded one, else the current."""
        commanded = self._streamer.target
        if commanded is not None and commanded.type_mask in (MASK_POSITION, MASK_MIXED):
            return float(commanded.position.z)
        pose = self.inputs.pose.value
        if pose is None:
            raise NoData(f"{what}: z left out, and no position yet to keep the altitude of")
        return float(pose.pose.position.z)

    def _kept_yaw(self, what: str) -> float:
        """The heading a position setpoint without ``az`` keeps: the commanded, else current."""
        commanded = self._streamer.target
        if commanded is not None and commanded.type_mask == MASK_POSITION:
            return float(commanded.yaw)
        pose = self.inputs.pose.value
        if pose is None:
            raise NoData(f"{what}: az left out, and no attitude yet to keep the heading of")
        return float(telemetry.orientation_of(pose)[2])

    def _warn_if_grounded(self, what: str) -> None:
        """Say once per landing that setpoints do nothing to a disarmed drone on the ground."""
        state, extended = self.inputs.state.value, self.inputs.extended.value
        grounded = (
            state is not None
            and not state.armed
            and extended is not None
            and extended.landed_state == LANDED_STATE_ON_GROUND
        )
        if grounded and not self._warned_grounded:
            self._warned_grounded = True
            log.warning(
                "%s: drone %r is disarmed on the ground, so nothing moves until takeoff()",
                what,
                self.ns,
            )
        elif not grounded:
            self._warned_grounded = False

    def _command_setpoint(self, target: PositionTarget) -> None:
        if self._closed:
            raise NotConnected(f"DroneWrapper {self.ns!r} is closed")
        self._streamer.set(target)

    def stop_commanding(self) -> None:
        """Stop the setpoint stream. The bridge hovers after its ``setpoint_timeout``."""
        self._streamer.stop()

    @property
    def commanding(self) -> PositionTarget | None:
        """The setpoint being streamed, or None."""
        return self._streamer.target

    @property
    def setpoints_sent(self) -> int:
        """How many setpoint messages were published so far."""
        return self._streamer.published

    # ------------------------------------------------------------------ services

    def _ask(self, service: Service[Any, T], request: Any, timeout: float) -> T:
        """One request/reply; raises the runtime's ServiceError / ServiceUnavailable."""
        return self.node.call(
            service, request, ns=self.ns, timeout=timeout, attachment=self._attachment
        )

    def _call(self, service: Service[Any, T], request: Any, what: str, timeout: float | None) -> T:
        timeout = self.service_timeout if timeout is None else timeout
        try:
            return self._ask(service, request, timeout)
        except ServiceUnavailable:
            raise self._no_reply(what, service.key(self.ns), timeout) from None
        except ServiceError as exc:
            raise CommandRefused(what, exc.message) from None

    def _command(self, service: Service[Any, Any], request: Any, what: str, timeout=None) -> Any:
        reply = self._call(service, request, what, timeout)
        ok = reply.mode_sent if hasattr(reply, "mode_sent") else reply.success
        if not ok:
            raise CommandRefused(what, reply.message, getattr(reply, "result", None))
        return reply

    def take_command(self, *, take_over: bool = True, timeout: float | None = None) -> str:
        """Take this drone's command lease (another operator's too, when ``take_over``): the
        bridge then obeys only our setpoints and commands. Returns the previous holder.

        Raises:
            CommandRefused: ``take_over`` is False and someone else holds the lease.
        """
        action = "take_over" if take_over else "take"
        reply = self._call(registry.COMMAND_LEASE, LeaseRequest(action=action), action, timeout)
        if not reply.granted:
            raise CommandRefused(action, reply.message)
        return reply.previous

    def release_command(self, *, timeout: float | None = None) -> None:
        """Give the command lease back (any authorised operator may then take it)."""
        self._call(registry.COMMAND_LEASE, LeaseRequest(action="release"), "release", timeout)

    def arm(self, *, timeout: float | None = None) -> None:
        """Arm the motors. Raises CommandRefused with the autopilot's reason on refusal.

        PX4 refuses to arm in OFFBOARD without a setpoint stream and says only "Resolve system
        health failures first"; the error then names the real cause.
        """
        try:
            self._command(registry.ARMING, CommandBool(value=True), "arming", timeout)
        except CommandRefused as exc:
            state = self.inputs.state.value
            if state is not None and state.mode == "OFFBOARD" and self.commanding is None:
                raise CommandRefused(
                    "arming",
                    f"{exc.reason}; the autopilot is in OFFBOARD and no setpoint is being "
                    "streamed: PX4 arms in OFFBOARD only with a setpoint stream (use takeoff(), "
                    "or set_cmd_pos(...) before arm())",
                    exc.result,
                ) from None
            raise

    def disarm(self, *, timeout: float | None = None) -> None:
        """Disarm the motors (the autopilot refuses in flight). Raises CommandRefused."""
        self._command(registry.ARMING, CommandBool(value=False), "disarming", timeout)

    def set_mode(self, mode: str, *, timeout: float | None = None) -> None:
        """Ask for a flight mode by name (``OFFBOARD``, ``AUTO.LOITER``, ``GUIDED`` ...).

        Returns when the autopilot acknowledged it. Raises CommandRefused otherwise.
        """
        if not isinstance(mode, str) or not mode.strip():
            raise InvalidArgument(f"mode must be a mode name, got {mode!r}")
        self._command(registry.SET_MODE, SetMode(custom_mode=mode), f"set_mode {mode}", timeout)

    def param_get(self, param: str, *, timeout: float | None = None) -> int | float:
        """Read an autopilot parameter; an int or a float."""
        if not isinstance(param, str) or not param:
            raise InvalidArgument(f"param must be a parameter name, got {param!r}")
        reply = self._command(
            registry.PARAM_GET, ParamGet(param_id=param), f"param_get {param}", timeout
        )
        return reply.value.as_number()

    def param_set(
        self, param: str, value: int | float, *, timeout: float | None = None
    ) -> int | float:
        """Write an autopilot parameter (ints as integer, floats as real); returns the value
        the autopilot reports after the write."""
        if not isinstance(param, str) or not param:
            raise InvalidArgument(f"param must be a parameter name, got {param!r}")
        if isinstance(value, int | np.integer) and not isinstance(value, bool):
            wrapped = ParamValue(integer=int(value))
        else:
            wrapped = ParamValue(real=setpoints.finite(param, value))
        reply = self._command(
            registry.PARAM_SET,
            ParamSet(param_id=param, value=wrapped),
            f"param_set {param}",
            timeout,
        )
        return reply.value.as_number()

    # ------------------------------------------------------------------ take-off and landing

    def takeoff(
        self,
        h: float = 3.0,
        *,
        timeout: float = 30.0,
        tolerance: float = 0.1,
        cancel: threading.Event | None = None,
    ) -> None:
        """Take off to ``h`` metres above the take-off point and return there.

        Idempotent: returns at once when already flying. PX4: streams a hold setpoint, enters
        OFFBOARD, arms, then streams a position setpoint ``h`` m above the start point (which
        keeps being streamed after the return). ArduPilot: GUIDED, arm, TAKEOFF command.
        Tello: TAKEOFF command. The steps are the runtime's (:mod:`dronewrapper.flying`).

        Raises:
            CommandRefused: a step was refused (the autopilot's reason is in the message), or
                the autopilot disarmed or left the mode during the climb.
            Timeout: the altitude was not reached within ``timeout`` seconds.
            NotConnected: no bridge / autopilot.
            Cancelled: ``cancel`` was set (from another thread): no further step, and the
                setpoint stream stopped (the bridge holds position).
        """
        h = setpoints.finite("h", h)
        if h <= 0:
            raise InvalidArgument(f"h must be > 0 m, got {h}")
        now = self.clock.monotonic()
        connection.require_connected(self.inputs, self.connect, "takeoff")
        kwargs = {"tolerance": tolerance, "call_timeout": self.service_timeout}
        self._fly(Takeoff(self._aircraft, h, timeout, now, **kwargs), cancel)

    def land(self, *, timeout: float = 60.0, cancel: threading.Event | None = None) -> None:
        """Land where the drone is and return when it is on the ground and disarmed.

        Stops the setpoint stream, then calls the bridge's LAND service (no GPS needed).

        Raises:
            CommandRefused: the autopilot refused to land (its reason is in the message).
            Timeout: not on the ground and disarmed within ``timeout`` seconds.
            Cancelled: ``cancel`` was set (see :meth:`takeoff`).
        """
        now = self.clock.monotonic()
        connection.require_connected(self.inputs, self.connect, "land")
        self._fly(Landing(self._aircraft, timeout, now, call_timeout=self.service_timeout), cancel)

    def _fly(self, sequence: Takeoff | Landing, cancel: threading.Event | None) -> None:
        """Step ``sequence`` to its end, waiting on the node's clock (or until ``cancel``)."""
        clock, cancel = self.clock, cancel or threading.Event()
        try:
            flying.fly(
                sequence,
                clock=clock.monotonic,
                sleep=lambda seconds: clock.wait(cancel, seconds),
                no_reply=self._no_reply,
                cancelled=cancel.is_set,
            )
        except Cancelled:
            self.stop_commanding()
            raise
