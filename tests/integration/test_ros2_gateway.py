"""A ROS 2 peer that shares no code with the project (zenoh-ros2-sdk, with the upstream
interface text of tests/data/ros2_interfaces) sees and flies the simulated Iris through the
gateway: compose/sim_iris_ros2.yaml (sim, bridge with the command lease, gateway) on a real
router on loopback.

One graph for the module; the tests run in order: discovery, echo, refusals (garbage, no
lease), parameters, then the flight (arming, takeoff, a PositionTarget that moves the aircraft
in ground truth, land).
"""

from __future__ import annotations

import math
import socket
import threading
import time

import pytest
from ros2_peer import ros2_peer

from dronewrapper.msgs import registry
from dronewrapper.msgs.geometry import PoseStamped
from dronewrapper.msgs.lease import LeaseRequest
from dronewrapper.msgs.mavros import PositionTarget
from dronewrapper.runtime.caller import commander_attachment
from support import Process, client_node, free_endpoint, free_port, python_module, wait_for

pytestmark = pytest.mark.integration

NS = "drone"
STATE = f"/{NS}/mavros/state"
POSE = f"/{NS}/mavros/local_position/pose"
SETPOINT = f"/{NS}/mavros/setpoint_raw/local"


@pytest.fixture(scope="module")
def graph(tmp_path_factory):
    """(router endpoint, a client node on it, the graph's process), once the bridge and the
    gateway are alive."""
    router = free_endpoint()
    log = tmp_path_factory.mktemp("ros2") / "sim_iris_ros2.log"
    argv = python_module(
        "dronewrapper",
        "up",
        "compose/sim_iris_ros2.yaml",
        "--router",
        router,
        "--ns",
        NS,
        "--var",
        f"onboard_port={free_port(socket.SOCK_DGRAM)}",
        "--var",
        f"gcs_port={free_port(socket.SOCK_DGRAM)}",
    )
    proc = Process(argv, log)
    try:
        with client_node(router, "ros2_test", NS, mode="client", open_timeout=60) as node:

            def ready() -> bool:
                assert proc.alive(), proc.output()[-4000:]
                alive = node.alive_services(NS)
                return {f"{NS}/alive/bridge_mavlink", f"{NS}/alive/ros2_gateway"} <= alive

            wait_for(ready, 60, interval=0.3, what="bridge and gateway alive")
            yield router, node, proc
    finally:
        proc.stop(30)


@pytest.fixture(scope="module")
def ros(graph):
    """zenoh-ros2-sdk's session on the graph's router (host, port), closed at the end."""
    host, port = graph[0].split("/", 1)[1].rsplit(":", 1)
    with ros2_peer(host, int(port)):
        yield host, int(port)


def test_peer_discovers_topics_and_services_by_liveliness(ros):
    from zenoh_ros2_sdk import get_service_names_and_types, get_topic_names_and_types

    host, port = ros

    def found() -> bool:
        topics = dict(get_topic_names_and_types(router_ip=host, router_port=port, timeout=1.0))
        services = dict(get_service_names_and_types(router_ip=host, router_port=port, timeout=1.0))
        return (
            topics.get(STATE) == ["mavros_msgs/msg/State"]
            and topics.get(POSE) == ["geometry_msgs/msg/PoseStamped"]
            and topics.get(SETPOINT) == ["mavros_msgs/msg/PositionTarget"]
            and services.get(f"/{NS}/mavros/cmd/arming") == ["mavros_msgs/srv/CommandBool"]
        )

    wait_for(found, 10, interval=0.3, what="the gateway's entities in the ROS 2 graph")


def _first(ros, topic: str, msg_type: str, timeout: float = 10.0, where=lambda msg: True):
    """The first message on ``topic`` for which ``where`` holds."""
    from zenoh_ros2_sdk import ROS2Subscriber

    got: list = []
    sub = ROS2Subscriber(
        topic, msg_type, lambda msg: where(msg) and got.append(msg),
        router_ip=ros[0], router_port=ros[1],
    )  # fmt: skip
    try:
        return wait_for(lambda: got[:1], timeout, what=f"a message on {topic}")[0]
    finally:
        sub.close()


def test_peer_echoes_state_pose_and_an_image(ros):
    # the bridge says connected once the autopilot's first heartbeat is in: wait for that State
    state = _first(ros, STATE, "mavros_msgs/msg/State", 20.0, where=lambda s: s.connected)
    assert state.connected and state.mode
    pose = _first(ros, POSE, "geometry_msgs/msg/PoseStamped")
    assert pose.header.frame_id == "map" and abs(pose.header.stamp.sec - time.time()) < 30
    image = _first(ros, f"/{NS}/cam_frontal/image_raw", "sensor_msgs/msg/Image", 20.0)
    assert image.width > 0 and image.height > 0 and image.encoding == "bgr8"
    assert len(image.data) == image.step * image.height == image.width * image.height * 3


def _client(ros, name: str, srv: str, timeout: float = 20.0):
    from zenoh_ros2_sdk import ROS2ServiceClient

    return ROS2ServiceClient(
        f"/{NS}/mavros/{name}",
        f"mavros_msgs/srv/{srv}",
        router_ip=ros[0],
        router_port=ros[1],
        timeout=timeout,
    )


def _target(vx: float) -> dict:
    """The fields of a body-velocity mavros_msgs/PositionTarget, as zenoh-ros2-sdk's classes."""
    from zenoh_ros2_sdk import ZenohSession

    types = ZenohSession.get_instance().store.types
    vector = types["geometry_msgs/msg/Vector3"]
    now = time.time()
    stamp = types["builtin_interfaces/msg/Time"](sec=int(now), nanosec=int(now % 1 * 1e9))
    return {
        "header": types["std_msgs/msg/Header"](stamp=stamp, frame_id="base_link"),
        "coordinate_frame": 8,
        "type_mask": 1991,
        "position": types["geometry_msgs/msg/Point"](x=0.0, y=0.0, z=0.0),
        "velocity": vector(x=vx, y=0.0, z=0.0),
        "acceleration_or_force": vector(x=0.0, y=0.0, z=0.0),
        "yaw": 0.0,
        "yaw_rate": 0.0,
    }


def _setpoints_seen(node):
    seen: list[PositionTarget] = []
    node.subscribe(registry.SETPOINT_RAW_LOCAL, seen.append)
    return seen


def test_garbage_and_commands_without_the_lease_are_refused(ros, graph):
    from zenoh_ros2_sdk import ROS2Publisher

    _router, node, _proc = graph
    seen = _setpoints_seen(node)
    time.sleep(0.5)
    # garbage bytes with a valid attachment on the exact ROS 2 key: nothing reaches the bridge
    from dronewrapper_ros2_codec import attachment
    from dronewrapper_ros2_codec.names import topic_key
    from dronewrapper_ros2_codec.typehash import type_hash

    key = topic_key(
        0, SETPOINT, "mavros_msgs/msg/PositionTarget", type_hash("mavros_msgs/msg/PositionTarget")
    )
    raw = node.session.declare_publisher(key)
    pub = ROS2Publisher(
        SETPOINT, "mavros_msgs/msg/PositionTarget", router_ip=ros[0], router_port=ros[1]
    )
    try:
        for i in range(5):
            raw.put(b"\x00\x01\x00\x00garbage", attachment=attachment.pack(i, 0, bytes(16)))
            pub.publish(**_target(math.nan))  # NaN: refused
            time.sleep(0.05)
        time.sleep(0.5)
        assert seen == []
    finally:
        raw.undeclare()
        pub.close()
    # garbage as a service request: answered, refused
    from dronewrapper_ros2_codec import cdr

    arming_key = topic_key(
        0,
        f"/{NS}/mavros/cmd/arming",
        "mavros_msgs/srv/CommandBool",
        type_hash("mavros_msgs/srv/CommandBool"),
    )
    replies = list(
        node.session.get(
            arming_key,
            payload=b"\x07garbage",
            timeout=10,
            attachment=attachment.pack(1, 0, bytes(16)),
        )
    )
    assert len(replies) == 1 and replies[0].ok is not None
    answer = cdr.decode("mavros_msgs/srv/CommandBool_Response", replies[0].ok.payload.to_bytes())
    assert answer == {"success": False, "result": 2}
    assert attachment.unpack(replies[0].ok.attachment.to_bytes()).sequence == 1
    arming = _client(ros, "cmd/arming", "CommandBool")
    # someone else holds the command lease: the ROS 2 node's command is refused, not obeyed
    alice = commander_attachment("alice")
    lease = node.call(registry.COMMAND_LEASE, LeaseRequest(action="take"), attachment=alice)
    assert lease.granted
    try:
        reply = arming.call(value=True)
        assert reply is not None and not reply.success and reply.result == 2  # DENIED
    finally:
        node.call(registry.COMMAND_LEASE, LeaseRequest(action="release"), attachment=alice)
        arming.close()


def test_peer_reads_and_writes_a_parameter(ros):
    from zenoh_ros2_sdk import ROS2ServiceClient, ZenohSession

    # zenoh-ros2-sdk 0.1.8 resolves the upstream file's unqualified ``ParamValue`` to
    # mavros_msgs/srv/msg/ParamValue: give it the same definition with the name qualified
    get = ROS2ServiceClient(
        f"/{NS}/mavros/param/get", "mavros_msgs/srv/ParamGet",
        request_definition="string param_id\n",
        response_definition="bool success\nmavros_msgs/ParamValue value\n",
        router_ip=ros[0], router_port=ros[1], timeout=20,
    )  # fmt: skip
    put = _client(ros, "param/set", "ParamSet")
    try:
        reply = get.call(param_id="SYS_AUTOSTART")
        assert reply is not None and reply.success and reply.value.integer == 10040
        value = ZenohSession.get_instance().store.types["mavros_msgs/msg/ParamValue"]
        reply = put.call(param_id="COM_OF_LOSS_T", value=value(integer=0, real=1.5))
        assert reply is not None and reply.success and reply.value.real == 1.5
        reply = get.call(param_id="NO_SUCH_PARAM")
        assert reply is not None and not reply.success
    finally:
        get.close()
        put.close()


def test_peer_arms_takes_off_moves_the_drone_and_lands(ros, graph):
    from zenoh_ros2_sdk import ROS2Publisher

    _router, node, _proc = graph
    truth = node.latest(registry.SIM_GROUND_TRUTH)
    arming = _client(ros, "cmd/arming", "CommandBool")
    takeoff = _client(ros, "cmd/takeoff", "CommandTOL", timeout=30)
    land = _client(ros, "cmd/land", "CommandTOL")
    set_mode = _client(ros, "set_mode", "SetMode")
    pub = ROS2Publisher(
        SETPOINT, "mavros_msgs/msg/PositionTarget", router_ip=ros[0], router_port=ros[1]
    )
    stop = threading.Event()
    try:
        reply = arming.call(value=True)
        assert reply is not None and reply.success, reply
        reply = takeoff.call(
            min_pitch=0.0, yaw=math.nan, latitude=math.nan, longitude=math.nan, altitude=2.5
        )
        assert reply is not None and reply.success, reply

        def z() -> float:
            pose: PoseStamped | None = truth.value
            return pose.pose.position.z if pose is not None else 0.0

        wait_for(lambda: z() > 1.5, 30, what="the climb in ground truth")
        start = truth.value.pose.position

        def stream() -> None:  # 20 Hz body velocity, 1 m/s forward: MAVROS's offboard recipe
            while not stop.is_set():
                pub.publish(**_target(1.0))
                stop.wait(0.05)

        threading.Thread(target=stream, daemon=True).start()
        time.sleep(1.5)  # the bridge primes OFFBOARD with the stream
        reply = set_mode.call(base_mode=0, custom_mode="OFFBOARD")
        assert reply is not None and reply.mode_sent, reply

        def moved() -> float:
            p = truth.value.pose.position
            return math.hypot(p.x - start.x, p.y - start.y)

        wait_for(lambda: moved() > 1.0, 20, what="horizontal motion in ground truth")
        stop.set()
        reply = land.call(
            min_pitch=0.0, yaw=math.nan, latitude=math.nan, longitude=math.nan, altitude=math.nan
        )
        assert reply is not None and reply.success, reply
        wait_for(lambda: z() < 0.3, 40, what="the landing in ground truth")
    finally:
        stop.set()
        pub.close()
        for client in (arming, takeoff, land, set_mode):
            client.close()


def test_a_humble_peer_is_reported_by_name_by_the_gateway_and_doctor(graph):
    from dronewrapper.doctor import FAIL, ros2_findings
    from dronewrapper_ros2_codec.names import SUBSCRIBER, NodeName, qos_text

    _router, node, proc = graph
    humble = NodeName(0, "0123456789abcdef0123456789abcdef", 0, "/", "humble_echo")
    token = humble.endpoint_token(
        1, SUBSCRIBER, STATE, "mavros_msgs/msg/State", "TypeHashNotSupported", qos_text()
    )
    declared = node.session.liveliness().declare_token(token)
    try:
        findings = wait_for(
            lambda: [f for f in ros2_findings(node.session) if f[0] == FAIL], 10, what="doctor"
        )
        assert len(findings) == 1
        text = findings[0][1]
        assert STATE in text and "/humble_echo subscribes" in text and "ROS 2 Humble" in text
        assert "/drone/mavros publishes" in text
        wait_for(lambda: "ROS 2 type mismatch on /drone/mavros/state" in proc.output(), 10,
                 what="the gateway's own report")  # fmt: skip
    finally:
        declared.undeclare()


def test_our_zenoh_opens_with_the_protocol_version_rmw_zenoh_speaks():
    """rmw_zenoh builds on zenoh-c 1.x, whose zenoh-protocol VERSION is 0x09 from 1.0.0 on
    (commons/zenoh-protocol/src/lib.rs); our eclipse-zenoh's first bytes on a link (INIT_SYN:
    2-byte length, header, version) must say the same (docs/ros2.md, "Same protocol")."""
    import json
    import socket as sockets

    import zenoh

    server = sockets.create_server(("127.0.0.1", 0))
    port = server.getsockname()[1]
    first: list[bytes] = []

    def accept() -> None:
        conn, _ = server.accept()
        with conn:
            conn.settimeout(5)
            first.append(conn.recv(64))

    thread = threading.Thread(target=accept)
    thread.start()
    conf = zenoh.Config()
    conf.insert_json5("mode", '"client"')
    conf.insert_json5("connect/endpoints", json.dumps([f"tcp/127.0.0.1:{port}"]))
    conf.insert_json5("scouting/multicast/enabled", "false")
    with pytest.raises(zenoh.ZError):  # nobody answers the handshake
        zenoh.open(conf)
    thread.join(10)
    server.close()
    (init,) = first
    assert init[2] & 0x1F == 0x01  # INIT (the SYN: no A flag)
    assert init[3] == 0x09
