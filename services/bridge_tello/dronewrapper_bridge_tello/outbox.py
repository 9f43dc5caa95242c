"""What the Tello core fills for the node after each call (:class:`Outbox`)."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from dronewrapper.msgs.registry import Topic


@dataclass
class Outbox:
    """What the node must do after a core call.

    Attributes:
        sends: SDK command strings for the Tello (``command``, ``rc 0 0 0 0`` ...), in order.
        samples: (registry topic, message) to publish on Zenoh.
        video_restart: a ``streamon`` is sent: the video receiver starts a new run (what
            arrives from now on is the new stream, decoded from its first key frame).
    """

    sends: list[str] = field(default_factory=list)
    samples: list[tuple[Topic, Any]] = field(default_factory=list)
    video_restart: bool = False
