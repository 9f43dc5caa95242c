"""A typed publisher on one concrete key: it checks the message's type, encodes it (or writes
it straight into shared memory) and puts it with its attachment. :meth:`Node.publisher
<dronewrapper.runtime.node.Node.publisher>` declares one with the topic's QoS."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, Generic, TypeVar

import zenoh

from dronewrapper.msgs import codec
from dronewrapper.runtime.session import encoding_for
from dronewrapper.runtime.shm_put import BLOCK_WAIT_S, ShmWriter

T = TypeVar("T")


class Publisher(Generic[T]):
    """A typed publisher on one concrete key; images go through ``shm`` (written straight into
    shared memory, see :mod:`dronewrapper.runtime.shm_put`) when given. ``max_bytes``: the
    largest payload it may put outside shared memory (a low-latency session's limit, see
    :data:`~dronewrapper.runtime.options.LOW_LATENCY_MAX_BYTES`); None: any size."""

    def __init__(
        self,
        session: zenoh.Session,
        key: str,
        msg_type: type[T],
        *,
        shm: ShmWriter | None = None,
        max_bytes: int | None = None,
        **qos: Any,
    ) -> None:
        self.key = key
        self._max_bytes = max_bytes
        self.type = msg_type
        self.count = 0
        self._shm = shm
        blocking = qos.get("congestion_control") == zenoh.CongestionControl.BLOCK
        self._shm_wait_s = BLOCK_WAIT_S if blocking else 0.0
        self._pub = session.declare_publisher(key, encoding=encoding_for(msg_type), **qos)

    def put(self, msg: T, *, attachment: bytes | None = None) -> None:
        """Publish ``msg`` (must be of this publisher's type); ``attachment`` travels with it
        (see :mod:`dronewrapper.runtime.caller`).

        Raises:
            TypeError: ``msg`` is not of this publisher's type.
            ValueError: the encoded message is over ``max_bytes`` outside shared memory.
        """
        if type(msg) is not self.type:
            raise TypeError(f"{self.key} carries {self.type.__name__}, got {type(msg).__name__}")
        payload: zenoh.ZBytes | bytes | None = None
        if self._shm:
            payload = self._shm.payload(msg, wait_s=self._shm_wait_s)
        if payload is None:
            data = codec.encode(msg)
            if self._max_bytes is not None and len(data) > self._max_bytes:
                raise ValueError(
                    f"{self.key}: a {len(data)}-byte {self.type.__name__} is over the "
                    f"{self._max_bytes} bytes a low-latency session carries outside shared "
                    "memory (it does not fragment); not sent"
                )
            payload = data
        if attachment is None:
            self._pub.put(payload)  # quicker in the binding than attachment=None
        else:
            self._pub.put(payload, attachment=attachment)
        self.count += 1

    def watched(self) -> bool:
        """True while at least one subscriber matches this key (so the work can be skipped)."""
        try:
            status = self._pub.matching_status  # a MatchingStatus; zenoh's stub says bool
            return bool(status.matching)  # type: ignore[attr-defined]
        except zenoh.ZError:
            return False

    def on_matching(self, callback: Callable[[bool], None]) -> Any:
        """Call ``callback(matching)`` whenever subscribers start or stop matching this key
        (a direct callback: keep it short); returns the listener (``undeclare()`` it)."""

        def on_status(status: zenoh.MatchingStatus) -> None:
            callback(status.matching)

        handler = zenoh.handlers.Callback(on_status, indirect=False)
        return self._pub.declare_matching_listener(handler)

    def undeclare(self) -> None:
        self._pub.undeclare()
