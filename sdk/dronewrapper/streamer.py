"""The setpoint stream: ONE background thread re-publishes the latest setpoint at a fixed rate.

The failsafe contract (docs/design.md): once the SDK commands, it keeps re-publishing the latest
setpoint at >= 20 Hz until it is changed or stopped, so ``set_cmd_vel(az=1); sleep(5)`` keeps
spinning.
If the stream stops (the app exits, crashes or calls :meth:`SetpointStreamer.stop`), the bridge
holds position after its ``setpoint_timeout`` and lands after ``commander_lost_timeout``.

A new setpoint is published at once on the caller's thread (lowest latency); the thread then
repeats it every period. ``header.stamp`` keeps the stamp given with the command (the source
frame's capture time), ``header.seq`` counts every publication.

Link gaps: while the link to the bridge is down (:meth:`SetpointStreamer.link_down`, e.g. the
router restarted) nothing is published; when it is back (:meth:`SetpointStreamer.link_up`) a
command older than ``expiry`` (the bridge's setpoint expiry) is not resent: the stream stops
and the app must command again. Otherwise a stale 1 m/s, repeated into the void during the
gap, would make a hovering drone fly off again the moment the link returned.
"""

from __future__ import annotations

import logging
import threading
import time
from collections.abc import Callable

import msgspec

from dronewrapper.msgs.mavros import PositionTarget

log = logging.getLogger("dronewrapper.streamer")

MIN_RATE_HZ = 20.0


class SetpointStreamer:
    """Publishes ``publish(target)`` now and then every ``1 / rate_hz`` s until changed.

    Args:
        publish: sends one PositionTarget (called under this object's lock, from the caller's
            thread for a new setpoint and from the stream thread for repetitions).
        rate_hz: repetition rate, at least 20 Hz.
        idle_timeout: if not None, stop streaming when no new setpoint was given for this many
            seconds (the bridge then hovers): a deadman for apps that may hang. None (the
            paper's behaviour) streams until changed or stopped.
        name: thread name, for debugging.
        expiry: seconds after which a command is stale if the link was down meanwhile (the
            bridge's ``setpoint_timeout``, 0.5 s by default).
    """

    def __init__(
        self,
        publish: Callable[[PositionTarget], None],
        *,
        rate_hz: float = 30.0,
        idle_timeout: float | None = None,
        name: str = "setpoints",
        expiry: float = 0.5,
    ) -> None:
        if not rate_hz >= MIN_RATE_HZ:
            raise ValueError(f"setpoint rate must be >= {MIN_RATE_HZ:g} Hz, got {rate_hz!r}")
        if idle_timeout is not None and not idle_timeout > 0:
            raise ValueError(f"idle_timeout must be > 0 s or None, got {idle_timeout!r}")
        if not expiry > 0:
            raise ValueError(f"expiry must be > 0 s, got {expiry!r}")
        self.period = 1.0 / rate_hz
        self.idle_timeout = idle_timeout
        self.expiry = expiry
        self.link_ok = True
        self.withheld = 0  # publications skipped while the link was down
        self.dropped_after_gap = 0  # commands not resent because they were stale after a gap
        self.published = 0
        self.errors = 0
        self._publish = publish
        self._name = name
        self._cond = threading.Condition()
        self._target: PositionTarget | None = None
        self._set_at = 0.0
        self._closed = False
        self._thread: threading.Thread | None = None

    @property
    def target(self) -> PositionTarget | None:
        """The setpoint being streamed, or None when not commanding."""
        return self._target

    @property
    def active(self) -> bool:
        """True while a setpoint is being streamed."""
        return self._target is not None

    def set(self, target: PositionTarget) -> None:
        """Publish ``target`` now and keep re-publishing it until changed or stopped."""
        with self._cond:
            if self._closed:
                raise RuntimeError("the setpoint stream is closed")
            self._target = target
            self._set_at = time.monotonic()
            self._send(target)
            if self._thread is None:
                self._thread = threading.Thread(target=self._run, name=self._name, daemon=True)
                self._thread.start()
            self._cond.notify_all()

    def link_down(self) -> None:
        """The bridge is unreachable: publish nothing until :meth:`link_up`."""
        with self._cond:
            if self.link_ok:
                log.warning("link to the bridge lost: setpoints withheld until it returns")
            self.link_ok = False

    def link_up(self, now: float | None = None) -> None:
        """The bridge is reachable again: resume, unless the command is older than ``expiry``
        (``now``: monotonic s, injectable for tests)."""
        now = time.monotonic() if now is None else now
        with self._cond:
            if self.link_ok:
                return
            age = now - self._set_at
            if self._target is not None and age > self.expiry:
                log.warning(
                    "link to the bridge back: the last command is %.1f s old (> %.1f s), "
                    "not resent; command again",
                    age,
                    self.expiry,
                )
                self._target = None
                self.dropped_after_gap += 1
            # Last: a reader that sees the link up (without taking the lock) also sees the
            # stale command already dropped.
            self.link_ok = True
            self._cond.notify_all()

    def stop(self) -> None:
        """Stop commanding: nothing more is published until the next :meth:`set`."""
        with self._cond:
            self._target = None
            self._cond.notify_all()

    def close(self, timeout: float = 2.0) -> None:
        """Stop and end the thread (idempotent)."""
        with self._cond:
            self._closed = True
            self._target = None
            self._cond.notify_all()
        if self._thread is not None and self._thread is not threading.current_thread():
            self._thread.join(timeout)

    def _send(self, target: PositionTarget) -> None:
        if not self.link_ok:
            self.withheld += 1
            return
        header = msgspec.structs.replace(target.header, seq=self.published)
        target = msgspec.structs.replace(target, header=header)
        try:
            self._publish(target)
        except Exception as exc:  # a closed session at exit, a transient transport error
            self.errors += 1
            if self.errors == 1 or self.errors % 100 == 0:
                log.warning("setpoint publish failed (%d so far): %s", self.errors, exc)
            return
        self.published += 1

    def _run(self) -> None:
        with self._cond:
            next_at = time.monotonic() + self.period
            while not self._closed:
                if self._target is None:
                    self._cond.wait()
                    next_at = time.monotonic() + self.period
                    continue
                now = time.monotonic()
                if self._set_at + self.period > now:  # a fresh set() just published
                    next_at = self._set_at + self.period
                if now < next_at:
                    self._cond.wait(next_at - now)
                    continue
                if self.idle_timeout is not None and now - self._set_at > self.idle_timeout:
                    log.warning(
                        "no new setpoint for %.1f s: stopped commanding (the bridge hovers)",
                        now - self._set_at,
                    )
                    self._target = None
                    continue
                self._send(self._target)
                next_at += self.period
                if next_at < now:  # stalled (GIL, suspended laptop): restart the schedule
                    next_at = now + self.period
