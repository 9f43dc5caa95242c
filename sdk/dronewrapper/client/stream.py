"""A drone client's setpoint stream, locked, driven by its own thread or by a service's loop.

The rules (rate, repetition, the idle deadman, the link-gap rule) are
:class:`~dronewrapper.client.setpoint_stream.SetpointStream`'s. This module adds a lock, so the
caller, the link's matching callback and the driver may touch the stream from their threads,
and its two drivers: a thread (``threaded``, the SDK's blocking client: a new setpoint is
published at once on the caller's thread, the thread then repeats it every period, waiting on
the node's clock, so a virtual clock runs it in virtual time and ``set_cmd_vel(az=1); sleep(5)``
keeps spinning until changed or stopped), or a service's loop that calls :meth:`poll` and wakes
by :meth:`next_due` (a loop that hangs stops streaming: a deadman for free).
"""

from __future__ import annotations

import threading
from collections.abc import Callable

from dronewrapper.client.setpoint_stream import DEFAULT_EXPIRY_S, SetpointStream
from dronewrapper.msgs.mavros import PositionTarget
from dronewrapper.runtime.clock import REAL, Clock


class SetpointStreamer:
    """:class:`SetpointStream` on its own thread (see the module doc).

    Args:
        publish: sends one PositionTarget (called under this object's lock, from the caller's
            thread for a new setpoint and from the stream thread for repetitions).
        clock: the clock the thread reads and waits on (the node's).
        rate_hz, idle_timeout, expiry: the stream's (see SetpointStream).
        name: thread name, for debugging.
        threaded: repeat on this object's thread (started by the first :meth:`set`); False:
            the owner's loop calls :meth:`poll`.
    """

    def __init__(
        self,
        publish: Callable[[PositionTarget], None],
        *,
        clock: Clock = REAL,
        rate_hz: float = 30.0,
        idle_timeout: float | None = None,
        name: str = "setpoints",
        expiry: float = DEFAULT_EXPIRY_S,
        threaded: bool = True,
    ) -> None:
        self.core = SetpointStream(
            publish, rate_hz=rate_hz, idle_timeout=idle_timeout, expiry=expiry
        )
        self.clock = clock
        self._name = name
        self._threaded = threaded
        self._cond = threading.Condition()
        self._changes = 0
        self._closed = False
        self._thread: threading.Thread | None = None

    @property
    def target(self) -> PositionTarget | None:
        """The setpoint being streamed, or None when not commanding."""
        return self.core.target

    @property
    def active(self) -> bool:
        """True while a setpoint is being streamed."""
        return self.core.target is not None

    @property
    def published(self) -> int:
        return self.core.published

    @property
    def link_ok(self) -> bool:
        return self.core.link_ok

    def set(self, target: PositionTarget, now: float | None = None) -> None:
        """Publish ``target`` now and keep re-publishing it until changed or stopped (``now``:
        the clock's monotonic time, read here when None)."""
        with self._cond:
            if self._closed:
                raise RuntimeError("the setpoint stream is closed")
            self.core.set(target, self.clock.monotonic() if now is None else now)
            if self._threaded and self._thread is None:
                self._thread = self.clock.thread(self._run, self._name)
                self._thread.start()
            self._changed()

    def poll(self, now: float) -> bool:
        """Re-publish the setpoint if one is due at ``now``; True if it did (a loop's driver)."""
        with self._cond:
            return self.core.poll(now)

    def next_due(self) -> float:
        """When the next re-publication is due (clock's monotonic s; inf when not streaming)."""
        with self._cond:
            return self.core.next_due()

    def link(self, matching: bool) -> None:
        """The publisher's matching status changed (see SetpointStream.link)."""
        with self._cond:
            self.core.link(matching, self.clock.monotonic())
            self._changed()

    def stop(self) -> None:
        """Stop commanding: nothing more is published until the next :meth:`set`."""
        with self._cond:
            self.core.stop()
            self._changed()

    def close(self, timeout: float = 2.0) -> None:
        """Stop and end the thread (idempotent)."""
        with self._cond:
            self._closed = True
            self.core.stop()
            self._changed()
        if self._thread is not None and self._thread is not threading.current_thread():
            self._thread.join(timeout)

    def _changed(self) -> None:
        self._changes += 1
        self._cond.notify_all()

    def _run(self) -> None:
        with self._cond:
            while not self._closed:
                now = self.clock.monotonic()
                due = self.core.next_due()
                if now >= due:
                    self.core.poll(now)
                    continue
                self.clock.wait_for(
                    self._cond,
                    self._changed_since(self._changes),
                    None if due == float("inf") else due - now,
                )

    def _changed_since(self, seen: int) -> Callable[[], bool]:
        return lambda: self._closed or self._changes != seen
