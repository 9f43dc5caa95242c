"""bridge_mavlink whose ``run`` raises once a trigger file appears: a bridge crashing inside a
process it shares with other drones (tests/integration/test_host_crash.py).

The bridge is the real one (its link, its threads, its node); only the end differs: instead of
waiting for a stop, ``run`` raises ``RuntimeError`` once the file named by the environment
variable ``DRONEWRAPPER_TEST_CRASH_FILE`` exists.
"""

from __future__ import annotations

import os
from pathlib import Path

from dronewrapper.runtime import Node
from dronewrapper.runtime.service import run_service
from dronewrapper_bridge_mavlink.config import Config
from dronewrapper_bridge_mavlink.flags import add_flags, as_overrides
from dronewrapper_bridge_mavlink.node import Bridge

TRIGGER_ENV = "DRONEWRAPPER_TEST_CRASH_FILE"


def run(node: Node, config: Config) -> int:
    """Start the bridge, announce it, raise once the trigger file exists."""
    trigger = Path(os.environ[TRIGGER_ENV])
    Bridge(node, config).start()
    node.announce()
    while not node.stop_event.wait(0.05):
        if trigger.exists():
            raise RuntimeError(f"injected crash ({trigger} exists)")
    return 0


def main(argv: list[str] | None = None) -> int:
    return run_service(
        "bridge_mavlink", __doc__, Config, run, argv, add_args=add_flags, configure=as_overrides
    )
