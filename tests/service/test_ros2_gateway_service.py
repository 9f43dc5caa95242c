"""The gateway's rules on the fake bus, with a recording stand-in for the ROS 2 side's Zenoh
session: what it declares, what it forwards out, what it refuses on the way in (each rule
held by a test), service calls through the bridge's real command lease, cameras on demand,
type mismatches named."""

from __future__ import annotations

import logging
import math
from types import SimpleNamespace
from typing import Any

import pytest
import zenoh
from ros2_session import PT, ZID, RosSession, ros_key

from dronewrapper.msgs import registry
from dronewrapper.msgs.mavros import CommandBoolResult, PositionTarget, State
from dronewrapper.msgs.sensor import Image
from dronewrapper.msgs.std import Header
from dronewrapper.runtime.caller import commander_of, current_commander
from dronewrapper.runtime.fake import FakeBus, FakeNode
from dronewrapper_bridge_base.commander_lease import LeaseGate
from dronewrapper_ros2_codec import attachment, cdr
from dronewrapper_ros2_codec.names import SUBSCRIBER, NodeName, qos_text
from dronewrapper_ros2_codec.typehash import type_hash
from dronewrapper_ros2_gateway.config import Config
from dronewrapper_ros2_gateway.entities import ENTITIES, PORTS
from dronewrapper_ros2_gateway.node import Gateway, commander_name


class Rig:
    def __init__(self, keys: list[str] | None = None) -> None:
        self.bus = FakeBus(start=100.0)
        self.node = FakeNode("ros2_gateway", self.bus, ports=PORTS)
        self.session = RosSession()
        self.gateway = Gateway(self.node, Config(keys=keys or []), self.session)  # type: ignore[arg-type]
        self.gateway.start()
        self.forwarded: list[tuple[PositionTarget, str]] = []
        publisher = self.gateway._setpoint_publishers.get("drone")

        def record(target: PositionTarget, *, attachment: bytes | None = None) -> None:
            self.forwarded.append((target, commander_of(attachment)))
            publisher.put(target, attachment=attachment)

        self.gateway._setpoint_publishers["drone"] = SimpleNamespace(put=record)


@pytest.fixture
def rig() -> Rig:
    return Rig()


def test_declares_a_node_token_and_one_token_and_key_per_entity(rig):
    tokens = rig.session.tokens
    assert tokens[0] == f"@ros2_lv/0/{ZID}/0/0/NN/%/%drone/mavros"
    assert len(tokens) == 1 + len(ENTITIES)
    state = ros_key("/drone/mavros/state", "mavros_msgs/msg/State")
    assert state in rig.session.publishers
    assert any(
        t.endswith(
            f"/MP/%/%drone/mavros/%drone%mavros%state/mavros_msgs::msg::dds_::State_/"
            f"{type_hash('mavros_msgs/msg/State')}/::,10:,:,:,,"
        )
        for t in tokens
    )
    assert ros_key("/drone/mavros/setpoint_raw/local", PT) in rig.session.subscribers
    assert ros_key("/drone/mavros/cmd/arming", "mavros_msgs/srv/CommandBool") in (
        rig.session.queryables
    )
    camera = next(t for t in tokens if "%drone%cam_frontal%image_raw/" in t)
    assert camera.endswith("/2::,5:,:,:,,")  # sensor data QoS


def test_keys_select_the_entities():
    rig = Rig(keys=["mavros/state"])
    assert list(rig.session.publishers) == [ros_key("/drone/mavros/state", "mavros_msgs/msg/State")]
    assert rig.session.subscribers == {} and rig.session.queryables == {}


def test_telemetry_goes_out_as_cdr_with_the_rmw_zenoh_attachment(rig):
    state = State(header=Header(stamp=1700000000.5), connected=True, armed=True, mode="OFFBOARD")
    publisher = rig.session.publishers[ros_key("/drone/mavros/state", "mavros_msgs/msg/State")]
    for _ in range(2):
        rig.bus.put(registry.STATE.key("drone"), _encode(state))
    (first, a1), (_, a2) = publisher.sent
    value = cdr.decode("mavros_msgs/msg/State", first)
    assert value["connected"] and value["mode"] == "OFFBOARD"
    assert value["header"]["stamp"] == {"sec": 1700000000, "nanosec": 500000000}
    m1, m2 = attachment.unpack(a1), attachment.unpack(a2)
    assert (m1.sequence, m2.sequence) == (1, 2) and m1.gid == m2.gid != bytes(16)


def _encode(msg: Any) -> bytes:
    from dronewrapper.msgs import codec

    return codec.encode(msg)


def _target(**kw: Any) -> dict[str, Any]:
    value: dict[str, Any] = {
        "header": {"stamp": {"sec": 1, "nanosec": 0}, "frame_id": ""},
        "coordinate_frame": 8,
        "type_mask": 1991,
        "position": {"x": 0.0, "y": 0.0, "z": 0.0},
        "velocity": {"x": 1.0, "y": 0.0, "z": 0.0},
        "acceleration_or_force": {"x": 0.0, "y": 0.0, "z": 0.0},
        "yaw": 0.0,
        "yaw_rate": 0.0,
    }
    value.update(kw)
    return value


META = attachment.pack(1, 0, bytes(16))


def test_a_good_setpoint_goes_to_the_bridge_under_the_gateway_commander_name(rig):
    assert rig.gateway.on_setpoint("drone", cdr.encode(PT, _target()), META)
    ((target, commander),) = rig.forwarded
    assert commander == "ros2_gateway"
    assert target.type_mask == 1991 and target.velocity.x == 1.0
    assert rig.bus.published[registry.SETPOINT_RAW_LOCAL.key("drone")][0].msg == target


@pytest.mark.parametrize(
    ("payload", "meta"),
    [
        (cdr.encode(PT, _target(velocity={"x": math.nan, "y": 0.0, "z": 0.0})), META),
        (cdr.encode(PT, _target(yaw_rate=math.inf)), META),
        (cdr.encode(PT, _target(type_mask=0)), META),  # "go to the origin" is not a control
        (cdr.encode(PT, _target(coordinate_frame=8, type_mask=3064)), META),
        (b"\x00\x01\x00\x00garbage", META),
        (b"", META),
        (cdr.encode(PT, _target()), None),  # rmw_zenoh drops samples without an attachment
        (cdr.encode(PT, _target()), b"commander=alice"),
    ],
    ids=["nan", "inf", "mask", "frame", "garbage", "empty", "no_attachment", "not_rmw"],
)
def test_bad_setpoints_are_refused_and_counted(rig, payload, meta):
    assert not rig.gateway.on_setpoint("drone", payload, meta)
    assert rig.forwarded == [] and rig.gateway.refused["setpoint"] == 1


ARMING = ENTITIES["mavros/cmd/arming"]
ARM = cdr.encode("mavros_msgs/srv/CommandBool_Request", {"value": True})


def _bridge(rig: Rig) -> LeaseGate:
    """A bridge's arming behind its command lease (the gate a bridge's core applies)."""
    gate = LeaseGate(10.0, logging.getLogger("bridge"))
    bridge = FakeNode("bridge", rig.bus)

    def arming(request: Any) -> CommandBoolResult:
        refusal = gate.command_refusal(current_commander(), "arming", rig.bus.clock())
        if refusal is not None:
            raise refusal
        return CommandBoolResult(success=request.value, result=0)

    bridge.serve(registry.ARMING, arming)
    return gate


def test_service_calls_are_the_bridge_s_under_its_command_lease(rig):
    guard = _bridge(rig)
    guard.lease.take_over("alice", rig.bus.clock())
    assert rig.gateway.serve("drone", ARMING, ARM) == {"success": False, "result": 2}
    assert guard.refused_commands == 1
    guard.lease.release("alice", rig.bus.clock())
    assert rig.gateway.serve("drone", ARMING, ARM) == {"success": True, "result": 0}
    assert guard.holder(rig.bus.clock()) == "ros2_gateway"


@pytest.mark.parametrize("payload", [None, b"", b"\x00\x01\x00\x00", b"\x07garbage"])
def test_garbage_requests_are_refused_without_reaching_the_bridge(rig, payload):
    guard = _bridge(rig)
    assert rig.gateway.serve("drone", ARMING, payload) == {"success": False, "result": 2}
    assert guard.holder(rig.bus.clock()) == ""


def test_no_bridge_is_a_failed_result_not_silence(rig):
    assert rig.gateway.serve("drone", ARMING, ARM) == {"success": False, "result": 4}


def test_a_camera_is_forwarded_only_while_a_ros2_subscriber_wants_it(rig):
    key = ros_key("/drone/cam_frontal/image_raw", "sensor_msgs/msg/Image")
    publisher = rig.session.publishers[key]
    image = Image(header=Header(stamp=5.0), height=1, width=2, step=6, data=memoryview(bytes(6)))
    camera = registry.IMAGE_RAW.key("drone", camera="cam_frontal")
    assert not rig.bus.matched(camera)
    publisher.matching_status.matching = True
    rig.gateway.follow_demand()
    rig.bus.put(camera, _encode(image))
    assert len(publisher.sent) == 1
    assert cdr.decode("sensor_msgs/msg/Image", publisher.sent[0][0])["width"] == 2
    publisher.matching_status.matching = False
    rig.gateway.follow_demand()
    assert not rig.bus.matched(camera)


def test_a_type_mismatch_announced_by_a_peer_is_named(rig):
    humble = NodeName(0, "feed", 0, "/", "echo").endpoint_token(
        1,
        SUBSCRIBER,
        "/drone/mavros/state",
        "mavros_msgs/msg/State",
        "TypeHashNotSupported",
        qos_text(),
    )
    (watch,) = rig.session.watchers.values()
    watch(SimpleNamespace(key_expr=humble, kind=zenoh.SampleKind.PUT))
    (text,) = rig.gateway.mismatches
    assert "/drone/mavros/state" in text and "/echo subscribes" in text and "Humble" in text
    watch(SimpleNamespace(key_expr=humble, kind=zenoh.SampleKind.DELETE))
    matching = NodeName(0, "feed", 0, "/", "ok").endpoint_token(
        2,
        SUBSCRIBER,
        "/drone/mavros/state",
        "mavros_msgs/msg/State",
        type_hash("mavros_msgs/msg/State"),
        qos_text(),
    )
    watch(SimpleNamespace(key_expr=matching, kind=zenoh.SampleKind.PUT))
    assert len(rig.gateway.mismatches) == 1


@pytest.mark.parametrize(
    ("identity", "configured", "name"),
    [
        ("", "", "ros2_gateway"),
        ("ros2-gw", "", "ros2-gw"),
        ("/keys/ros2-gw.crt", "", "ros2-gw"),
        ("ros2-gw", "lab", "lab"),
    ],
)
def test_the_commander_name_is_the_identity_s_unless_configured(identity, configured, name):
    assert commander_name(Config(commander=configured), identity) == name


def test_each_drone_is_its_own_node_with_ids_unique_in_the_session():
    session = RosSession()
    node = FakeNode("ros2_gateway", FakeBus(), ports=PORTS)
    Gateway(node, Config(drones=["drone1", "drone2"], keys=["mavros/state"]), session).start()  # type: ignore[arg-type]
    ids = [tuple(t.split("/")[3:5]) for t in session.tokens]
    assert len(set(ids)) == len(ids) == 4
    assert sorted(session.publishers) == sorted(
        ros_key(f"/{ns}/mavros/state", "mavros_msgs/msg/State") for ns in ("drone1", "drone2")
    )
