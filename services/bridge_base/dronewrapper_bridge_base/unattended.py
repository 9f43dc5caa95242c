"""A long action left to the aircraft, and the commander that started it (pure; time injected, s).

A mission, a go-to or a return runs on the aircraft while its commander's program may do
anything else, or die. Such a program streams no setpoints, so the setpoint watchdog cannot
see it go; instead the request names the commander's process (``{ns}/alive/{name}``) and that
process beats about once a second (``{ns}/dronewrapper/commander/beat``, the SDK's
``dronewrapper.beat``); the bridge hands each beat to :meth:`Unattended.on_alive`.

The rule: the request counts as the first beat; once the watched key stays silent for
``lost_timeout`` s, the commander is lost; when the action has also ended (the go-to reached
its point, the mission's last item is done, or the aircraft holds), the bridge takes
``action`` once:
``return`` (fly home and land) or ``land`` (here). A return in progress is left to finish.
A request that names no key is not watched: the action then stays the autopilot's. A new
action, a setpoint stream taking over, or a disarm ends the watch.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

ACTIONS = ("return", "land")


@dataclass(frozen=True)
class UnattendedConfig:
    """``lost_timeout``: s the watched key may be absent; ``action``: ``return`` or ``land``."""

    lost_timeout: float = 5.0
    action: str = "return"

    def __post_init__(self) -> None:
        if self.action not in ACTIONS:
            raise ValueError(
                f"unattended_action must be one of {', '.join(ACTIONS)}, got {self.action!r}"
            )
        if not (math.isfinite(self.lost_timeout) and 0 < self.lost_timeout <= 600):
            raise ValueError(
                f"unattended_lost_timeout must be in (0, 600] s, got {self.lost_timeout!r}"
            )


class Unattended:
    """The watched action (see module docstring)."""

    def __init__(self, config: UnattendedConfig = UnattendedConfig()) -> None:
        self.config = config
        self.what = ""  # "mission", "goto", "return"; "" none
        self.key = ""
        self.seen = False
        self.finished = False
        self.acted = False
        self._last_seen = -math.inf

    @property
    def watching(self) -> str:
        """The key to look for now ("" when nothing is watched)."""
        return self.key if self.what and not self.acted else ""

    def start(self, what: str, key: str, now: float) -> None:
        """``what`` began for the commander whose process holds ``key`` ("" none)."""
        self.what, self.key = (what, key) if key else ("", "")
        self.seen = bool(key)  # the request is its commander's first beat
        self.finished = self.acted = False
        self._last_seen = now

    def ended(self, now: float) -> None:
        """The action has done what it was asked (the aircraft now holds)."""
        self.finished = True

    def clear(self) -> None:
        """Nothing is watched any more (another action or commander, a disarm)."""
        self.what = self.key = ""

    def on_alive(self, keys: set[str], now: float) -> None:
        """The keys of the commanders that beat now."""
        if self.key and self.key in keys:
            self.seen, self._last_seen = True, now

    def lost(self, now: float) -> bool:
        """The watched commander has been gone for ``lost_timeout`` s."""
        return bool(self.what) and self.seen and now - self._last_seen > self.config.lost_timeout

    def tick(self, now: float, *, holding: bool) -> str:
        """The action to take now ("" none): once, when the commander is lost and the action
        has ended (``holding``: the aircraft holds on its own, e.g. a finished mission)."""
        if self.acted or self.what in ("", "return") or not self.lost(now):
            return ""
        if not (self.finished or holding):
            return ""
        self.acted = True
        return self.config.action

    def reason(self, now: float) -> str:
        """Why :meth:`tick` acted, for the log and the commander."""
        gone = now - self._last_seen
        return (
            f"the commander of the {self.what} ({self.key}) has been gone for {gone:.1f} s and "
            f"the {self.what} has ended: {self.config.action}"
        )
