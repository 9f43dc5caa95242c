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
clock. This module is the facade: construction, life cycle, connection, take-off and landing.
The rest of the API comes in parts, one module each: the getters (:mod:`dronewrapper.inputs`,
which read the newest message already received, no network round trip, and raise
:class:`~dronewrapper.errors.NoData` if none has arrived yet), the waits
(:mod:`dronewrapper.waits`), the setpoints (:mod:`dronewrapper.motion`) and the bridge's
services (:mod:`dronewrapper.commands`). Blocking calls take timeouts and raise
:class:`~dronewrapper.errors.Timeout`, :class:`~dronewrapper.errors.CommandRefused` (with the
autopilot's reason) or :class:`~dronewrapper.errors.NotConnected` (:mod:`dronewrapper.connection`
says why).
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

from dronewrapper import connection, diagnosis, flying, images, setpoints
from dronewrapper.commands import Commands
from dronewrapper.discovery import default_connect
from dronewrapper.errors import Cancelled, DroneError, InvalidArgument
from dronewrapper.inputs import Getters, Inputs
from dronewrapper.missions import MissionsMixin
from dronewrapper.motion import Motion
from dronewrapper.msgs import registry
from dronewrapper.msgs.flight import CancelRequest
from dronewrapper.msgs.mavros import (
    PositionTarget,
    State,
    StatusText,
)
from dronewrapper.msgs.refusal import Refusal
from dronewrapper.msgs.registry import Topic
from dronewrapper.refusals import RefusalInbox
from dronewrapper.runtime.caller import commander_attachment
from dronewrapper.runtime.contract import NodeApi
from dronewrapper.runtime.flight import FlightSequence, Landing, Takeoff
from dronewrapper.runtime.options import is_local_endpoint
from dronewrapper.script_log import show_progress
from dronewrapper.streamer import SetpointStreamer
from dronewrapper.waits import Waits

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


class DroneWrapper(Getters, Waits, Motion, Commands, MissionsMixin):
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
            With an identity the certificate's name is the commander, whatever this says
            (the router binds every command to it, see docs/security.md).
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
        show_progress()  # INFO lines on stderr for a script that configured no logging
        self.land_on_exit = land_on_exit
        self.service_timeout = service_timeout
        self._closed = False
        self._warned_grounded = False
        identity = self._identity = identity or os.environ.get("DRONEWRAPPER_IDENTITY", "")
        self.commander = commander or default_commander(identity)
        self._attachment = commander_attachment(self.commander)
        self._forbidden = (
            diagnosis.forbidden(identity, self.connect)
            if node is None
            else diagnosis.node_forbidden(node)
        )
        self.compressed_images = self._choose_compression(compressed_images, node, cameras)
        self._own_node = node is None
        if node is None:
            node = connection.open_node(
                self.ns, self.connect, timeout, mode=mode, identity=identity
            )
        self.node: NodeApi = node
        self.clock = node.clock
        bound = getattr(node, "bound_name", "")
        if bound and bound != self.commander:  # the router binds our commands to it
            log.warning("commander %r: the certificate's name %r commands", self.commander, bound)
        self.commander = bound or self.commander
        self._attachment = commander_attachment(self.commander)
        deadline = self.clock.monotonic() + timeout
        _open_wrappers.add(self)
        try:
            self.inputs = Inputs(
                node, self.ns, compressed_images=self.compressed_images, cameras=cameras
            )
            self._declare_mission_inputs()  # home, envelope, mission (missions.py)
            self._refusals = RefusalInbox(self.ns, self.commander, self.clock)
            self.inputs.subscribe(registry.REFUSAL, self._refusals.on_refusal)
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
                self.ns, state=self.inputs.state, stop=self.stop_commanding, ask=self._ask
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
    def refusals(self) -> list[Refusal]:
        """The bridge's last 20 refusals of our setpoints, newest last (``msgs.refusal``)."""
        return list(self._refusals.recent)

    def on_refusal(self, callback: Callable[[Refusal], None]) -> Callable[[], None]:
        """``callback(refusal)`` as each of ours arrives (a Zenoh thread); returns a stop."""
        return self._refusals.listen(callback)

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
        sent = self.clock.time()  # the send time: the bridges' late-setpoint rule
        self._setpoints.put(target, attachment=commander_attachment(self.commander, sent))

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
        for part in ("_beat", "_beat_publisher", "_streamer", "_matching", "inputs", "_setpoints"):
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
        state = connection.wait_for_connection(self.inputs, self.connect, self._identity, timeout)
        self._warn_of_envelope()  # held for set_cmd_*; warns if a commander's is in force
        return state

    def _require_connected(self, what: str) -> State:
        """The connected State, or NotConnected saying why ``what`` cannot be done."""
        return connection.require_connected(self.inputs, self.connect, self._identity, what)

    def _no_reply(self, what: str, key: str, timeout: float) -> DroneError:
        return connection.no_reply(self.inputs, self.connect, self._identity, what, key, timeout)

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

        One request to the bridge, which flies the take-off its aircraft's way (PX4: OFFBOARD
        on its own held setpoint, arm, climb; ArduPilot: GUIDED, arm, TAKEOFF; Tello: takeoff,
        then up to ``h``) and answers once there; the aircraft then holds there by itself
        until commanded. Idempotent: already flying, nothing is done (a warning says so).

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
        self._require_connected("takeoff")
        self._check_takeoff(h)  # above the envelope: refused, the limit named
        kwargs = {"tolerance": tolerance, "call_timeout": self.service_timeout}
        self._fly(Takeoff(self._aircraft, h, timeout, now, **kwargs), cancel)

    def land(self, *, timeout: float = 60.0, cancel: threading.Event | None = None) -> None:
        """Land where the drone is and return when it is on the ground and disarmed.

        Stops the setpoint stream, then one request to the bridge, which lands here (no GPS
        needed) and answers once on the ground and disarmed.

        Raises:
            CommandRefused: the autopilot refused to land (its reason is in the message).
            Timeout: not on the ground and disarmed within ``timeout`` seconds.
            Cancelled: ``cancel`` was set (see :meth:`takeoff`).
        """
        now = self.clock.monotonic()
        self._require_connected("land")
        self._fly(Landing(self._aircraft, timeout, now, call_timeout=self.service_timeout), cancel)

    def _fly(self, sequence: FlightSequence, cancel: threading.Event | None) -> None:
        """Step ``sequence`` to its end, waiting on the node's clock (or until ``cancel``)."""
        clock, cancel = self.clock, cancel or threading.Event()
        ended = threading.Event()
        watcher = threading.Thread(
            target=flying.cancel_on,
            args=(cancel, ended, self._ask_cancel),
            name="dronewrapper-cancel",
            daemon=True,
        )
        watcher.start()
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
        finally:
            ended.set()
            watcher.join(timeout=self.service_timeout + 1.0)

    def _ask_cancel(self) -> None:
        """Ask the bridge to end its running take-off, landing, go-to or return (it holds where
        it is)."""
        self._ask(registry.FLIGHT_CANCEL, CancelRequest(reason="the caller cancelled"), 2.0)
