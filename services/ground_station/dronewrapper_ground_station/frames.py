"""Latest-only video: the station keeps each camera's newest JPEG message in a newest-value
holder (:class:`~dronewrapper.runtime.latest.Latest`, on the station node's clock), never a queue.

The bus callback updates the holder; each page's sender takes the newest when the page has
drawn the previous one (it acknowledges each frame), so a slow page or link skips frames instead
of falling behind: what it shows is never older than one frame plus its own transfer.
"""

from __future__ import annotations

from dronewrapper.msgs.sensor import CompressedImage


def pack(frame: CompressedImage, header: bytes) -> bytes:
    """A WebSocket binary message: 4-byte big-endian header length, JSON header, JPEG."""
    return len(header).to_bytes(4, "big") + header + bytes(frame.data)
