"""The commander's beat: this process is alive, said about once a second on
``{ns}/dronewrapper/commander/beat`` while a go-to, return or mission it started may run
unattended (the bridge then ends it as for a lost commander once the beats stop: docs/design.md
"Long actions"). One daemon thread on the node's clock; it ends with the process, so a Ctrl-C,
a crash or a closed wrapper stop the beats.
"""

from __future__ import annotations

import threading
from collections.abc import Callable

from dronewrapper.msgs.flight import CommanderBeat
from dronewrapper.runtime.clock import Clock

PERIOD_S = 1.0


class Beat:
    """Publishes ``CommanderBeat(key)`` every :data:`PERIOD_S` s from :meth:`start` (idempotent)
    until :meth:`close`."""

    def __init__(self, publish: Callable[[CommanderBeat], None], key: str, clock: Clock) -> None:
        self._publish = publish
        self.key = key
        self._clock = clock
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None

    def start(self) -> None:
        if self._thread is None and not self._stop.is_set():
            self._send()  # at once: the bridge sees it before the action's first check
            self._thread = self._clock.thread(self._run, "dronewrapper-beat")
            self._thread.start()

    def _send(self) -> None:
        self._publish(CommanderBeat(key=self.key, stamp=self._clock.time()))

    def _run(self) -> None:
        while not self._clock.wait(self._stop, PERIOD_S):
            try:
                self._send()
            except Exception:  # a closed session: the process is ending
                return

    def close(self) -> None:
        self._stop.set()
        if self._thread is not None and self._thread is not threading.current_thread():
            self._thread.join(2.0)
