"""A DroneWrapper's inputs: one drone's newest values on a node, and the getters that read them.

:class:`Inputs` subscribes, in the drone's namespace, a newest-value holder per telemetry stream
(aged on the node's clock), keeps the autopilot's last 20 texts, and the camera holders: those
asked for at the start, or each camera the first time it is read (lazy cameras, so frames cross
the network only for a program that uses them). :meth:`Inputs.need` is the read every getter
makes: the newest value, :class:`~dronewrapper.errors.NoData` before the first, a warning once
when it is older than its stream's rate allows (:func:`dronewrapper.health.stale_after`).

:class:`Getters` is the paper's getters over ``self.inputs`` (no I/O, no waiting): positions in
local ENU metres, velocities in body FLU or local ENU m/s, angles in radians (ENU, yaw
counter-clockwise positive), images as BGR ``uint8`` arrays.
"""

from __future__ import annotations

import collections
import logging
from collections.abc import Callable, Sequence
from typing import Any, TypeVar

import numpy as np

from dronewrapper import images, telemetry
from dronewrapper.errors import InvalidArgument, NoData
from dronewrapper.health import stale_after
from dronewrapper.msgs import registry
from dronewrapper.msgs.link import LinkStatus
from dronewrapper.msgs.mavros import LANDED_STATE_IN_AIR, LANDED_STATE_TAKEOFF, State, StatusText
from dronewrapper.msgs.registry import Topic
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
"""A getter's name without ``get_`` -> the holder it reads (see :meth:`Inputs.age`)."""


def camera_key_name(camera: str) -> str:
    """The key name of ``camera`` (``frontal`` -> ``cam_frontal``); InvalidArgument if unknown."""
    try:
        return registry.camera_key_name(camera)
    except ValueError as exc:
        raise InvalidArgument(str(exc)) from None


class Inputs:
    """The newest values of one drone (see the module doc).

    Args:
        node: the node the wrapper stands on; ``ns``: the drone's namespace.
        compressed_images: cameras come as JPEG (``.../image_raw/compressed``), else raw.
        cameras: cameras to receive from the start; None: each on its first read.
    """

    def __init__(
        self, node: NodeApi, ns: str, *, compressed_images: bool, cameras: Sequence[str] | None
    ) -> None:
        self.node, self.ns, self.compressed_images = node, ns, compressed_images
        self.subscriptions: list[Declared] = []
        self.holders: dict[str, Latest[Any]] = {}
        """The newest-value holders by key (see :meth:`latest`)."""
        self._stale_after: dict[str, float] = {}
        self._stale_warned: set[str] = set()
        self.state: Latest[State] = self.latest(registry.STATE)
        self.extended = self.latest(registry.EXTENDED_STATE)
        self.pose = self.latest(registry.LOCAL_POSE)
        self.velocity_body = self.latest(registry.VELOCITY_BODY)
        self.velocity_local = self.latest(registry.VELOCITY_LOCAL)
        self.global_ = self.latest(registry.GLOBAL_POSITION)
        self.battery = self.latest(registry.BATTERY)
        self.link = self.latest(registry.LINK_STATUS)
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
        asked again (by another reader of this drone, the station) it is the same holder and
        the key is subscribed once."""
        key = topic.key(self.ns, **parts)
        held = self.holders.get(key)
        if held is not None:
            return held
        holder: Latest[T] = Latest(name=key, clock=self.node.clock)
        self.subscribe(topic, holder.update, **parts)
        self._stale_after[key] = stale_after(topic.rate_hz)
        self.holders[key] = holder
        return holder

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
        return getattr(self, AGES[what]).age()

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


class Getters:
    """The paper's getters over ``self.inputs`` (see the module doc); a DroneWrapper part."""

    inputs: Inputs

    def get_state(self) -> State:
        """The newest autopilot State (connected, armed, mode, autopilot, failsafe ...)."""
        return self.inputs.need(self.inputs.state, "state")

    def get_position(self) -> np.ndarray:
        """``np.array([x, y, z])``: position in local ENU metres (origin: the take-off point)."""
        return telemetry.position_of(self.inputs.need(self.inputs.pose, "local position"))

    def get_velocity(self) -> np.ndarray:
        """``np.array([vx, vy, vz])``: velocity in body FLU m/s (forward, left, up)."""
        return telemetry.linear_of(self.inputs.need(self.inputs.velocity_body, "body velocity"))

    def get_velocity_local(self) -> np.ndarray:
        """``np.array([vx, vy, vz])``: velocity in local ENU m/s (east, north, up)."""
        msg = self.inputs.need(self.inputs.velocity_local, "local velocity")
        return telemetry.linear_of(msg)

    def get_yaw_rate(self) -> float:
        """Yaw rate in rad/s, counter-clockwise positive."""
        msg = self.inputs.need(self.inputs.velocity_body, "body velocity")
        return telemetry.yaw_rate_of(msg)

    def get_orientation(self) -> np.ndarray:
        """``np.array([roll, pitch, yaw])`` in radians, ENU (yaw 0 = east, CCW positive)."""
        return telemetry.orientation_of(self.inputs.need(self.inputs.pose, "local position"))

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
        return int(self.inputs.need(self.inputs.extended, "extended state").landed_state)

    def get_battery(self) -> float:
        """Battery charge as a fraction 0..1 (NaN if the aircraft does not report it)."""
        return float(self.inputs.need(self.inputs.battery, "battery state").percentage)

    def get_link(self) -> LinkStatus:
        """The autopilot link as the bridge last reported it (about once a second): its load
        (``load``, 1.0 = a serial line full), rates, frames lost, reconnects; ``describe()``
        says ``link 94 % full (serial 57600 baud: 5.4 / 1.8 kB/s down/up), 0 lost, ...``.
        NoData when the bridge reports none (the Tello's)."""
        return self.inputs.need(self.inputs.link, "link status")

    def get_global_position(self) -> np.ndarray:
        """``np.array([latitude, longitude, altitude])``: degrees, degrees, metres AMSL.

        Raises NoData when the aircraft has no GPS (nothing published).
        """
        return telemetry.global_of(self.inputs.need(self.inputs.global_, "global position (GPS)"))

    def is_flying(self) -> bool:
        """True if the landed state is in the air or taking off."""
        extended = self.inputs.extended.value
        return extended is not None and extended.landed_state in (
            LANDED_STATE_IN_AIR,
            LANDED_STATE_TAKEOFF,
        )

    def age(self, what: str) -> float:
        """Seconds since the newest value of a getter's stream arrived (inf before the first).

        ``what`` names a getter without ``get_``: ``position``, ``orientation``, ``velocity``,
        ``velocity_local``, ``yaw_rate``, ``landed_state``, ``battery``, ``global_position``,
        ``state``, ``frontal_image``, ``ventral_image``.
        """
        return self.inputs.age(what)

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
        return self.inputs.image(camera, with_stamp=with_stamp)

    def decode_image(self, msg: Any) -> np.ndarray:
        """A camera message (raw or JPEG, as this object receives them) as a BGR array."""
        return self.inputs.decode_image(msg)

    def get_frontal_image(self) -> np.ndarray:
        """The newest frontal camera frame, BGR ``uint8`` (height, width, 3)."""
        return self.get_image("frontal")

    def get_ventral_image(self) -> np.ndarray:
        """The newest ventral (downward) camera frame, BGR ``uint8`` (height, width, 3)."""
        return self.get_image("ventral")
