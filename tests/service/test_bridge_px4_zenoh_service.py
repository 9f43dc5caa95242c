"""The PX4 Zenoh bridge's process on the fake bus, its PX4 side a stand-in session fed with a
real PX4 SIH's recorded tokens and CDR samples (tests/data/px4_zenoh/sih_ground.json), which
answers the bridge's vehicle commands as PX4's commander does (an ack, then the new arming or
nav state). Held here: the wiring both ways (PX4's samples to the MAVROS-equivalent keys; a
commander's setpoint to PX4's exact key as CDR with rmw_zenoh's attachment), the writes to PX4
declared as commands (never dropped nor batched on the way), the bridge's own liveliness
tokens, a service answered by PX4's ack, and a doctored token refused by name."""

from __future__ import annotations

import json
from pathlib import Path
from types import SimpleNamespace
from typing import Any

import pytest
import zenoh
from ros2_session import RosSession

from dronewrapper.msgs import registry
from dronewrapper.msgs.geometry import Vector3
from dronewrapper.msgs.mavros import FRAME_BODY_NED, MASK_VELOCITY, CommandBool, PositionTarget
from dronewrapper.runtime.caller import commander_attachment
from dronewrapper.runtime.fake import FakeBus, FakeNode
from dronewrapper_bridge_px4_zenoh import commands as cmds
from dronewrapper_bridge_px4_zenoh import topics as t
from dronewrapper_bridge_px4_zenoh.config import Config
from dronewrapper_bridge_px4_zenoh.node import PORTS, Bridge
from dronewrapper_bridge_px4_zenoh.versions import Versions
from dronewrapper_ros2_codec import attachment, cdr
from dronewrapper_ros2_codec.names import PUBLISHER, parse_endpoint

RECORDING = json.loads(
    (Path(__file__).resolve().parents[1] / "data" / "px4_zenoh" / "sih_ground.json").read_text()
)
DOCTORED = "RIHS01_" + "ab" * 32


def sample(key: str, payload: bytes, att: bytes | None = None) -> Any:
    return SimpleNamespace(
        key_expr=key,
        payload=SimpleNamespace(to_bytes=lambda: payload),
        attachment=att,
        kind=zenoh.SampleKind.PUT,
    )


class Ring:
    """A subscriber with Zenoh's ``RingChannel(1)``: the newest sample, taken by try_recv."""

    def __init__(self) -> None:
        self.newest: Any = None
        self.received = 0

    def __call__(self, sample: Any) -> None:
        self.newest, self.received = sample, self.received + 1

    def try_recv(self) -> Any:
        sample, self.newest = self.newest, None
        return sample

    def undeclare(self) -> None:
        pass


class Px4Session(RosSession):
    """PX4's side of the router: replays the recording, answers vehicle commands."""

    def __init__(self) -> None:
        super().__init__()
        self.publisher_qos: dict[str, dict[str, Any]] = {}
        self.status_key = next(k for k in RECORDING["samples"] if "/vehicle_status/" in k)
        self.status = cdr.decode(
            t.VEHICLE_STATUS.type_name,
            bytes.fromhex(RECORDING["samples"][self.status_key]["payload"]),
        )

    def px4_publishes(self, key: str, payload: bytes, att: bytes | None = None) -> None:
        for pattern, callback in self.subscribers.items():
            if zenoh.KeyExpr(pattern).intersects(zenoh.KeyExpr(key)):
                callback(sample(key, payload, att))

    def replay(self, doctor: str = "") -> None:
        for token in RECORDING["tokens"]:
            if doctor and f"/{doctor.replace('/', '%')}/" in token:
                token = token.replace(parse_endpoint(token).type_hash, DOCTORED)
            for callback in self.watchers.values():
                callback(sample(token, b""))
        for key, recorded in RECORDING["samples"].items():
            att = bytes.fromhex(recorded["attachment"])
            self.px4_publishes(key, bytes.fromhex(recorded["payload"]), att)

    def declare_subscriber(self, key: str, callback: Any, **kw: Any) -> Any:
        if isinstance(callback, zenoh.handlers.RingChannel):
            ring = Ring()
            super().declare_subscriber(key, ring, **kw)
            return ring
        return super().declare_subscriber(key, callback, **kw)

    def declare_publisher(self, key: str, **qos: Any) -> Any:
        publisher = super().declare_publisher(key, **qos)
        self.publisher_qos[key] = qos
        if "/fmu/in/vehicle_command/" in key:
            publisher.put = lambda payload, *, attachment: self.commander(payload)
        return publisher

    def commander(self, payload: bytes) -> None:
        """PX4's commander: an ack for each command, and its effect on vehicle_status."""
        command = cdr.decode(t.COMMAND.type_name, payload)
        self.commands.append(command)
        ack = {
            "timestamp": 0,
            "command": command["command"],
            "result": cmds.ACCEPTED,
            "result_param1": 0,
            "result_param2": 0,
            "target_system": command["source_system"],
            "target_component": command["source_component"],
            "from_external": False,
        }
        ack_key = Versions().key(t.COMMAND_ACK)
        self.px4_publishes(ack_key, cdr.encode(t.COMMAND_ACK.type_name, ack))
        if command["command"] == cmds.ARM_DISARM:
            self.status["arming_state"] = 2 if command["param1"] == 1.0 else 1
            self.px4_publishes(self.status_key, cdr.encode(t.VEHICLE_STATUS.type_name, self.status))

    commands: list[dict[str, Any]]


class Rig:
    def __init__(self, **config: Any) -> None:
        self.bus = FakeBus(start=1_700_000_000.0)
        self.node = FakeNode("bridge_px4_zenoh", self.bus, ports=PORTS)
        self.session = Px4Session()
        self.session.commands = []
        self.bridge = Bridge(self.node, Config(**config), self.session)
        self.bridge.declare()
        self.user = FakeNode("app", self.bus)

    def latest(self, topic: Any) -> Any:
        return self.user.latest(topic)


@pytest.fixture
def rig() -> Rig:
    return Rig()


def test_pxs_recorded_samples_arrive_on_the_mavros_keys(rig):
    state, pose, battery = (
        rig.latest(registry.STATE),
        rig.latest(registry.LOCAL_POSE),
        rig.latest(registry.BATTERY),
    )
    rig.session.replay()
    rig.bridge.tick_once("stream")
    assert state.value.connected and state.value.mode == "AUTO.LOITER" and not state.value.armed
    assert pose.value.header.frame_id == "map"
    assert 14.0 < battery.value.voltage < 17.0


def test_a_setpoint_reaches_pxs_exact_key_as_cdr_with_rmw_zenohs_attachment(rig):
    rig.session.replay()
    target = PositionTarget(
        coordinate_frame=FRAME_BODY_NED, type_mask=MASK_VELOCITY, velocity=Vector3(x=1.0)
    )
    rig.user.publisher(registry.SETPOINT_RAW_LOCAL).put(
        target, attachment=commander_attachment("app")
    )
    key = Versions().key(t.TRAJECTORY)
    assert key.startswith("0/fmu/in/trajectory_setpoint/px4_msgs::msg::dds_::TrajectorySetpoint_/")
    ((payload, att),) = rig.session.publishers[key].sent
    value = cdr.decode(t.TRAJECTORY.type_name, payload)
    assert value["velocity"][:2] != [0.0, 0.0] and payload[:4] == b"\x00\x01\x00\x00"
    assert attachment.unpack(att).sequence == 1
    ((mode_payload, _),) = rig.session.publishers[Versions().key(t.OFFBOARD_MODE)].sent
    assert cdr.decode(t.OFFBOARD_MODE.type_name, mode_payload)["velocity"]


def test_the_bridge_announces_its_publishers_in_pxs_versions(rig):
    endpoints = [parse_endpoint(token) for token in rig.session.tokens[1:]]
    assert {e.topic for e in endpoints if e.kind == PUBLISHER} == {
        t.OFFBOARD_MODE.name,
        t.TRAJECTORY.name,
        t.COMMAND.name,
    }
    versions = Versions()
    assert all(versions.learn(e) is None for e in endpoints)


def test_the_writes_to_px4_travel_as_commands_never_dropped_nor_batched(rig):
    # with Zenoh's default (droppable, batched) the router stopped forwarding them to PX4
    written = {key: qos for key, qos in rig.session.publisher_qos.items() if "/fmu/in/" in key}
    assert len(written) == 3
    for qos in written.values():
        assert qos["congestion_control"] == zenoh.CongestionControl.BLOCK
        assert qos["express"] is True
        assert qos["priority"] == zenoh.Priority.INTERACTIVE_HIGH


def test_arming_is_answered_by_pxs_commander(rig):
    rig.session.replay()
    reply = rig.user.call(
        registry.ARMING, CommandBool(value=True), attachment=commander_attachment("app")
    )
    assert reply.success and reply.message == "ARM_DISARM accepted"
    (command,) = rig.session.commands
    assert command["target_system"] == 1 and command["from_external"]


def test_a_doctored_token_is_refused_by_name_on_statustext(rig):
    texts = []
    rig.user.subscribe(registry.STATUSTEXT, texts.append)
    rig.session.replay(doctor="/fmu/out/vehicle_status")
    (text,) = [m.text for m in texts]
    assert "/fmu/out/vehicle_status" in text and DOCTORED in text
    assert Versions().expected["/fmu/out/vehicle_status"] in text


def test_pxs_high_rate_samples_wait_undecoded_for_the_tick(rig):
    rig.session.replay()
    rig.bridge.tick_once("stream")
    decoded = rig.bridge.core.samples_received
    key = next(k for k in RECORDING["samples"] if "/vehicle_local_position/" in k)
    payload = bytes.fromhex(RECORDING["samples"][key]["payload"])
    for _ in range(50):  # PX4's ~110 Hz local position between two ticks, and more
        rig.session.px4_publishes(key, payload)
    assert rig.bridge.core.samples_received == decoded  # nothing decoded on arrival
    poses = []
    rig.user.subscribe(registry.LOCAL_POSE, poses.append)
    rig.bridge.tick_once("stream")
    assert rig.bridge.core.samples_received == decoded + 1 and len(poses) == 1
    rig.bridge.tick_once("stream")  # nothing new from PX4: nothing decoded, no pose
    assert rig.bridge.core.samples_received == decoded + 1 and len(poses) == 1
