"""The gateway hosted by the bridge, seen by a ROS 2 peer that shares no code with the project
(zenoh-ros2-sdk): compose/sim_iris_ros2_hosted.yaml (sim, bridge with the command lease, and
the gateway beside it in the bridge's process) on a real router on loopback. The peer discovers the
entities, echoes a State and arms and disarms the drone through the bridge's lease, under the
gateway's commander name; and on the same router, a hosted gateway's conversion of a pose is
done on the putting thread before ``put`` returns."""

from __future__ import annotations

import socket

import pytest
from ros2_peer import ros2_peer

from dronewrapper.msgs import registry
from dronewrapper.msgs.geometry import PoseStamped
from dronewrapper_ros2_gateway.config import Config
from dronewrapper_ros2_gateway.hosted import hosted_gateway
from support import client_node, free_endpoint, free_port, python_module, wait_for

pytestmark = pytest.mark.integration

NS = "drone"


def test_a_ros2_peer_sees_and_commands_the_bridge_hosted_gateway(spawn):
    from zenoh_ros2_sdk import (
        ROS2ServiceClient,
        ROS2Subscriber,
        get_topic_names_and_types,
    )

    router = free_endpoint()
    graph = spawn(
        python_module(
            "dronewrapper", "up", "compose/sim_iris_ros2_hosted.yaml", "--router", router,
            "--ns", NS,
            "--var", f"onboard_port={free_port(socket.SOCK_DGRAM)}",
            "--var", f"gcs_port={free_port(socket.SOCK_DGRAM)}",
        ),
        "hosted_graph",
    )  # fmt: skip
    wait_for(lambda: "all processes ready" in graph.output() or not graph.alive(), 90, what="up")
    assert graph.alive(), graph.output()[-3000:]
    host, port = router.split("/", 1)[1].rsplit(":", 1)
    with ros2_peer(host, int(port)):

        def discovered() -> bool:
            topics = dict(get_topic_names_and_types(router_ip=host, router_port=int(port)))
            return topics.get(f"/{NS}/mavros/state") == ["mavros_msgs/msg/State"]

        wait_for(discovered, 10, interval=0.3, what="the bridge's ROS 2 entities")
        states: list = []
        sub = ROS2Subscriber(
            f"/{NS}/mavros/state", "mavros_msgs/msg/State",
            lambda msg: msg.connected and states.append(msg),
            router_ip=host, router_port=int(port),
        )  # fmt: skip
        wait_for(lambda: states, 20, what="a connected State from the bridge's own process")
        sub.close()
        arming = ROS2ServiceClient(
            f"/{NS}/mavros/cmd/arming", "mavros_msgs/srv/CommandBool",
            router_ip=host, router_port=int(port), timeout=20,
        )  # fmt: skip
        try:
            reply = arming.call(value=True)
            assert reply is not None and reply.success, reply
            reply = arming.call(value=False)
            assert reply is not None and reply.success, reply
        finally:
            arming.close()
    wait_for(lambda: "command lease acquired: ros2_gateway" in graph.output(), 10, what="lease")
    output = graph.output()  # one process, the gateway a service of its own in it, hosted
    assert "bridge_mavlink+ros2_gateway |" in output
    assert "beside the bridge, in its process" in output

    # the hosted conversion runs inside put(): on a real session, no thread in between
    with (
        client_node(router, "host", "drone_t", mode="client") as node,
        hosted_gateway(node, Config(keys=["mavros/local_position/pose"])) as gateway,
    ):
        ((_, _, out),) = gateway.outgoing
        pose = node.publisher(registry.LOCAL_POSE)
        for count in range(1, 4):
            pose.put(PoseStamped())
            assert out.count == count
    graph.stop()
