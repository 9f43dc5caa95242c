"""The gateway under the security setup: the drone's graph secured (compose/sim_iris_secure.yaml:
TLS listener with the registry's access control, the command lease), the gateway with its own
operator certificate on that router, and the ROS 2 graph on its own router (``ros_connect``),
where a ROS 2 peer sharing no code with the project (zenoh-ros2-sdk) arms and disarms the drone:
the bridge sees the gateway's identity as the commander."""

from __future__ import annotations

import socket

import pytest
from key_store import issued_store
from ros2_peer import ros2_peer

from support import free_endpoint, free_port, python_module, wait_for, zenoh_router

pytestmark = pytest.mark.integration


def test_gateway_commands_with_its_own_identity(spawn, tmp_path, monkeypatch):
    from zenoh_ros2_sdk import ROS2ServiceClient

    store = issued_store(tmp_path / "keys", {"drone1": "drone", "ros2-gw": "operator"})
    monkeypatch.setenv("DRONEWRAPPER_KEYS", str(store.root))
    tls = f"tls/127.0.0.1:{free_port()}"
    graph = spawn(
        python_module(
            "dronewrapper", "up", "compose/sim_iris_secure.yaml", "--router", free_endpoint(),
            "--listen", tls, "--identity", "drone1",
            "--var", f"onboard_port={free_port(socket.SOCK_DGRAM)}",
            "--var", f"gcs_port={free_port(socket.SOCK_DGRAM)}",
        ),
        "secure_graph",
    )  # fmt: skip
    with zenoh_router() as ros_router:
        wait_for(
            lambda: "all processes ready" in graph.output() or not graph.alive(), 90, what="graph"
        )
        assert graph.alive(), graph.output()[-3000:]
        gateway = spawn(
            python_module(
                "dronewrapper", "ros2", "--connect", tls, "--mode", "client",
                "--identity", "ros2-gw", "--set", f"ros_connect=[{ros_router}]",
            ),
            "gateway",
        )  # fmt: skip
        host, port = ros_router.split("/", 1)[1].rsplit(":", 1)
        with ros2_peer(host, int(port)):
            arming = ROS2ServiceClient(
                "/drone/mavros/cmd/arming", "mavros_msgs/srv/CommandBool",
                router_ip=host, router_port=int(port), timeout=10,
            )  # fmt: skip

            def armed() -> bool:
                assert gateway.alive(), gateway.output()[-3000:]
                reply = arming.call(value=True)
                return reply is not None and reply.success

            wait_for(armed, 60, interval=0.5, what="arming through the gateway")
            reply = arming.call(value=False)
            assert reply is not None and reply.success
            arming.close()
        gateway.stop()
    graph.stop()
    assert "command lease acquired: ros2-gw" in graph.output()
