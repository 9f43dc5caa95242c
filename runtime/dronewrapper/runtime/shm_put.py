"""Images written straight into Zenoh shared memory: the pixels are copied once, not twice.

A message put as ``bytes`` costs two copies of its pixels on the way out: MessagePack writes the
whole message into a new buffer, then Zenoh copies that buffer into shared memory. Zenoh's
shared-memory API saves one: the message is encoded without its pixels (a few dozen bytes), the
MessagePack ``bin`` header of its last field, ``data``, is widened to the pixels' size, and
header and pixels are written into one buffer from Zenoh's provider (``ZShmMut``), which is put
as it is. The bytes on the wire are exactly MessagePack's, so subscribers see no difference.

What the Python binding (eclipse-zenoh 1.10) still forces: ``ZShmMut`` takes only ``bytes`` or
``bytearray`` (no buffer protocol), so pixels held in a NumPy array or a memoryview of one are
copied to ``bytes`` first, and MessagePack cannot encode into shared memory; on the receiving
side ``ZBytes`` has no buffer protocol either, so ``to_bytes()`` copies the payload out of shared
memory once (the typed decode after it is zero-copy).
"""

from __future__ import annotations

import logging
import time
from typing import Any

import msgspec
import zenoh

from dronewrapper.msgs import codec

log = logging.getLogger("dronewrapper.runtime")

MIN_BYTES = 64 * 1024
"""Smaller payloads go the ordinary way (Zenoh's own shared-memory threshold is 3 kB; below
this size the saved copy is worth less than the allocation)."""

POOL_BYTES = 32 * 1024 * 1024
"""Shared memory a process's provider may hold (RAM-backed, touched as used): 35 frames of
640x480 bgr8 in flight, 11 of 1280x720."""

BLOCK_WAIT_S = 0.1
"""How long a BLOCK publisher waits for room in a full pool before it falls back (s)."""
WAIT_STEP_S = 0.0005
"""How often a waiting put looks for a released buffer (s)."""

_EMPTY_DATA_TAIL = b"\xa4data\xc4\x00"  # "data" -> bin8 of length 0
_BIN32 = b"\xc6"


def pixel_bytes(data: Any) -> bytes:
    """``data`` as ``bytes``, without copying when it is ``bytes`` or a whole view of them."""
    if isinstance(data, bytes):
        return data
    whole_view = (
        isinstance(data, memoryview)
        and isinstance(data.obj, bytes)
        and data.c_contiguous
        and data.nbytes == len(data.obj)
    )
    if whole_view:
        return data.obj
    return bytes(data)


def split_message(msg: Any) -> tuple[bytes, bytes] | None:
    """(MessagePack of ``msg`` up to its pixels, the pixels) so that ``head + pixels`` is
    exactly ``codec.encode(msg)``; None for a message without a large trailing ``data`` field."""
    data = getattr(msg, "data", None)
    if data is None or not isinstance(msg, msgspec.Struct):
        return None
    try:
        size = memoryview(data).nbytes
    except TypeError:
        return None
    if size < MIN_BYTES:
        return None
    head = codec.encode(msgspec.structs.replace(msg, data=b""))
    if not head.endswith(_EMPTY_DATA_TAIL):  # ``data`` is not the last field
        return None
    return head[:-2] + _BIN32 + size.to_bytes(4, "big"), pixel_bytes(data)


class ShmWriter:
    """Builds shared-memory payloads for large messages (one provider per process, made on
    first use); falls back to the ordinary path (``payload`` returns None, counted in
    ``fallbacks``) when the message does not fit the scheme or the pool is really full.

    Zenoh's provider reclaims sent buffers only when an allocation fails (garbage collection),
    and never merges the reclaimed chunks: after a few seconds of frames the pool is a row of
    frame-sized free chunks, and a frame a byte larger than the last (MessagePack's header
    grows as ``header.seq`` passes 127, 255 and 65535; a camera changes size) fits none of
    them. A failed allocation is therefore retried once after a defragmentation; only a pool
    full of buffers still in flight (readers slower than the camera) falls back.
    """

    def __init__(self, pool_bytes: int = POOL_BYTES) -> None:
        self.pool_bytes = pool_bytes
        self.fallbacks = 0
        """Puts that went the ordinary way because the pool had no room (0 in a healthy
        process: readers keep up)."""
        self._provider: Any = None
        self._policy: Any = None

    def _alloc(self, size: int) -> Any:
        from zenoh.shm import GarbageCollect, ShmProvider

        if self._provider is None:
            self._provider = ShmProvider.default_backend(self.pool_bytes)
            self._policy = GarbageCollect()
        try:
            return self._provider.alloc(size, self._policy)
        except zenoh.ZError:  # free chunks, but none of this size: merge them, and retry
            self._provider.defragment()
            return self._provider.alloc(size, self._policy)

    def _alloc_waiting(self, size: int, wait_s: float) -> Any:
        deadline = time.monotonic() + wait_s
        while True:
            try:
                return self._alloc(size)
            except zenoh.ZError:
                if time.monotonic() >= deadline:
                    raise
            time.sleep(WAIT_STEP_S)

    def payload(self, msg: Any, *, wait_s: float = 0.0) -> zenoh.ZBytes | None:
        """The message in a shared-memory buffer, or None: put ``codec.encode(msg)`` instead.

        ``wait_s``: how long a full pool may be waited on for a reader to release a buffer
        (s; a publisher whose congestion control is BLOCK waits, a DROP one does not).
        """
        parts = split_message(msg)
        if parts is None:
            return None
        head, pixels = parts
        size = len(head) + len(pixels)
        try:
            buf = self._alloc_waiting(size, wait_s)
        except zenoh.ZError as exc:  # every buffer in flight (slow readers), or no SHM
            self.fallbacks += 1
            if self.fallbacks & (self.fallbacks - 1) == 0:  # the 1st, 2nd, 4th, 8th ...
                log.warning(
                    "shared-memory put fell back to an ordinary one (%d so far): %s for %d "
                    "bytes in a pool of %d MiB (readers too slow to release their frames?)",
                    self.fallbacks,
                    exc,
                    size,
                    self.pool_bytes // (1024 * 1024),
                )
            return None
        buf[0 : len(head)] = head
        buf[len(head) : size] = pixels
        return zenoh.ZBytes(buf)
