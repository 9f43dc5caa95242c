"""Whether anyone subscribes to the Tello's camera: the camera publishers' matching listeners.

Zenoh calls a matching listener on its own thread whenever subscribers start or stop matching
a publisher's key; :class:`CameraWatch` only records the latest status of each key there (no
lock, no call into the core), and the bridge's control loop reads :attr:`CameraWatch.watched`
at every tick, so the video's decision (video_demand.py) runs in the core with the core's time.
"""

from __future__ import annotations

from collections.abc import Iterable
from typing import Any


class CameraWatch:
    """The matching status of ``publishers`` (the raw image and its compressed form).

    Args:
        publishers: publishers with ``key`` and ``on_matching(callback)`` (the runtime's
            ``Publisher``, or the fake bus's).
    """

    def __init__(self, publishers: Iterable[Any]) -> None:
        publishers = list(publishers)
        self._matching = {p.key: p.watched() for p in publishers}
        self._listeners = [p.on_matching(self._recorder(p.key)) for p in publishers]

    def _recorder(self, key: str):
        def record(matching: bool) -> None:
            self._matching[key] = bool(matching)

        return record

    @property
    def watched(self) -> bool:
        """True while at least one subscriber matches one of the camera's keys."""
        return any(self._matching.values())

    def close(self) -> None:
        """Undeclare the listeners."""
        for listener in self._listeners:
            listener.undeclare()
        self._listeners = []
