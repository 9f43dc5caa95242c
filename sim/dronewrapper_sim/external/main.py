"""``dronewrapper sim --autopilot px4-sih|ardupilot``: the world around an external autopilot."""

from __future__ import annotations

import logging
from typing import Any

from dronewrapper.runtime.contract import NodeApi
from dronewrapper_sim.world.scenario import Scenario

log = logging.getLogger("sim")


def run_external(node: NodeApi, config: Any, scenario: Scenario) -> int:
    """Run the world around ``config.autopilot`` on ``node`` until SIGINT/SIGTERM."""
    from dronewrapper_sim.external.world_runner import ExternalWorldRunner

    try:
        runner = ExternalWorldRunner(config, scenario, node)
    except OSError as exc:
        log.error("%s", exc)
        return 1
    try:
        log.info("ready: %s", runner.describe())
        node.announce()
        runner.run(node.stop_event)
    finally:
        node.stop()
        runner.close()
    log.info("stopped after %d truth samples", runner.truth_published)
    return 0
