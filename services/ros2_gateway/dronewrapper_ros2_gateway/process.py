"""The gateway's ``run(node, config)``: a process of its own, or beside other services in one.

Started alone (``python -m dronewrapper_ros2_gateway``, ``dronewrapper ros2``), it is
:func:`dronewrapper_ros2_gateway.node.run`. Started as a member of a process that hosts several
services on one Zenoh session (:mod:`dronewrapper.runtime.host`: a graph's ``beside:``, such as
``compose/sim_iris_ros2_hosted.yaml``, which puts it in the bridge's process), it is
:func:`dronewrapper_ros2_gateway.hosted.run_hosted`: the bridge's puts reach it on the putting
thread, with no second process and no thread hand-off.
"""

from __future__ import annotations

from dronewrapper.runtime import host
from dronewrapper.runtime.node import Node
from dronewrapper_ros2_gateway import hosted, node
from dronewrapper_ros2_gateway.config import Config


def run(process_node: Node, config: Config) -> int:
    """The gateway on ``process_node`` until it stops; the exit status."""
    if host.current() is None:
        return node.run(process_node, config)
    return hosted.run_hosted(process_node, config)
