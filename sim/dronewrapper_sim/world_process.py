"""What every world process of the simulator does around its runner (the built-in autopilot's
:class:`~dronewrapper_sim.runner.SimRunner`, the world around an external autopilot, or the
simulated Tello's :class:`~dronewrapper_sim.tello.server.TelloServer`): make
it, announce it ready on the node, run it until the node stops, close it.
"""

from __future__ import annotations

import logging
from collections.abc import Callable
from typing import Any, Protocol, TypeVar

from dronewrapper.runtime.contract import NodeApi


class WorldRunner(Protocol):
    """A runner of the world: what it is, its loop until ``stop``, and its release."""

    def describe(self) -> str: ...

    def run(self, stop: Any) -> None: ...

    def close(self) -> None: ...


R = TypeVar("R", bound=WorldRunner)


def run_world(node: NodeApi, make: Callable[[], R], log: logging.Logger) -> R | None:
    """Make the runner (``make()``; an OSError, such as a port taken, is logged and gives
    None), announce it ready on ``node``, run it until the node stops, then stop the node and
    close the runner. The closed runner is returned for its figures."""
    try:
        runner = make()
    except OSError as exc:
        log.error("%s", exc)
        return None
    try:
        log.info("ready: %s", runner.describe())
        node.announce()
        runner.run(node.stop_event)
    finally:
        node.stop()
        runner.close()
    return runner
