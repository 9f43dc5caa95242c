"""The newest raw sample of each of PX4's high-rate topics, kept for the core's tick.

PX4 publishes ``vehicle_local_position`` at ~110 Hz and ``vehicle_attitude`` at ~200 Hz (global
position ~50 Hz); the bridge publishes pose at its stream rate (``stream_rate_hz``, the
contract's 30 Hz). Decoding every sample as it arrives cost a large share of a core in Python
on a loaded machine and starved the setpoint stream. So raw samples are only stored here (one
dict assignment under a small lock, nothing decoded, no core lock taken), a newer one
replacing the one not yet read; the core's tick takes what is there and decodes only that
(:meth:`~dronewrapper_bridge_px4_zenoh.core.Px4ZenohCore.tick`). The node puts, before each
tick, the newest sample its Zenoh subscriber kept (a ring of one).

:class:`NewestSamples` is the one thread-safe piece of the core's state: whoever puts and the
tick that takes each hold the store's own lock (for a dict operation only).
"""

from __future__ import annotations

import threading
from dataclasses import dataclass


@dataclass(frozen=True)
class RawSample:
    """One sample as received: its data key and CDR payload (bytes, encapsulation included)."""

    key: str
    payload: bytes


class NewestSamples:
    """Per topic name, the newest :class:`RawSample` not yet taken.

    Attributes:
        received: samples put since the start.
        replaced: samples replaced by a newer one before the tick took them (never decoded).
    """

    def __init__(self) -> None:
        self._lock = threading.Lock()
        self._newest: dict[str, RawSample] = {}
        self.received = 0
        self.replaced = 0

    def put(self, topic: str, key: str, payload: bytes) -> None:
        """Keep ``payload`` (on data key ``key``) as ``topic``'s newest sample."""
        with self._lock:
            self.received += 1
            if topic in self._newest:
                self.replaced += 1
            self._newest[topic] = RawSample(key, payload)

    def take(self) -> dict[str, RawSample]:
        """The newest sample of each topic put since the last take (then forgotten)."""
        with self._lock:
            newest, self._newest = self._newest, {}
        return newest

    def __len__(self) -> int:
        return len(self._newest)
