"""When the Tello's video should stream, and which command switches it now (pure, time injected).

The config's ``video`` mode decides what is wanted:

- ``on``: stream whenever the Tello is in SDK mode;
- ``off``: never touch the stream (no command is sent, the video socket stays closed);
- ``on_demand``: stream while a subscriber matches the camera's keys (``image_raw`` or its
  ``compressed`` form), and for ``idle_s`` seconds after the last one has gone, so a viewer that
  leaves and comes back within that time finds the stream still running.

What the Tello does is known only from its replies: ``streaming`` is None (unknown) at every
connection, since a Tello left streaming by an earlier client keeps streaming, so the first
decision sends the wanted command (``streamoff`` too, when nobody watches). A refused or
unanswered command is tried again ``retry_s`` later, at most ``attempts`` times in a row; then
:class:`VideoDemand` gives up until the demand changes or the Tello reconnects. It asks for one
command at a time and only when the caller says the Tello's command slot is free, so the video
never queues ahead of a flight command.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

ON, OFF, ON_DEMAND = "on", "off", "on_demand"
MODES = (ON, OFF, ON_DEMAND)
STREAMON, STREAMOFF = "streamon", "streamoff"


@dataclass(frozen=True)
class VideoPolicy:
    """How the video follows its demand.

    Attributes:
        mode: ``on``, ``off`` or ``on_demand``.
        idle_s: s the stream runs on after the last subscriber has gone (``on_demand``).
        retry_s: s between tries of a refused or unanswered ``streamon``/``streamoff``.
        attempts: tries in a row before giving up until the demand changes or the Tello
            reconnects.
    """

    mode: str = ON
    idle_s: float = 10.0
    retry_s: float = 2.0
    attempts: int = 3

    def __post_init__(self) -> None:
        if self.mode not in MODES:
            raise ValueError(f"video must be one of {', '.join(MODES)}, got {self.mode!r}")
        if not (math.isfinite(self.idle_s) and 0.0 <= self.idle_s <= 3600.0):
            raise ValueError(f"video_idle_s must be in [0, 3600] s, got {self.idle_s!r}")
        if not (math.isfinite(self.retry_s) and 0.1 <= self.retry_s <= 60.0):
            raise ValueError(f"video_retry_s must be in [0.1, 60] s, got {self.retry_s!r}")
        if not 1 <= self.attempts <= 100:
            raise ValueError(f"video_attempts must be in [1, 100], got {self.attempts!r}")


class VideoDemand:
    """The stream's wanted and known state, and the next command to reach the wanted one.

    Attributes:
        streaming: the stream as the Tello last confirmed it (None: unknown).
        in_flight: the command sent and not yet answered (None: none).
        failures: refused or unanswered tries in a row of the current command.
        gave_up: ``attempts`` tries failed; nothing more until the demand changes or the Tello
            reconnects.
    """

    def __init__(self, policy: VideoPolicy) -> None:
        self.policy = policy
        self.streaming: bool | None = None
        self.in_flight: str | None = None
        self.failures = 0
        self.gave_up = False
        self._watched_at = -math.inf  # monotonic s when a subscriber was last seen
        self._retry_at = -math.inf
        self._wanted: bool | None = None

    def wanted(self, now: float) -> bool | None:
        """Whether the stream should run at ``now`` (None: the mode leaves it alone)."""
        if self.policy.mode == OFF:
            return None
        if self.policy.mode == ON:
            return True
        return now - self._watched_at < self.policy.idle_s

    def next_command(
        self, now: float, *, watched: bool, connected: bool, slot_free: bool
    ) -> str | None:
        """The command to send now (``streamon``/``streamoff``), or None.

        Args:
            now: monotonic s.
            watched: a subscriber matches the camera's keys now.
            connected: the Tello is connected and in SDK mode.
            slot_free: no other command is waiting for the Tello's reply.
        """
        if watched:
            self._watched_at = now
        if not connected:
            self._forget()
            return None
        wanted = self.wanted(now)
        if wanted != self._wanted:  # a new demand gets its own tries
            self._wanted, self.failures, self.gave_up = wanted, 0, False
            self._retry_at = -math.inf
        if (
            wanted is None
            or wanted == self.streaming
            or self.gave_up
            or self.in_flight is not None
            or not slot_free
            or now < self._retry_at
        ):
            return None
        self.in_flight = STREAMON if wanted else STREAMOFF
        return self.in_flight

    def on_result(self, command: str, accepted: bool, now: float) -> None:
        """The Tello's answer to ``command``: ``accepted`` (``ok``), else refused or silent."""
        if command != self.in_flight:
            return  # an answer from before a reconnection
        self.in_flight = None
        if accepted:
            self.streaming = command == STREAMON
            self.failures = 0
            return
        self.failures += 1
        self._retry_at = now + self.policy.retry_s
        if self.failures >= self.policy.attempts:
            self.gave_up = True

    def _forget(self) -> None:
        """The link is down: what the Tello streams is unknown again (it may have restarted)."""
        self.streaming, self.in_flight = None, None
        self.failures, self.gave_up, self._wanted = 0, False, None
        self._retry_at = -math.inf
