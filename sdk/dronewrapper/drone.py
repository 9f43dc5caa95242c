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

A DroneWrapper is the blocking face of one :class:`~dronewrapper.client.DroneClient` (its input
holders, its "connected" rule, its setpoint stream on its own thread, its calls, its refusals),
standing on a node (the node contract, :mod:`dronewrapper.runtime.contract`): the one it is
given, or its own (:func:`dronewrapper.connection.open_node`). Its time is the node's clock.
This module is the facade: construction, life cycle and connection; every other verb is the
same method of a part it owns, one module each, each given what it uses: the getters
(:mod:`dronewrapper.getters`, which read the newest message already received, no network round
trip, and raise :class:`~dronewrapper.errors.NoData` if none has arrived yet), the waits
(:mod:`dronewrapper.waits`), the setpoints (:mod:`dronewrapper.motion`), the bridge's services
(:mod:`dronewrapper.commands`), the envelope (:mod:`dronewrapper.envelope_guard`), the long
actions (:mod:`dronewrapper.flights`: take-off, landing, go-to, return, mission steps) and the
missions (:mod:`dronewrapper.missions`). Blocking calls take timeouts and raise
:class:`~dronewrapper.errors.Timeout`, :class:`~dronewrapper.errors.CommandRefused` (with the
autopilot's reason) or :class:`~dronewrapper.errors.NotConnected` (:mod:`dronewrapper.connection`
says why).
"""

from __future__ import annotations

import atexit
import collections
import logging
import os
import weakref
from collections.abc import Callable, Sequence
from typing import Any, TypeVar

from dronewrapper import connection, diagnosis, images
from dronewrapper.client import DroneClient
from dronewrapper.client.drone_client import CLIENT_PORTS, default_commander
from dronewrapper.client.inputs import chosen_streams
from dronewrapper.commands import Commands
from dronewrapper.discovery import default_connect
from dronewrapper.envelope_guard import EnvelopeGuard
from dronewrapper.errors import DroneError
from dronewrapper.flights import Flights
from dronewrapper.forward import forward
from dronewrapper.getters import Getters
from dronewrapper.missions import Missions
from dronewrapper.motion import Motion
from dronewrapper.msgs import registry
from dronewrapper.msgs.mavros import PositionTarget, State, StatusText
from dronewrapper.msgs.refusal import Refusal
from dronewrapper.msgs.registry import Topic
from dronewrapper.runtime.contract import NodeApi
from dronewrapper.runtime.options import is_local_endpoint
from dronewrapper.runtime.ports import Ports
from dronewrapper.script_log import show_progress
from dronewrapper.waits import Waits

__all__ = ["DroneWrapper", "default_commander"]

T = TypeVar("T")

log = logging.getLogger("dronewrapper")

_open_wrappers: weakref.WeakSet[DroneWrapper] = weakref.WeakSet()


@atexit.register
def _close_all() -> None:
    """Close every wrapper still open at interpreter exit (an open Zenoh session can hang it)."""
    for wrapper in list(_open_wrappers):
        wrapper.close()


WRAPPER_PORTS = CLIENT_PORTS | Ports(
    "sdk",
    publishes=(registry.COMMANDER_BEAT,),  # flights.py: the beat of an unattended flight
    subscribes=(t for t in registry.TOPICS.values() if "bridge" in t.publishers),
    calls=(s for s in registry.SERVICES.values() if s.server == "bridge"),
)
"""What a :class:`DroneWrapper` may do on its node (a bridge's topics and services, the
setpoints and the commander's beat): the part of a service's ``PORTS`` it brings
(:mod:`dronewrapper.runtime.ports`)."""


class DroneWrapper:
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
        streams: the telemetry streams received from the start (``inputs.STREAMS`` names);
            None (default): all. ``state``, ``extended`` and ``pose`` always (the flights read
            them); another is subscribed on its first read, whose getter raises NoData until
            its first sample: a fleet reading only poses and states pays for those alone.
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
        streams: Sequence[str] | None = None,
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
        wanted_streams = chosen_streams(streams)  # InvalidArgument before any network
        self.connect = connect or default_connect()
        show_progress()  # INFO lines on stderr for a script that configured no logging
        self.land_on_exit = land_on_exit
        self.service_timeout = service_timeout
        self._closed = False
        identity = self._identity = identity or os.environ.get("DRONEWRAPPER_IDENTITY", "")
        commander = commander or default_commander(identity)
        forbidden = (
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
        if bound and bound != commander:  # the router binds our commands to it
            log.warning("commander %r: the certificate's name %r commands", commander, bound)
        self.commander = bound or commander
        deadline = self.clock.monotonic() + timeout
        _open_wrappers.add(self)
        try:
            self.client = DroneClient(
                node,
                name=self.commander,
                ns=self.ns,
                rate_hz=setpoint_rate_hz,
                idle_timeout=command_timeout,
                threaded_stream=True,
                inline_calls=True,  # a blocking call waits on this thread anyway
                forbidden=forbidden,
                streams=wanted_streams,
                cameras=cameras,
                compressed_images=self.compressed_images,
            )
            self.inputs = self.client.inputs
            self.getters = Getters(self.inputs)
            self.waits = Waits(self.clock, self.getters)
            self.commands = Commands(self.client, self._no_reply, service_timeout)
            self.guard = EnvelopeGuard(self.client, self.commands)
            self._home = self.guard.home_holder  # read by the firmware tier's tests
            self.motion = Motion(self.client, self.guard.check_setpoint)
            self.missions = Missions(self.client, self.commands, self.guard)
            self.flights = Flights(
                self.client,
                self.guard,
                require_connected=self._require_connected,
                no_reply=self._no_reply,
                service_timeout=service_timeout,
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
        return list(self.client.refusals.recent)

    def on_refusal(self, callback: Callable[[Refusal], None]) -> Callable[[], None]:
        """``callback(refusal)`` as each of ours arrives (a Zenoh thread); returns a stop."""
        return self.client.refusals.listen(callback)

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

    @property
    def commanding(self) -> PositionTarget | None:
        """The setpoint being streamed, or None."""
        return self.client.target

    @property
    def setpoints_sent(self) -> int:
        """How many setpoint messages were published so far."""
        return self.client.published

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
        for part in ("flights", "client"):
            owned = getattr(self, part, None)
            if owned is not None:
                try:
                    owned.close()
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
        return self.client.is_connected()

    def wait_for_connection(self, timeout: float = 10.0) -> State:
        """Block until the bridge reports its autopilot connected and every telemetry stream the
        getters read (landed state, position, velocities, battery) has arrived; returns the State.

        Raises:
            NotConnected: no bridge, a bridge without an autopilot, or a stream still missing
                after ``timeout`` s (the message names the missing keys).
        """
        state = connection.wait_for_connection(self.client, self.connect, self._identity, timeout)
        # held for set_cmd_*; warns if a commander's is in force
        self.guard.warn_if_commanded(min(2.0, self.service_timeout))
        return state

    def _require_connected(self, what: str) -> State:
        """The connected State, or NotConnected saying why ``what`` cannot be done."""
        return connection.require_connected(self.client, self.connect, self._identity, what)

    def _no_reply(self, what: str, key: str, timeout: float) -> DroneError:
        return connection.no_reply(self.client, self.connect, self._identity, what, key, timeout)

    # ------------------------------------------------------------------ the parts' verbs

    get_state = forward("getters", Getters.get_state)
    get_position = forward("getters", Getters.get_position)
    get_velocity = forward("getters", Getters.get_velocity)
    get_velocity_local = forward("getters", Getters.get_velocity_local)
    get_yaw_rate = forward("getters", Getters.get_yaw_rate)
    get_orientation = forward("getters", Getters.get_orientation)
    get_roll = forward("getters", Getters.get_roll)
    get_pitch = forward("getters", Getters.get_pitch)
    get_yaw = forward("getters", Getters.get_yaw)
    get_landed_state = forward("getters", Getters.get_landed_state)
    get_battery = forward("getters", Getters.get_battery)
    get_link = forward("getters", Getters.get_link)
    get_global_position = forward("getters", Getters.get_global_position)
    is_flying = forward("getters", Getters.is_flying)
    age = forward("getters", Getters.age)
    get_image = forward("getters", Getters.get_image)
    decode_image = forward("getters", Getters.decode_image)
    get_frontal_image = forward("getters", Getters.get_frontal_image)
    get_ventral_image = forward("getters", Getters.get_ventral_image)

    wait_for = forward("waits", Waits.wait_for)
    wait_for_altitude = forward("waits", Waits.wait_for_altitude)
    wait_for_landed_state = forward("waits", Waits.wait_for_landed_state)
    wait_for_image = forward("waits", Waits.wait_for_image)

    set_cmd_pos = forward("motion", Motion.set_cmd_pos)
    set_cmd_vel = forward("motion", Motion.set_cmd_vel)
    set_cmd_mix = forward("motion", Motion.set_cmd_mix)
    stop_commanding = forward("motion", Motion.stop_commanding)

    take_command = forward("commands", Commands.take_command)
    release_command = forward("commands", Commands.release_command)
    arm = forward("commands", Commands.arm)
    disarm = forward("commands", Commands.disarm)
    set_mode = forward("commands", Commands.set_mode)
    param_get = forward("commands", Commands.param_get)
    param_set = forward("commands", Commands.param_set)

    envelope = forward("guard", EnvelopeGuard.envelope)
    set_envelope = forward("guard", EnvelopeGuard.set_envelope)
    reset_envelope = forward("guard", EnvelopeGuard.reset_envelope)
    home = forward("guard", EnvelopeGuard.home)

    takeoff = forward("flights", Flights.takeoff)
    land = forward("flights", Flights.land)
    goto = forward("flights", Flights.goto)
    goto_local = forward("flights", Flights.goto_local)
    return_to_launch = forward("flights", Flights.return_to_launch)
    start_mission = forward("flights", Flights.start_mission)
    pause_mission = forward("flights", Flights.pause_mission)
    resume_mission = forward("flights", Flights.resume_mission)

    upload_mission = forward("missions", Missions.upload_mission)
    mission_progress = forward("missions", Missions.mission_progress)
