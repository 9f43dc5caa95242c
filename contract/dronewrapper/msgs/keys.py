"""What an entry of the key registry is: a key template with its placeholders, and the three
kinds of entry (:class:`Topic`, :class:`Service`, :class:`Liveliness`) with the transport
classes a topic travels in. The entries themselves: :mod:`dronewrapper.msgs.registry`.

    >>> Topic("{ns}/camera/{camera}").key("drone1", camera="cam_frontal")
    'drone1/camera/cam_frontal'
"""

from __future__ import annotations

import re
import string
from dataclasses import KW_ONLY, dataclass, field
from functools import cached_property
from typing import Generic, TypeVar

T = TypeVar("T")
Req = TypeVar("Req")
Rep = TypeVar("Rep")

DEFAULT_NAMESPACE = "drone"
CAMERAS = ("cam_frontal", "cam_ventral")
CAMERA_SHORT_NAMES = {"frontal": "cam_frontal", "ventral": "cam_ventral"}
"""The SDK's camera names (``get_image("frontal")``) and the key names they stand for."""


def camera_key_name(camera: str) -> str:
    """The key name (``cam_frontal``) of a camera given by short or key name.

    Raises:
        ValueError: an unknown camera.
    """
    if camera in CAMERA_SHORT_NAMES:
        return CAMERA_SHORT_NAMES[camera]
    if camera in CAMERAS:
        return camera
    raise ValueError(f"unknown camera {camera!r}: use 'frontal' or 'ventral'")


_FIELD_VALUE = r"[A-Za-z0-9_\-.]+"  # one chunk: no '/', no wildcard


def _fields(template: str) -> tuple[str, ...]:
    return tuple(name for _, name, _, _ in string.Formatter().parse(template) if name)


def _check_chunk(name: str, value: str) -> str:
    if not isinstance(value, str) or not re.fullmatch(_FIELD_VALUE, value):
        raise ValueError(f"key field {name}={value!r} must be one chunk of [A-Za-z0-9_-.]")
    return value


@dataclass(frozen=True)
class _Template:
    template: str

    @cached_property
    def fields(self) -> tuple[str, ...]:
        """Names of the placeholders in the template, in order."""
        return _fields(self.template)

    def key(self, ns: str = DEFAULT_NAMESPACE, **parts: str) -> str:
        """The concrete key for namespace ``ns`` and the other placeholders in ``parts``."""
        values = {"ns": ns, **parts}
        missing = [f for f in self.fields if f not in values]
        if missing:
            raise ValueError(f"{self.template}: missing key field(s) {', '.join(missing)}")
        return self.template.format(**{f: _check_chunk(f, values[f]) for f in self.fields})

    def wildcard(self, ns: str = "*", **parts: str) -> str:
        """A key expression matching every instance (unset placeholders become ``*``)."""
        values = {"ns": ns, **parts}
        return self.template.format(**{f: values.get(f, "*") for f in self.fields})

    @cached_property
    def regex(self) -> re.Pattern[str]:
        """Regex matching concrete keys of this template, capturing each placeholder."""
        out = ""
        for literal, name, _, _ in string.Formatter().parse(self.template):
            out += re.escape(literal)
            if name:
                out += f"(?P<{name}>{_FIELD_VALUE})"
        return re.compile(out + r"\Z")

    def match(self, key: str) -> dict[str, str] | None:
        """The placeholder values if ``key`` is an instance of this template, else None."""
        m = self.regex.match(key)
        return m.groupdict() if m else None


COMMAND = "command"
"""Transport class of commands (setpoints, teleop): highest priority, sent at once, and the
sender waits rather than drop one."""
TELEMETRY = "telemetry"
"""Transport class of telemetry, state and detections: high priority, never behind images; a
publisher is never blocked by a slow subscriber (its queue drops only if the link is dead)."""
STREAM = "stream"
"""Transport class of camera frames: lowest priority, latest-only, dropped under congestion,
so a slow link loses frames but never control."""
TRANSPORTS = (COMMAND, TELEMETRY, STREAM)


@dataclass(frozen=True)
class Topic(_Template, Generic[T]):
    """A pub/sub key: template, message type, nominal rate (Hz, 0 = event-driven), publishers,
    and its transport class (``command``, ``telemetry`` or ``stream``); all but the template are
    keyword entries."""

    _: KW_ONLY
    type: type[T] = field(default=object)  # type: ignore[assignment]
    rate_hz: float = 0.0
    publishers: tuple[str, ...] = ()
    doc: str = ""
    transport: str = TELEMETRY

    def __post_init__(self) -> None:
        if self.transport not in TRANSPORTS:
            raise ValueError(f"{self.template}: transport must be one of {TRANSPORTS}")


@dataclass(frozen=True)
class Service(_Template, Generic[Req, Rep]):
    """A request/reply key served by a Zenoh queryable (keyword entries after the template)."""

    _: KW_ONLY
    request: type[Req] = field(default=object)  # type: ignore[assignment]
    reply: type[Rep] = field(default=object)  # type: ignore[assignment]
    server: str = ""
    doc: str = ""


@dataclass(frozen=True)
class Liveliness(_Template):
    """A liveliness token key: present while the process holding it is alive."""

    _: KW_ONLY
    doc: str = ""
