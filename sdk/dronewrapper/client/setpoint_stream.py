"""The setpoint stream's rules, in injected time: one core for the SDK and the services.

The failsafe contract (docs/design.md): a commander re-publishes its latest setpoint at >= 20 Hz
until it is changed or stopped; if the stream stops, the bridge holds position after its
``setpoint_timeout`` and lands after ``commander_lost_timeout``.

:class:`SetpointStream` holds those rules and nothing else (no thread, no bus): :meth:`set`
publishes a new setpoint at once, :meth:`poll` repeats it when due, :meth:`next_due` says when.
``header.stamp`` keeps the stamp given with the command (the source frame's capture time),
``header.seq`` counts every publication. A :class:`~dronewrapper.client.DroneClient` drives it
(:class:`~dronewrapper.client.stream.SetpointStreamer`) from its own thread in the SDK, or from a
service's loop; both on their node's clock.

Link gaps: :meth:`SetpointStream.link` hears the publisher's matching status. While the bridge's
subscriber is unreachable (after it was reachable once: a router restart, lost Wi-Fi) nothing is
published; when it is back, a command older than ``expiry`` (the bridge's setpoint expiry) is
dropped, never resent: the stream stops and the commander must command again. A stale 1 m/s,
repeated into the void during the gap, would otherwise make a hovering drone fly off the moment
the link returned.

Times are seconds on the driver's monotonic clock.
"""

from __future__ import annotations

import logging
import math
from collections.abc import Callable

import msgspec

from dronewrapper.msgs.mavros import PositionTarget

log = logging.getLogger("dronewrapper.setpoints")

MIN_RATE_HZ = 20.0
"""The contract's lowest setpoint rate (Hz)."""
DEFAULT_EXPIRY_S = 0.5
"""The bridges' default setpoint expiry (s): a command older than this after a gap is stale."""


class SetpointStream:
    """The latest setpoint, repeated every ``1 / rate_hz`` s until changed or stopped.

    Args:
        publish: sends one PositionTarget (may raise: counted in ``errors``, never fatal).
        rate_hz: repetition rate, at least 20 Hz.
        idle_timeout: if not None, stop when no new setpoint was given for this many seconds
            (the bridge then hovers): a deadman for a commander that may hang.
        expiry: seconds after which a command is stale once the link was down meanwhile.
    """

    def __init__(
        self,
        publish: Callable[[PositionTarget], None],
        *,
        rate_hz: float = 30.0,
        idle_timeout: float | None = None,
        expiry: float = DEFAULT_EXPIRY_S,
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
        self.published = 0
        self.errors = 0
        self.withheld = 0
        """Publications skipped while the link was down."""
        self.dropped_after_gap = 0
        """Commands not resent because they were stale after a gap."""
        self._publish = publish
        self._target: PositionTarget | None = None
        self._set_at = -math.inf
        self._next_due = math.inf
        self._matched_once = False

    @property
    def target(self) -> PositionTarget | None:
        """The setpoint being streamed, or None."""
        return self._target

    def set(self, target: PositionTarget, now: float) -> None:
        """Publish ``target`` now and repeat it from :meth:`poll` until changed or stopped."""
        self._target = target
        self._set_at = now
        self._send(target)
        self._next_due = now + self.period

    def stop(self) -> None:
        """Stop streaming: nothing more until the next :meth:`set`."""
        self._target = None
        self._next_due = math.inf

    def next_due(self) -> float:
        """When :meth:`poll` has work next (inf when not streaming)."""
        return self._next_due

    def poll(self, now: float) -> bool:
        """Repeat the setpoint if due (or end it at the idle timeout); True if it published."""
        if self._target is None or now < self._next_due:
            return False
        if self.idle_timeout is not None and now - self._set_at > self.idle_timeout:
            log.warning(
                "no new setpoint for %.1f s: stopped commanding (the bridge hovers)",
                now - self._set_at,
            )
            self.stop()
            return False
        self._send(self._target)
        self._next_due += self.period
        if self._next_due <= now:  # stalled (GIL, suspended laptop): restart, never burst
            self._next_due = now + self.period
        return True

    def link(self, matching: bool, now: float) -> None:
        """The bridge's setpoint subscriber became (un)reachable (the publisher's matching
        status). Unreachable counts only once it was reachable."""
        if matching:
            self._matched_once = True
            self.link_up(now)
        elif self._matched_once:
            self.link_down()

    def link_down(self) -> None:
        """The bridge is unreachable: publish nothing until :meth:`link_up`."""
        if self.link_ok:
            log.warning("link to the bridge lost: setpoints withheld until it returns")
        self.link_ok = False

    def link_up(self, now: float) -> None:
        """The bridge is reachable again: resume, unless the command is older than
        ``expiry``, which is then dropped."""
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
            self.stop()
            self.dropped_after_gap += 1
        # Last: a reader that sees the link up (without a lock) sees the stale command gone.
        self.link_ok = True

    def _send(self, target: PositionTarget) -> None:
        if not self.link_ok:
            self.withheld += 1
            return
        header = msgspec.structs.replace(target.header, seq=self.published)
        try:
            self._publish(msgspec.structs.replace(target, header=header))
        except Exception as exc:  # a closed session at exit, a transient transport error
            self.errors += 1
            if self.errors == 1 or self.errors % 100 == 0:
                log.warning("setpoint publish failed (%d so far): %s", self.errors, exc)
            return
        self.published += 1
