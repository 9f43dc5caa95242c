"""Raw MAVLink frames carried over Zenoh, for a ground station beside the bridge."""

from __future__ import annotations

import msgspec

from dronewrapper.msgs.std import Header


class MavlinkFrames(msgspec.Struct, kw_only=True, forbid_unknown_fields=True, frozen=True):
    """Whole MAVLink frames (v1 or v2, signed or not) exactly as they crossed the link, oldest
    first; a batch of a few milliseconds, so 400 frames/s are not 400 Zenoh messages.

    Attributes:
        header: when the batch was sent.
        frames: the frames' bytes.
    """

    header: Header = msgspec.field(default_factory=Header)
    frames: list[bytes]
