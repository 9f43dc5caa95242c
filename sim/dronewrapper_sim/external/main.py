"""``dronewrapper sim --autopilot px4-sih|ardupilot``: the world around an external autopilot."""

from __future__ import annotations

import logging
from typing import Any

from dronewrapper.runtime.contract import NodeApi
from dronewrapper_sim.world.scenario import Scenario
from dronewrapper_sim.world_process import run_world

log = logging.getLogger("sim")


def run_external(node: NodeApi, config: Any, scenario: Scenario) -> int:
    """Run the world around ``config.autopilot`` on ``node`` until SIGINT/SIGTERM."""
    from dronewrapper_sim.external.world_runner import ExternalWorldRunner

    runner = run_world(node, lambda: ExternalWorldRunner(config, scenario, node), log)
    if runner is None:
        return 1
    log.info("stopped after %d truth samples", runner.truth_published)
    return 0
