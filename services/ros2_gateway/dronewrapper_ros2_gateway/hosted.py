"""The gateway hosted by the process that publishes the drone's telemetry (a bridge).

The gateway and the bridge run as two services of one process, each ``run(node, config)`` on a
node of its own over one Zenoh session (:mod:`dronewrapper.runtime.host`; in a graph, the
gateway's ``beside: bridge_mavlink``), so a pose reaches ROS 2 without a hop through another
process; neither imports the other. It is the same :class:`Gateway` as the standalone
process's, with two differences:

- our telemetry comes by direct callbacks on the session it shares with the bridge. Zenoh delivers a
  session's own put to such a callback synchronously, on the putting thread, once the sample has
  left for the router: each pose is converted and put on its ROS 2 key before the bridge's ``put``
  returns, with no thread or GIL hand-off and no second process. Cameras stay on Zenoh's callback
  threads (a frame's copy never holds up the bridge's loops);
- its commander name is ``commander``, else ``ros2_gateway``: never the bridge's identity.

Setpoints and service calls from ROS 2 take the standalone gateway's road: the gateway puts
them on the bus, the bridge takes them on its own setpoint subscription and service
queryables, with the gateway's commander name and send time, so the bridge's validation, command
lease and late-setpoint rule judge them as any commander's. The gateway holds only the node,
never the bridge.
"""

from __future__ import annotations

import contextlib
import logging
import threading
from collections.abc import Iterator

from dronewrapper.runtime.node import Node
from dronewrapper_ros2_gateway.config import Config
from dronewrapper_ros2_gateway.node import (
    DEFAULT_COMMANDER,
    Gateway,
    follow_demand_until_stopped,
    log_started,
    ros_session_for,
)

log = logging.getLogger("ros2_gateway")


def check_hosted(config: Config, ns: str) -> None:
    """Raise ValueError (naming the key) unless ``config`` fits a gateway hosted by the process
    of drone ``ns``: beside a bridge, the gateway presents that bridge's drone only."""
    if config.drones not in ([], [ns]):
        raise ValueError(
            f"drones: beside a bridge, the gateway presents its drone only ({ns!r}); "
            f"got {config.drones}"
        )


def run_hosted(node: Node, config: Config) -> int:
    """The gateway hosted beside the bridge until ``node`` stops; the exit status (2: a
    config :func:`check_hosted` refuses)."""
    try:
        check_hosted(config, node.ns)
    except ValueError as exc:
        log.error("bad config: %s", exc)
        return 2
    with hosted_gateway(node, config):
        node.announce()
        node.spin()
    return 0


@contextlib.contextmanager
def hosted_gateway(node: Node, config: Config | None) -> Iterator[Gateway | None]:
    """The gateway on ``node`` while the block runs; None, and nothing declared, when
    ``config`` is None. Raises ValueError for a config :func:`check_hosted` refuses."""
    if config is None:
        yield None
        return
    check_hosted(config, node.ns)
    session, own = ros_session_for(node, config)
    commander = config.commander or DEFAULT_COMMANDER
    gateway = Gateway(node, config, session, commander=commander, inline=True)
    done = threading.Event()
    watcher = node.clock.thread(lambda: follow_demand_until_stopped(gateway, done), "ros2-demand")
    try:
        gateway.start()
        watcher.start()
        log_started(gateway, "beside the bridge, in its process")
        yield gateway
    finally:
        done.set()
        if watcher.is_alive():
            watcher.join(timeout=2.0)
        gateway.close()
        if own:
            session.close()
