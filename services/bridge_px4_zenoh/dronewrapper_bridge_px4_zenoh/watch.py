"""The unattended-action rule on the PX4 Zenoh bridge's core (pure): a go-to or return whose
commander's process disappeared ends as for a lost commander once the action has ended
(:mod:`~dronewrapper_bridge_base.unattended`, the rule bridge_mavlink keeps too).

A go-to or return request names its commander's process (``watch``: ``{ns}/alive/{name}``);
:func:`start` begins the watch; the core (its
:class:`~dronewrapper_bridge_base.guided_core.GuidedCore` part) hears each commander's beat and
each change of PX4's mode or arming, and calls :func:`tick` each stream tick. When the go-to
has ended (reached, timed out or cancelled: the bridge then holds there in OFFBOARD) and its
commander has been silent for ``unattended_lost_timeout`` s, the bridge asks PX4 for
``unattended_action`` (``return``: RTL, or ``land``) once. A return is left to finish; a
setpoint (a commander steering), a new action or a disarm ends the watch.
"""

from __future__ import annotations

import logging
from collections.abc import Callable
from typing import Protocol

from dronewrapper_bridge_base.core_view import Clock
from dronewrapper_bridge_base.unattended import Unattended
from dronewrapper_bridge_px4_zenoh import operations as ops


class WatchPort(ops.Heard, Clock, Protocol):
    """What the watch uses of the core besides its time and PX4's mode as heard: the
    unattended rule and its tick."""

    unattended: Unattended

    def unattended_tick(self, holding: Callable[[], bool]) -> None: ...


log = logging.getLogger("bridge_px4_zenoh")


def start(core: WatchPort, what: str, key: str) -> None:
    """The ``what`` ("goto", "return") started now is watched for its commander's ``key``."""
    core.unattended.start(what, key, core.now)
    log.info("%s: its commander's process %s", what, f"is {key}" if key else "is not known")


def tick(core: WatchPort) -> None:
    """Take the unattended action when its time has come (once): PX4's return or landing,
    the bridge's hold let go."""
    core.unattended_tick(lambda: ops.shown_mode(core) == ops.HOLD_MODE)
