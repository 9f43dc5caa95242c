"""Samples to messages: the one decode path of every subscriber (Node, FakeNode, DroneWrapper).

A sample's payload is decoded with its topic's registry type and handed to the callback while
the sample's commander (its attachment) is recorded (see :mod:`dronewrapper.runtime.caller`).
An undecodable payload or an exception in the callback is counted per key in
:class:`SampleErrors` and logged at most once per period per key, and never ends the
subscription nor reaches Zenoh's receive thread.
"""

from __future__ import annotations

import logging
import time
from collections import Counter
from collections.abc import Callable
from typing import Any, TypeVar

import msgspec

from dronewrapper.msgs import codec
from dronewrapper.runtime import caller

T = TypeVar("T")

ERROR_LOG_PERIOD_S = 5.0
"""Shortest time between two log lines of the same error kind on the same key (s)."""

Deliver = Callable[[str, bytes, Any], None]
"""``deliver(key, payload, attachment)``: decode one sample and call the callback with it."""


class SampleErrors:
    """Counts of undecodable samples (``decode``) and failed callbacks (``callback``) per key,
    logged to ``log`` at most every ``period`` seconds of ``clock`` per key and kind."""

    def __init__(
        self,
        log: logging.Logger,
        clock: Callable[[], float] = time.monotonic,
        period: float = ERROR_LOG_PERIOD_S,
    ) -> None:
        self.log = log
        self.decode: Counter[str] = Counter()
        self.callback: Counter[str] = Counter()
        self._clock = clock
        self._period = period
        self._last_log: dict[tuple[str, str], float] = {}

    def note(self, counter: Counter[str], what: str, key: str, exc: BaseException) -> None:
        """Count ``exc`` under ``key`` in ``counter`` and log it unless logged recently."""
        counter[key] += 1
        now = self._clock()
        if now - self._last_log.get((what, key), -float("inf")) >= self._period:
            self._last_log[(what, key)] = now
            self.log.warning("%s on %s (%d so far): %s", what, key, counter[key], exc)


def decoding(
    message_type: type[T],
    callback: Callable[..., None],
    errors: SampleErrors,
    *,
    keyed: bool = False,
) -> Deliver:
    """A ``deliver(key, payload, attachment)`` that decodes ``payload`` as ``message_type``
    and calls ``callback(msg)`` (``callback(key, msg)`` when ``keyed``: for a wildcard whose
    matches differ by key); failures are counted and logged in ``errors``."""
    decoder = codec.decoder(message_type)

    def deliver(key: str, payload: bytes, attachment: Any = None) -> None:
        try:
            msg = decoder.decode(payload)
        except (msgspec.DecodeError, msgspec.ValidationError) as exc:
            errors.note(errors.decode, "undecodable sample", key, exc)
            return
        try:
            with caller.handling(attachment, key):
                if keyed:
                    callback(key, msg)
                else:
                    callback(msg)
        except Exception as exc:  # never let an exception reach Zenoh's receive thread
            errors.note(errors.callback, "callback error", key, exc)

    return deliver
