"""A minimal service built on the common entry point, for launcher and runtime tests.

It publishes a ControllerStatus at 20 Hz, serves ARMING (refusing disarm), and can be told to
die, to never become ready, to ignore SIGINT, or to take a while to stop (like a controller
landing on exit).
"""

from __future__ import annotations

import signal
import time

import msgspec

from dronewrapper.msgs import CommandBool, CommandBoolResult, ControllerStatus, Header, registry
from dronewrapper.runtime import Node, Ratekeeper, ServiceError
from dronewrapper.runtime.service import run_service


class ToyConfig(msgspec.Struct, forbid_unknown_fields=True, kw_only=True):
    rate_hz: float = 20.0
    announce: bool = True
    die_after_s: float = 0.0
    exit_code: int = 3
    ignore_sigint: bool = False
    stop_delay_s: float = 0.0


def run(node: Node, config: ToyConfig) -> int:
    if config.ignore_sigint:
        signal.signal(signal.SIGINT, signal.SIG_IGN)
    status = node.publisher(registry.CONTROLLER_STATUS)

    def arm(req: CommandBool) -> CommandBoolResult:
        if not req.value:
            raise ServiceError("toy refuses to disarm")
        return CommandBoolResult(success=True, result=0)

    node.serve(registry.ARMING, arm)
    if config.announce:
        node.announce()
    node.log.info("toy up")
    started = time.monotonic()
    rate = Ratekeeper(config.rate_hz, stop=node.stop_event)
    while rate.sleep():
        status.put(ControllerStatus(header=Header.now(), mode="toy", state="tracking"))
        if config.die_after_s and time.monotonic() - started > config.die_after_s:
            node.log.error("toy dying on purpose")
            return config.exit_code
    if config.stop_delay_s:
        node.log.info("toy stopping slowly")
        time.sleep(config.stop_delay_s)
    node.log.info("toy stopped")
    return 0


if __name__ == "__main__":
    raise SystemExit(run_service("toy", __doc__, ToyConfig, run))
