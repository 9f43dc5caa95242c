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

Getters read the newest message already received (no network round trip) and raise
:class:`~dronewrapper.errors.NoData` if none has arrived yet. Blocking calls take timeouts and
raise :class:`~dronewrapper.errors.Timeout`, :class:`~dronewrapper.errors.CommandRefused` (with the
autopilot's reason) or :class:`~dronewrapper.errors.NotConnected`.

Size: over 400 lines on purpose: this is the paper's API, one class a user reads top to bottom
(getters, setpoints, commands, parameters); its plumbing lives in ``telemetry``, ``setpoints``,
``streamer`` and the runtime.
"""

from __future__ import annotations

import atexit
import collections
import contextlib
import getpass
import logging
import os
import socket
import time
import weakref
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any, TypeVar

import numpy as np
import zenoh

from dronewrapper import flying, images, setpoints, telemetry
from dronewrapper.diagnosis import identity_facts, no_reply, seconds
from dronewrapper.discovery import (
    alive_services,
    connection_problem,
    default_connect,
    open_client,
)
from dronewrapper.errors import (
    CommandRefused,
    DroneError,
    InvalidArgument,
    NoData,
    NotConnected,
    Timeout,
)
from dronewrapper.health import stale_after
from dronewrapper.missions import MissionsMixin
from dronewrapper.msgs import codec, registry
from dronewrapper.msgs.lease import LeaseRequest
from dronewrapper.msgs.mavros import (
    LANDED_STATE_IN_AIR,
    LANDED_STATE_ON_GROUND,
    LANDED_STATE_TAKEOFF,
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
from dronewrapper.runtime.commander import STATE_FRESH_S
from dronewrapper.runtime.delivery import SampleErrors, decoding
from dronewrapper.runtime.errors import ServiceError, ServiceUnavailable
from dronewrapper.runtime.flight import Landing, Takeoff
from dronewrapper.runtime.latest import Latest
from dronewrapper.runtime.node import call_service, encoding_for
from dronewrapper.runtime.options import is_local_endpoint
from dronewrapper.runtime.qos import qos_for
from dronewrapper.script_log import show_progress
from dronewrapper.streamer import SetpointStreamer

T = TypeVar("T")

log = logging.getLogger("dronewrapper")

CAMERAS = {"frontal": "cam_frontal", "ventral": "cam_ventral"}
"""Camera short names accepted by the image methods, and their key names."""

TELEMETRY_READ_BY_GETTERS = (
    ("extended state", "_extended"),
    ("local position", "_pose"),
    ("body velocity", "_velocity_body"),
    ("local velocity", "_velocity_local"),
    ("battery state", "_battery"),
)
"""The streams every bridge publishes and the getters read: the constructor and
:meth:`DroneWrapper.wait_for_connection` wait for each of them (global position needs a GPS and
images a camera, so those are waited for by their own ``wait_for_*`` calls)."""


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


def _camera_key_name(camera: str) -> str:
    if camera in CAMERAS:
        return CAMERAS[camera]
    if camera in CAMERAS.values():
        return camera
    raise InvalidArgument(f"unknown camera {camera!r}: use 'frontal' or 'ventral'")


class DroneWrapper(MissionsMixin):
    """One drone, reached through a Zenoh router. Several objects fly several drones.

    Args:
        name: the vehicle namespace (``drone``, ``drone1`` ...); default env
            ``DRONEWRAPPER_NAMESPACE`` or ``drone``.
        connect: the router endpoint, e.g. ``tcp/192.168.1.10:7447`` from a laptop; default env
            ``DRONEWRAPPER_CONNECT`` or ``tcp/127.0.0.1:7447``.
        timeout: seconds to reach the router and find a bridge whose autopilot is connected.
        mode: Zenoh session mode (``client``: everything through the router; ``peer``).
        session: an open ``zenoh.Session`` to reuse (a service embedding the SDK); it is not
            closed by :meth:`close`. ``connect`` and ``mode`` are then ignored.
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
        node: a runtime ``Node``, or a ``FakeNode`` on the fake bus (tests), to talk through
            instead of a session; it is not closed by :meth:`close`. ``connect``, ``mode`` and
            ``session`` are then ignored.
        clock, sleep: the monotonic clock (s) of the getters' ages and of the deadlines of
            takeoff(), land() and the polling waits (wait_for, wait_for_altitude ...), and
            how those calls wait: injected time in tests (the connection and image waits
            block on arrivals, in real time).

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
        session: zenoh.Session | None = None,
        cameras: Sequence[str] | None = None,
        compressed_images: bool | None = None,
        land_on_exit: bool = False,
        setpoint_rate_hz: float = 30.0,
        command_timeout: float | None = None,
        service_timeout: float = 10.0,
        wait: bool = True,
        identity: str | None = None,
        commander: str | None = None,
        node: Any = None,
        clock: Callable[[], float] = time.monotonic,
        sleep: Callable[[float], Any] = time.sleep,
    ) -> None:
        self.ns = name or os.environ.get("DRONEWRAPPER_NAMESPACE") or registry.DEFAULT_NAMESPACE
        self.connect = connect or default_connect()
        show_progress()  # INFO lines on stderr for a script that configured no logging
        if compressed_images is None:
            remote = session is None and node is None and not is_local_endpoint(self.connect)
            compressed_images = remote and images.has_jpeg_decoder()
            if remote and not compressed_images:
                log.warning(
                    "the router %s is on another machine but OpenCV is missing, so camera "
                    "frames come raw (~220 Mbit/s each): pip install 'dronewrapper[images]'",
                    self.connect,
                )
        elif compressed_images and cameras != ():
            images.jpeg_decoder()  # fail now, not at the first frame, if OpenCV is missing
        registry.STATE.key(self.ns)  # validates the namespace (one key chunk)
        self.land_on_exit = land_on_exit
        self.compressed_images = compressed_images
        self.service_timeout = service_timeout
        self.sample_errors = SampleErrors(log) if node is None else node.sample_errors
        self.decode_errors: collections.Counter[str] = self.sample_errors.decode
        self._closed = False
        self._warned_grounded = False
        self._stale_after: dict[str, float] = {}
        self._stale_warned: set[str] = set()
        self._subscribers: list[Any] = []
        self._node = node
        self._clock, self._sleep = clock, sleep
        self._own_session = session is None and node is None
        deadline = time.monotonic() + timeout
        identity = self._identity = identity or os.environ.get("DRONEWRAPPER_IDENTITY", "")
        self.commander = commander or default_commander(identity)
        self._attachment = commander_attachment(self.commander)
        if node is not None:
            session = node.session
        elif session is None:
            session = open_client(self.connect, timeout, mode=mode, identity=identity)
        self.session: zenoh.Session = session
        _open_wrappers.add(self)
        try:
            self._declare_inputs(cameras)
            self._declare_setpoints()
            self._aircraft = flying.WrapperAircraft(
                self.ns,
                state=self._state,
                extended=self._extended,
                pose=self._pose,
                status_texts=self.status_texts,
                set_target=self._command_setpoint,
                stop=self.stop_commanding,
                ask=self._ask,
                wall=time.time,
            )
            self._streamer = SetpointStreamer(
                self._publish_setpoint,
                rate_hz=setpoint_rate_hz,
                idle_timeout=command_timeout,
                name=f"{self.ns}-setpoints",
            )
            self._bridge_matched = False
            if node is not None:
                self._matching = self._setpoints.on_matching(self._on_setpoint_matching)
            else:  # a direct callback: no thread to block interpreter exit (see _subscribe)
                self._matching = self._setpoints.declare_matching_listener(
                    zenoh.handlers.Callback(
                        lambda status: self._on_setpoint_matching(status.matching), indirect=False
                    )
                )
            if wait:
                self.wait_for_connection(max(0.0, deadline - time.monotonic()))
        except BaseException:
            self.close()
            raise

    # ------------------------------------------------------------------ plumbing

    def _declare_inputs(self, cameras: Sequence[str]) -> None:
        self._state: Latest[State] = self._latest(registry.STATE)
        self._extended = self._latest(registry.EXTENDED_STATE)
        self._pose = self._latest(registry.LOCAL_POSE)
        self._velocity_body = self._latest(registry.VELOCITY_BODY)
        self._velocity_local = self._latest(registry.VELOCITY_LOCAL)
        self._global = self._latest(registry.GLOBAL_POSITION)
        self._battery = self._latest(registry.BATTERY)
        self._declare_mission_inputs()  # home, envelope, mission (missions.py)
        self.status_texts: collections.deque[StatusText] = collections.deque(maxlen=20)
        """The autopilot's last 20 text messages (newest last)."""
        self._subscribe(registry.STATUSTEXT, self.status_texts.append)
        self._images: dict[str, Latest[Any]] = {}
        self._decoded: dict[str, tuple[Any, np.ndarray]] = {}
        self._lazy_cameras = cameras is None
        self._images_declared = False
        for camera in cameras or ():
            self._camera_holder(camera)
        self._images_declared = True

    def _declare_setpoints(self) -> None:
        if self._node is not None:  # a typed publisher (the runtime's)
            key = registry.SETPOINT_RAW_LOCAL.key(self.ns)
            self._setpoints = self._node.publisher(registry.SETPOINT_RAW_LOCAL, key=key)
        else:
            self._setpoints = self.session.declare_publisher(
                registry.SETPOINT_RAW_LOCAL.key(self.ns),
                encoding=encoding_for(PositionTarget),
                **qos_for(registry.SETPOINT_RAW_LOCAL),
            )

    def _camera_holder(self, camera: str) -> Latest[Any] | None:
        """The newest-frame holder of ``camera``, subscribing now if cameras are lazy; None if
        the camera was not requested."""
        key_name = _camera_key_name(camera)
        holder = self._images.get(key_name)
        if holder is None and (self._lazy_cameras or not self._images_declared):
            topic = registry.IMAGE_COMPRESSED if self.compressed_images else registry.IMAGE_RAW
            holder = self._images[key_name] = self._latest(topic, camera=key_name)
        return holder

    def subscribe(
        self, topic: Topic[T], callback: Callable[[T], None], **parts: str
    ) -> zenoh.Subscriber:
        """Call ``callback(msg)`` for every decodable message on ``topic`` in this drone's
        namespace (``parts`` fill the other key fields, e.g. ``camera="cam_frontal"``).

        The callback runs on a Zenoh thread: keep it short. Undecodable samples are counted in
        ``decode_errors``; an exception in the callback is logged and never ends the
        subscription. ``undeclare()`` the returned subscriber to stop; :meth:`close` does too.
        """
        return self._subscribe(topic, callback, **parts)

    def _subscribe(
        self, topic: Topic[T], callback: Callable[[T], None], **parts: str
    ) -> zenoh.Subscriber:
        if self._node is not None:
            subscriber = self._node.subscribe(topic, callback, key=topic.key(self.ns, **parts))
            self._subscribers.append(subscriber)
            return subscriber
        key = topic.key(self.ns, **parts)
        deliver = decoding(topic.type, callback, self.sample_errors)

        def on_sample(sample: zenoh.Sample) -> None:
            deliver(key, sample.payload.to_bytes(), sample.attachment)

        # Direct callbacks (no Python thread per subscriber): the handler is tiny (decode and
        # store), and no non-daemon thread is left to block interpreter exit before our atexit
        # hook closes the session (the paper's listing never calls close()).
        handler = zenoh.handlers.Callback(on_sample, indirect=False)
        subscriber = self.session.declare_subscriber(key, handler)
        self._subscribers.append(subscriber)
        return subscriber

    def _latest(self, topic: Topic[T], **parts: str) -> Latest[T]:
        holder: Latest[T] = Latest(name=topic.key(self.ns, **parts), clock=self._clock)
        self._subscribe(topic, holder.update, **parts)
        self._stale_after[holder.name] = stale_after(topic.rate_hz)
        return holder

    def _on_setpoint_matching(self, matching: bool) -> None:
        """The bridge's setpoint subscriber became (un)reachable: a link gap (router restart,
        lost Wi-Fi) withholds setpoints, and a command that went stale meanwhile is not resent
        (see SetpointStreamer). "Unreachable" counts only after it was reachable once."""
        if self._closed:
            return
        if matching:
            self._bridge_matched = True
            self._streamer.link_up()
        elif self._bridge_matched:
            self._streamer.link_down()

    def _publish_setpoint(self, target: PositionTarget) -> None:
        message = target if self._node is not None else codec.encode(target)
        self._setpoints.put(message, attachment=self._attachment)

    def _need(self, latest: Latest[T], what: str) -> T:
        value = latest.value
        if value is None:
            raise NoData(
                f"no {what} received yet on {latest.name}: is the bridge running and publishing? "
                "(wait_for_connection() waits for it)"
            )
        age, limit = latest.age(), self._stale_after.get(latest.name, float("inf"))
        if age > limit and latest.name not in self._stale_warned:
            self._stale_warned.add(latest.name)
            log.warning(
                "%s is %.1f s old (stale after %.1f s for its rate): the link or the bridge is "
                "slow; check with `dronewrapper doctor`",
                latest.name,
                age,
                limit,
            )
        elif age <= limit:
            self._stale_warned.discard(latest.name)
        return value

    def age(self, what: str) -> float:
        """Seconds since the newest value of a getter's stream arrived (inf before the first).

        ``what`` names a getter without ``get_``: ``position``, ``orientation``, ``velocity``,
        ``velocity_local``, ``yaw_rate``, ``landed_state``, ``battery``, ``global_position``,
        ``state``, ``frontal_image``, ``ventral_image``.
        """
        holders = {
            "position": self._pose,
            "orientation": self._pose,
            "velocity": self._velocity_body,
            "yaw_rate": self._velocity_body,
            "velocity_local": self._velocity_local,
            "landed_state": self._extended,
            "battery": self._battery,
            "global_position": self._global,
            "state": self._state,
        }
        if what in ("frontal_image", "ventral_image"):
            holder = self._camera_holder(what.removesuffix("_image"))
            return holder.age() if holder is not None else float("inf")
        if what not in holders:
            raise InvalidArgument(f"age of {what!r}: use one of {', '.join(sorted(holders))}")
        return holders[what].age()

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
        """Stop commanding, drop the subscriptions and close the session if it is ours.

        Idempotent; also done at interpreter exit. Does not land: the bridge hovers, then lands
        after its ``commander_lost_timeout``.
        """
        if self._closed:
            return
        self._closed = True
        _open_wrappers.discard(self)
        streamer = getattr(self, "_streamer", None)
        if streamer is not None:
            streamer.close()
        matching = getattr(self, "_matching", None)
        if matching is not None:
            with contextlib.suppress(Exception):
                matching.undeclare()
        try:
            if self._own_session:
                time.sleep(0.05)  # let the last messages leave before the session closes
                self.session.close()
            else:
                for entity in [*self._subscribers, getattr(self, "_setpoints", None)]:
                    if entity is not None:
                        with contextlib.suppress(Exception):  # one the caller undeclared
                            entity.undeclare()
        except Exception as exc:  # a session already closed by its owner
            log.debug("close: %s", exc)

    def __repr__(self) -> str:
        state = self._state.value
        link = "closed" if self._closed else ("connected" if self.is_connected() else "waiting")
        mode = f" mode={state.mode} armed={state.armed}" if state else ""
        return f"DroneWrapper(name={self.ns!r}, connect={self.connect!r}, {link}{mode})"

    # ------------------------------------------------------------------ connection

    def is_connected(self) -> bool:
        """True if a fresh State (< 3 s old) says the bridge's autopilot is connected."""
        state = self._state.fresh(STATE_FRESH_S)
        return bool(state is not None and state.connected)

    def wait_for_connection(self, timeout: float = 10.0) -> State:
        """Block until the bridge reports its autopilot connected and every telemetry stream the
        getters read (landed state, position, velocities, battery) has arrived; returns the State.

        Raises:
            NotConnected: no bridge, a bridge without an autopilot, or a stream still missing
                after ``timeout`` s (the message names the missing keys).
        """
        deadline = time.monotonic() + timeout
        seen = -1
        while True:
            state = self._state.fresh(STATE_FRESH_S)
            if state is not None and state.connected:
                break
            remaining = deadline - time.monotonic()
            if remaining <= 0:
                raise NotConnected(self._diagnose(timeout))
            seen = self._state.count
            with contextlib.suppress(TimeoutError):
                self._state.wait(min(remaining, 0.5), newer_than=seen)
        for _, attribute in TELEMETRY_READ_BY_GETTERS:
            holder: Latest[Any] = getattr(self, attribute)
            with contextlib.suppress(TimeoutError):
                holder.wait(max(0.0, deadline - time.monotonic()))
        missing = [
            f"{what} ({getattr(self, attribute).name})"
            for what, attribute in TELEMETRY_READ_BY_GETTERS
            if getattr(self, attribute).value is None
        ]
        if missing:
            raise NotConnected(
                f"the bridge of drone {self.ns!r} is connected but after {seconds(timeout)} s "
                f"nothing arrived on: {', '.join(missing)}; is the link too slow, or the bridge "
                "old?"
            )
        log.info("connected to drone %r via %s", self.ns, self.connect)
        return state

    def _diagnose(self, timeout: float) -> str:
        if self._node is not None and self._node.session is None:  # the fake bus: in process
            linked = True
        else:
            info = self.session.info
            linked = bool(list(info.routers_zid()) or list(info.peers_zid()))
        keys: set[str] = set()
        if linked:
            with contextlib.suppress(Exception):
                keys = self._alive_services("*")
        state = self._state.value
        return connection_problem(
            self.ns,
            self.connect,
            linked=linked,
            alive_keys=keys,
            state_connected=None if state is None else state.connected,
            state_age=self._state.age(),
            fresh_s=STATE_FRESH_S,
            waited=timeout,
            **identity_facts(self._identity, self.connect),
        )

    def _require_connected(self, what: str) -> State:
        state = self._state.fresh(STATE_FRESH_S)
        if state is None or not state.connected:
            raise NotConnected(f"{what}: {self._diagnose(0.0)}")
        return state

    # ------------------------------------------------------------------ getters (no I/O)

    def get_state(self) -> State:
        """The newest autopilot State (connected, armed, mode, autopilot, failsafe ...)."""
        return self._need(self._state, "state")

    def get_position(self) -> np.ndarray:
        """``np.array([x, y, z])``: position in local ENU metres (origin: the take-off point)."""
        return telemetry.position_of(self._need(self._pose, "local position"))

    def get_velocity(self) -> np.ndarray:
        """``np.array([vx, vy, vz])``: velocity in body FLU m/s (forward, left, up)."""
        return telemetry.linear_of(self._need(self._velocity_body, "body velocity"))

    def get_velocity_local(self) -> np.ndarray:
        """``np.array([vx, vy, vz])``: velocity in local ENU m/s (east, north, up)."""
        return telemetry.linear_of(self._need(self._velocity_local, "local velocity"))

    def get_yaw_rate(self) -> float:
        """Yaw rate in rad/s, counter-clockwise positive."""
        return telemetry.yaw_rate_of(self._need(self._velocity_body, "body velocity"))

    def get_orientation(self) -> np.ndarray:
        """``np.array([roll, pitch, yaw])`` in radians, ENU (yaw 0 = east, CCW positive)."""
        return telemetry.orientation_of(self._need(self._pose, "local position"))

    def get_roll(self) -> float:
        """Roll angle in radians."""
        return float(self.get_orientation()[0])

    def get_pitch(self) -> float:
        """Pitch angle in radians."""
        return float(self.get_orientation()[1])

    def get_yaw(self) -> float:
        """Yaw angle in radians, ENU: 0 facing east, counter-clockwise positive."""
        return float(self.get_orientation()[2])

    def get_landed_state(self) -> int:
        """MAVROS landed state: 0 undefined, 1 on ground, 2 in air, 3 taking off, 4 landing."""
        return int(self._need(self._extended, "extended state").landed_state)

    def get_battery(self) -> float:
        """Battery charge as a fraction 0..1 (NaN if the aircraft does not report it)."""
        return float(self._need(self._battery, "battery state").percentage)

    def get_global_position(self) -> np.ndarray:
        """``np.array([latitude, longitude, altitude])``: degrees, degrees, metres AMSL.

        Raises NoData when the aircraft has no GPS (nothing published).
        """
        return telemetry.global_of(self._need(self._global, "global position (GPS)"))

    def is_flying(self) -> bool:
        """True if the landed state is in the air or taking off."""
        extended = self._extended.value
        return extended is not None and extended.landed_state in (
            LANDED_STATE_IN_AIR,
            LANDED_STATE_TAKEOFF,
        )

    def get_image(self, camera: str = "frontal", *, with_stamp: bool = False) -> Any:
        """The newest frame of ``camera`` as a BGR ``uint8`` array (height, width, 3).

        Args:
            camera: ``frontal`` or ``ventral``.
            with_stamp: return ``(image, stamp)``, the stamp being the capture time in seconds
                since the Unix epoch (for latency measurements).

        Raises:
            NoData: no frame received yet (no camera running, or the camera was not
                requested in ``cameras=``).
        """
        key_name = _camera_key_name(camera)
        holder = self._camera_holder(camera)
        if holder is None:
            raise NoData(
                f"camera {camera!r} was not requested: DroneWrapper(cameras=[..., {camera!r}])"
            )
        msg = holder.value
        if msg is None:
            raise NoData(
                f"no image received yet on {holder.name}: is a camera running? "
                "(wait_for_image() waits for the first frame)"
            )
        cached = self._decoded.get(key_name)
        if cached is None or cached[0] is not msg:
            self._decoded[key_name] = cached = (msg, self.decode_image(msg))
        image = cached[1].copy()
        return (image, float(msg.header.stamp)) if with_stamp else image

    def decode_image(self, msg: Any) -> np.ndarray:
        """A camera message (raw or JPEG, as this object receives them) as a BGR array."""
        if self.compressed_images:
            return images.compressed_to_bgr(msg)
        return images.image_to_bgr(msg)

    def get_frontal_image(self) -> np.ndarray:
        """The newest frontal camera frame, BGR ``uint8`` (height, width, 3)."""
        return self.get_image("frontal")

    def get_ventral_image(self) -> np.ndarray:
        """The newest ventral (downward) camera frame, BGR ``uint8`` (height, width, 3)."""
        return self.get_image("ventral")

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
        deadline = self._clock() + timeout
        while True:
            try:
                value = predicate()
            except NoData:
                value = None
            if _satisfied(value):
                return value
            if self._clock() >= deadline:
                raise Timeout(f"timed out after {timeout:g} s waiting for {what}")
            self._sleep(interval)

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
        holder = self._camera_holder(camera)
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
        pose = self._pose.value
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
        stamp = setpoints.check_stamp(stamp, time.time())
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
        stamp = setpoints.check_stamp(stamp, time.time())
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
        stamp = setpoints.check_stamp(stamp, time.time())
        z = self._kept_altitude("set_cmd_mix") if z is None else z
        target = setpoints.mixed_target(vx, vy, z, az, stamp=stamp)
        self._warn_if_grounded("set_cmd_mix")
        self._command_setpoint(target)

    def _kept_altitude(self, what: str) -> float:
        """The altitude a setpoint without ``z`` keeps: the commanded one, else the current."""
        commanded = self._streamer.target
        if commanded is not None and commanded.type_mask in (MASK_POSITION, MASK_MIXED):
            return float(commanded.position.z)
        pose = self._pose.value
        if pose is None:
            raise NoData(f"{what}: z left out, and no position yet to keep the altitude of")
        return float(pose.pose.position.z)

    def _kept_yaw(self, what: str) -> float:
        """The heading a position setpoint without ``az`` keeps: the commanded, else current."""
        commanded = self._streamer.target
        if commanded is not None and commanded.type_mask == MASK_POSITION:
            return float(commanded.yaw)
        pose = self._pose.value
        if pose is None:
            raise NoData(f"{what}: az left out, and no attitude yet to keep the heading of")
        return float(telemetry.orientation_of(pose)[2])

    def _warn_if_grounded(self, what: str) -> None:
        """Say once per landing that setpoints do nothing to a disarmed drone on the ground."""
        state, extended = self._state.value, self._extended.value
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
        if self._node is not None:
            return self._node.call(
                service, request, ns=self.ns, timeout=timeout, attachment=self._attachment
            )
        return call_service(
            self.session, service, request, ns=self.ns, timeout=timeout, attachment=self._attachment
        )

    def _call(self, service: Service[Any, T], request: Any, what: str, timeout: float | None) -> T:
        timeout = self.service_timeout if timeout is None else timeout
        try:
            return self._ask(service, request, timeout)
        except ServiceUnavailable:
            raise self._no_reply(what, service.key(self.ns), timeout) from None
        except ServiceError as exc:
            raise CommandRefused(what, exc.message) from None

    def _no_reply(self, what: str, key: str, timeout: float) -> DroneError:
        """A call nobody answered, diagnosed (:func:`dronewrapper.diagnosis.no_reply`)."""
        try:
            names = self._alive_services(self.ns)
        except Exception:
            names = set()
        ask = {"ns": self.ns, "connect": self.connect, "alive_names": names}
        ask["sees_telemetry"] = self._state.value is not None
        return no_reply(what, key, timeout, **ask, **identity_facts(self._identity, self.connect))

    def _alive_services(self, ns: str) -> set[str]:
        """The liveliness keys present in ``ns`` ("*": all), through the node when given."""
        if self._node is not None:
            return self._node.alive_services(ns, timeout=1.0)
        return alive_services(self.session, ns, timeout=1.0)

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
            state = self._state.value
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

    def takeoff(self, h: float = 3.0, *, timeout: float = 30.0, tolerance: float = 0.1) -> None:
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
        """
        h = setpoints.finite("h", h)
        if h <= 0:
            raise InvalidArgument(f"h must be > 0 m, got {h}")
        now = self._clock()
        self._require_connected("takeoff")
        self._check_takeoff(h)  # above the envelope: refused, the limit named
        kwargs = {"tolerance": tolerance, "call_timeout": self.service_timeout}
        self._fly(Takeoff(self._aircraft, h, timeout, now, **kwargs))

    def land(self, *, timeout: float = 60.0) -> None:
        """Land where the drone is and return when it is on the ground and disarmed.

        Stops the setpoint stream, then calls the bridge's LAND service (no GPS needed).

        Raises:
            CommandRefused: the autopilot refused to land (its reason is in the message).
            Timeout: not on the ground and disarmed within ``timeout`` seconds.
        """
        now = self._clock()
        self._require_connected("land")
        self._fly(Landing(self._aircraft, timeout, now, call_timeout=self.service_timeout))

    def _fly(self, sequence: Takeoff | Landing) -> None:
        flying.fly(sequence, clock=self._clock, sleep=self._sleep, no_reply=self._no_reply)
