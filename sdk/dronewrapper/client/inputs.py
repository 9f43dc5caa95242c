"""One drone's inputs: a newest-value holder per key, the autopilot's texts and the cameras.

:class:`Inputs` subscribes, in the drone's namespace, one newest-value holder per telemetry key
(:class:`~dronewrapper.runtime.latest.Latest`: the value and its age on the node's clock), asked
for by name (``inputs.pose``) or by topic (:meth:`Inputs.latest`); asked again, by whoever reads
this drone (the SDK's getters, a service's loop, the station), it is the same holder, so each
key is subscribed once per drone. The streams named at construction are subscribed at once,
the others on their first read. It keeps the autopilot's last 20 texts, and the camera holders:
those asked for at the start, or each camera the first time it is read (lazy cameras, so frames
cross the network only for a program that uses them). :meth:`Inputs.need` is the read every
getter makes: the newest value, :class:`~dronewrapper.errors.NoData` before the first, a
warning once when it is older than its stream's rate allows
(:func:`dronewrapper.health.stale_after`).
"""

from __future__ import annotations

import collections
import logging
import threading
from collections.abc import Callable, Iterable, Sequence
from typing import Any, TypeVar

import numpy as np

from dronewrapper import images
from dronewrapper.errors import InvalidArgument, NoData
from dronewrapper.health import stale_after
from dronewrapper.msgs import registry
from dronewrapper.msgs.geometry import PoseStamped, TwistStamped
from dronewrapper.msgs.link import LinkStatus
from dronewrapper.msgs.mavros import ExtendedState, State, StatusText
from dronewrapper.msgs.registry import Topic
from dronewrapper.msgs.sensor import BatteryState, NavSatFix
from dronewrapper.runtime.contract import Declared, NodeApi
from dronewrapper.runtime.latest import Latest

T = TypeVar("T")

log = logging.getLogger("dronewrapper")

TELEMETRY_READ_BY_GETTERS = (
    ("extended state", "extended"),
    ("local position", "pose"),
    ("body velocity", "velocity_body"),
    ("local velocity", "velocity_local"),
    ("battery state", "battery"),
)
"""The streams every bridge publishes and the getters read (what ``wait_for_connection`` waits
for; global position needs a GPS and images a camera, so those have their own waits)."""

STREAMS: dict[str, Topic[Any]] = {
    "state": registry.STATE,
    "extended": registry.EXTENDED_STATE,
    "pose": registry.LOCAL_POSE,
    "velocity_body": registry.VELOCITY_BODY,
    "velocity_local": registry.VELOCITY_LOCAL,
    "global_": registry.GLOBAL_POSITION,
    "battery": registry.BATTERY,
    "link": registry.LINK_STATUS,
}
"""The named streams (``inputs.NAME``) and their topics."""

GETTER_STREAMS = tuple(STREAMS)
"""Every named stream: what the SDK's getters read, subscribed from the start."""
FLIGHT_STREAMS = ("state", "extended", "pose")
"""What a flight step and the "ready" rule read: the least a service's loop subscribes."""


def chosen_streams(names: Sequence[str] | None) -> tuple[str, ...]:
    """The streams to subscribe at once for a script that asked for ``names`` (None: every
    getter's): those, with the flight's (:data:`FLIGHT_STREAMS`) always. InvalidArgument names
    an unknown one."""
    if names is None:
        return GETTER_STREAMS
    if isinstance(names, str):
        raise InvalidArgument(f"streams must be a list of names, got the string {names!r}")
    unknown = [name for name in names if name not in STREAMS]
    if unknown:
        raise InvalidArgument(f"unknown streams {unknown}: known are {', '.join(STREAMS)}")
    return tuple(dict.fromkeys((*FLIGHT_STREAMS, *names)))


AGES = {
    "position": "pose",
    "orientation": "pose",
    "velocity": "velocity_body",
    "yaw_rate": "velocity_body",
    "velocity_local": "velocity_local",
    "landed_state": "extended",
    "battery": "battery",
    "global_position": "global_",
    "state": "state",
}
"""A getter's name without ``get_`` -> the stream it reads (see :meth:`Inputs.age`)."""


def camera_key_name(camera: str) -> str:
    """The key name of ``camera`` (``frontal`` -> ``cam_frontal``); InvalidArgument if unknown."""
    try:
        return registry.camera_key_name(camera)
    except ValueError as exc:
        raise InvalidArgument(str(exc)) from None


class Inputs:
    """The newest values of one drone (see the module doc).

    Args:
        node: the node the client stands on; ``ns``: the drone's namespace.
        compressed_images: cameras come as JPEG (``.../image_raw/compressed``), else raw.
        cameras: cameras to receive from the start; None: each on its first read.
        streams: the named streams (:data:`STREAMS`) to subscribe at once.
    """

    def __init__(
        self,
        node: NodeApi,
        ns: str,
        *,
        compressed_images: bool = False,
        cameras: Sequence[str] | None = (),
        streams: Iterable[str] = GETTER_STREAMS,
    ) -> None:
        self.node, self.ns, self.compressed_images = node, ns, compressed_images
        self.subscriptions: list[Declared] = []
        self.holders: dict[str, Latest[Any]] = {}
        """The newest-value holders by key (see :meth:`latest`)."""
        self._lock = threading.Lock()
        self._stale_after: dict[str, float] = {}
        self._stale_warned: set[str] = set()
        for name in streams:
            self.stream(name)
        self.status_texts: collections.deque[StatusText] = collections.deque(maxlen=20)
        self.subscribe(registry.STATUSTEXT, self.status_texts.append)
        self.images: dict[str, Latest[Any]] = {}
        self._decoded: dict[str, tuple[Any, np.ndarray]] = {}
        for camera in cameras or ():
            self._add_camera(camera_key_name(camera))
        self._lazy_cameras = cameras is None

    def subscribe(self, topic: Topic[T], callback: Callable[[T], None], **parts: str) -> Any:
        """``callback(msg)`` for every decodable message on ``topic`` in this namespace."""
        sub = self.node.subscribe(topic, callback, key=topic.key(self.ns, **parts))
        self.subscriptions.append(sub)
        return sub

    def latest(self, topic: Topic[T], **parts: str) -> Latest[T]:
        """The holder of ``topic``'s newest value, aged on the node's clock: one per key, so
        asked again it is the same holder and the key is subscribed once."""
        key = topic.key(self.ns, **parts)
        with self._lock:
            held = self.holders.get(key)
            if held is not None:
                return held
            holder: Latest[T] = Latest(name=key, clock=self.node.clock)
            self.holders[key] = holder
            self._stale_after[key] = stale_after(topic.rate_hz)
        self.subscribe(topic, holder.update, **parts)
        return holder

    # ---- the named streams (see STREAMS): attributes once subscribed

    state: Latest[State]
    extended: Latest[ExtendedState]
    pose: Latest[PoseStamped]
    velocity_body: Latest[TwistStamped]
    velocity_local: Latest[TwistStamped]
    global_: Latest[NavSatFix]
    battery: Latest[BatteryState]
    link: Latest[LinkStatus]

    def stream(self, name: str) -> Latest[Any]:
        """The holder of the named stream ``name`` (:data:`STREAMS`), subscribed on first use
        and kept as the attribute ``name`` (a plain read after that: getters read it at any
        rate)."""
        holder = self.__dict__.get(name)
        if holder is None:
            holder = self.latest(STREAMS[name])  # one holder per key, whoever asks first
            setattr(self, name, holder)
        return holder

    def subscribed(self, name: str) -> bool:
        """Whether the named stream is subscribed: asked for at the start, or read since."""
        return name in self.__dict__

    def __getattr__(self, name: str) -> Any:
        """A named stream not subscribed yet: subscribe it now (see :meth:`stream`)."""
        if name in STREAMS:
            return self.stream(name)
        raise AttributeError(f"{type(self).__name__!r} object has no attribute {name!r}")

    def close(self) -> None:
        for sub in self.subscriptions:
            try:
                sub.undeclare()
            except Exception as exc:  # one the caller undeclared, a session already closed
                log.debug("undeclare: %s", exc)

    # ---- reading

    def need(self, holder: Latest[T], what: str) -> T:
        """The newest value of ``holder``; NoData before the first (naming the key)."""
        value = holder.value
        if value is None:
            raise NoData(
                f"no {what} received yet on {holder.name}: is the bridge running and publishing? "
                "(wait_for_connection() waits for it)"
            )
        age, limit = holder.age(), self._stale_after.get(holder.name, float("inf"))
        if age > limit and holder.name not in self._stale_warned:
            self._stale_warned.add(holder.name)
            log.warning(
                "%s is %.1f s old (stale after %.1f s for its rate): the link or the bridge is "
                "slow; check with `dronewrapper doctor`",
                holder.name,
                age,
                limit,
            )
        elif age <= limit:
            self._stale_warned.discard(holder.name)
        return value

    def age(self, what: str) -> float:
        """Seconds since the newest value of a getter's stream arrived (inf before the first);
        ``what``: a getter's name without ``get_`` (``position``, ``frontal_image`` ...)."""
        if what in ("frontal_image", "ventral_image"):
            holder = self.camera(what.removesuffix("_image"))
            return holder.age() if holder is not None else float("inf")
        if what not in AGES:
            raise InvalidArgument(f"age of {what!r}: use one of {', '.join(sorted(AGES))}")
        return self.stream(AGES[what]).age()

    # ---- cameras

    def camera(self, camera: str) -> Latest[Any] | None:
        """The newest-frame holder of ``camera``, subscribing now if cameras are lazy; None if
        it was not asked for."""
        key_name = camera_key_name(camera)
        holder = self.images.get(key_name)
        if holder is None and self._lazy_cameras:
            holder = self._add_camera(key_name)
        return holder

    def _add_camera(self, key_name: str) -> Latest[Any]:
        topic = registry.IMAGE_COMPRESSED if self.compressed_images else registry.IMAGE_RAW
        holder = self.images[key_name] = self.latest(topic, camera=key_name)
        return holder

    def image(self, camera: str, *, with_stamp: bool = False) -> Any:
        """The newest frame of ``camera`` as BGR (decoded once per frame); NoData if none."""
        holder = self.camera(camera)
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
        cached = self._decoded.get(holder.name)
        if cached is None or cached[0] is not msg:
            self._decoded[holder.name] = cached = (msg, self.decode_image(msg))
        image = cached[1].copy()
        return (image, float(msg.header.stamp)) if with_stamp else image

    def decode_image(self, msg: Any) -> np.ndarray:
        """A camera message (raw or JPEG, as this object receives them) as a BGR array."""
        if self.compressed_images:
            return images.compressed_to_bgr(msg)
        return images.image_to_bgr(msg)
