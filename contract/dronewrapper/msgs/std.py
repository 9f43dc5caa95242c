"""Standard message parts shared by every message: the header and the error reply.

`Header.stamp` is float seconds since the Unix epoch (wall clock), as docs/design.md fixes, so
stamps from different processes and machines can be compared directly.
"""

from __future__ import annotations

import time

import msgspec


class Header(msgspec.Struct, frozen=True, kw_only=True):
    """ROS std_msgs/Header: when and in which frame the data was true.

    Attributes:
        stamp: capture or measurement time, float seconds since the Unix epoch.
        frame_id: the coordinate frame of the data (``map`` = local ENU, ``base_link`` = body FLU,
            ``cam_frontal`` = camera optical frame).
        seq: message counter of the publisher (0 when unused).
    """

    stamp: float = 0.0
    frame_id: str = ""
    seq: int = 0

    @classmethod
    def now(cls, frame_id: str = "", seq: int = 0) -> Header:
        """A header stamped with the current wall-clock time."""
        return cls(stamp=time.time(), frame_id=frame_id, seq=seq)


class ErrorReply(msgspec.Struct, kw_only=True, frozen=True):
    """Payload of a service's error reply: the request was malformed or could not be served.

    Attributes:
        message: what is wrong, for a person to read (names the bad field or the refusal reason).
        code: a short machine-readable class: ``bad_request``, ``refused``, ``timeout``,
            ``unavailable`` or ``internal``.
    """

    message: str
    code: str = "bad_request"
