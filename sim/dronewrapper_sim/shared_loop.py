"""A simulated Iris on its host's shared loop (:mod:`dronewrapper.runtime.poller`).

Hosted with other members, a :class:`~dronewrapper_sim.runner.SimRunner` needs no thread of
its own: its physics loop is a deadline of the host's one loop thread (the next wake-up, on
the ``loop_rate_hz`` grid every sim of the host shares, so they step and send together) and
each of its MAVLink links a socket the same thread reads when a datagram waits (the autopilot
answers at once, as on a thread of its own). An exception out of its steps or its links ends
this sim alone: its node stops and :func:`run_on_poller` raises it on the member's thread.
"""

from __future__ import annotations

import math
import threading
from collections.abc import Mapping
from typing import Protocol

from dronewrapper.runtime.clock import Clock
from dronewrapper.runtime.poller import NO_FILE, Poller
from dronewrapper_sim.mavlink_io import MavlinkUdpLink


class SimRunner(Protocol):
    """What the loop needs of a :class:`dronewrapper_sim.runner.SimRunner`."""

    @property
    def links(self) -> Mapping[str, MavlinkUdpLink]: ...

    @property
    def time(self) -> Clock: ...

    def begin(self) -> None: ...

    def next_wake(self) -> float: ...

    def wake(self, now: float) -> float: ...

    def receive(self, link: MavlinkUdpLink) -> None: ...


WAIT_S = 1.0
"""How often the member's own thread looks for a stop while the loop runs it (s)."""


class _Steps:
    """The physics loop as a deadline."""

    def __init__(self, runner: SimRunner) -> None:
        self.runner = runner

    def fileno(self) -> int:
        return NO_FILE

    def on_readable(self) -> None:
        """Never called: no socket."""
        return None

    def on_due(self, now: float) -> float:
        return self.runner.wake(now)


class _Link:
    """One MAVLink link's socket, read when readable."""

    def __init__(self, runner: SimRunner, link: MavlinkUdpLink) -> None:
        self.runner = runner
        self.link = link

    def fileno(self) -> int:
        return self.link.fileno()

    def on_readable(self) -> None:
        self.runner.receive(self.link)
        return None

    def on_due(self, now: float) -> float:
        return math.inf


def run_on_poller(runner: SimRunner, poller: Poller, stop: threading.Event) -> None:
    """Run ``runner`` on ``poller`` until ``stop`` is set (the calling thread waits).

    Raises:
        Exception: what failed the runner on the loop (its node stopped meanwhile).
    """
    failures: list[BaseException] = []
    runner.begin()
    poller.add(_Steps(runner), stop, failures.append, due=runner.next_wake())
    for link in runner.links.values():
        poller.add(_Link(runner, link), stop, failures.append, due=math.inf)
    while not runner.time.wait(stop, WAIT_S):
        pass
    if failures:
        raise failures[0]
