"""The gateway hosted by a bridge, on the fake bus: the real bridge core (lease, late-setpoint
rule) on the shared bridge wiring, the gateway on the same node, a recording stand-in for the
ROS 2 side's session. A ROS 2 node is one more commander of that bridge, never a bypass."""

from __future__ import annotations

import logging
from types import SimpleNamespace
from typing import Any

import pytest
from ros2_session import PT, RosSession, ros_key

from dronewrapper.msgs import registry
from dronewrapper.msgs.lease import LeaseRequest
from dronewrapper.msgs.sensor import Image
from dronewrapper.msgs.std import Header
from dronewrapper.runtime.caller import commander_attachment
from dronewrapper.runtime.config import ConfigError, load_config
from dronewrapper.runtime.fake import FakeBus, FakeNode
from dronewrapper_bridge_base.bridge_node import BridgeNode
from dronewrapper_bridge_mavlink import node as mavlink_node
from dronewrapper_bridge_mavlink.config import Config as MavlinkConfig
from dronewrapper_bridge_mavlink.core import BridgeCore
from dronewrapper_bridge_tello.config import Config as TelloConfig
from dronewrapper_ros2_codec import attachment, cdr
from dronewrapper_ros2_gateway.config import Config
from dronewrapper_ros2_gateway.entities import ENTITIES
from dronewrapper_ros2_gateway.hosted import check_hosted, hosted_gateway

SETPOINT_KEY = ros_key("/drone/mavros/setpoint_raw/local", PT)
ARM = cdr.encode("mavros_msgs/srv/CommandBool_Request", {"value": True})


class Wired(BridgeNode):
    """bridge_mavlink's core on the bridge wiring (in the bus's time: the node's), sends
    dropped."""

    def send(self, out) -> None:
        pass


class HostingBridge:
    """A bridge node (identity ``drone1``) hosting the gateway, and a user node beside it."""

    def __init__(self, **config: Any) -> None:
        self.bus = FakeBus(start=1_700_000_000.0)
        self.node = FakeNode("bridge_mavlink", self.bus)
        self.node.options = SimpleNamespace(identity="drone1")  # type: ignore[attr-defined]
        self.node.session = RosSession()  # type: ignore[attr-defined]
        self.subscribed: list[tuple[str, bool | None]] = []
        subscribe = self.node.subscribe

        def recording(topic: Any, callback: Any, **kw: Any) -> Any:
            self.subscribed.append((kw.get("key", ""), kw.get("direct")))
            return subscribe(topic, callback, **kw)

        self.node.subscribe = recording  # type: ignore[method-assign]
        core = BridgeCore(MavlinkConfig(**config))
        publishers = {t: self.node.publisher(t) for t in mavlink_node.PUBLISHED}
        self.bridge = Wired(self.node, core, publishers, logging.getLogger("bridge"))
        self.bridge.serve(mavlink_node.SERVICES)
        self.user = FakeNode("apps", self.bus)

    @property
    def session(self) -> RosSession:
        return self.node.session  # type: ignore[attr-defined]

    def ros_setpoint(self, vx: float, sent_ns: int, sequence: int = 1) -> None:
        """A ROS 2 PositionTarget (body velocity ``vx``) as Zenoh hands it to the gateway."""
        payload = cdr.encode(PT, _target(vx))
        meta = attachment.pack(sequence, sent_ns, bytes(16))
        sample = SimpleNamespace(
            payload=SimpleNamespace(to_bytes=lambda: payload),
            attachment=SimpleNamespace(to_bytes=lambda: meta),
        )
        self.session.subscribers[SETPOINT_KEY](sample)

    def lease(self, action: str, who: str) -> Any:
        request = LeaseRequest(action=action)
        return self.user.call(registry.COMMAND_LEASE, request, attachment=commander_attachment(who))


def _target(vx: float) -> dict[str, Any]:
    vector = {"x": 0.0, "y": 0.0, "z": 0.0}
    return {
        "header": {"stamp": {"sec": 1, "nanosec": 0}, "frame_id": ""},
        "coordinate_frame": 8,  # body
        "type_mask": 1991,  # velocity
        "position": vector,
        "velocity": {**vector, "x": vx},
        "acceleration_or_force": vector,
        "yaw": 0.0,
        "yaw_rate": 0.0,
    }


def test_no_ros2_section_hosts_nothing():
    bridge = HostingBridge()
    with hosted_gateway(bridge.node, None) as gateway:
        assert gateway is None
    own = 2  # the bridge's own subscriptions: setpoints and commanders' beats
    assert bridge.session.tokens == [] and bridge.subscribed[own:] == []


def test_a_bridge_presents_its_own_drone_only():
    check_hosted(Config(drones=["drone"]), "drone")
    with pytest.raises(
        ValueError, match=r"drones: beside a bridge, the gateway presents its drone only"
    ):
        check_hosted(Config(drones=["drone", "drone2"]), "drone")
    bridge = HostingBridge()
    with (  # refused before anything is declared
        pytest.raises(ValueError, match=r"drones: beside a bridge"),
        hosted_gateway(bridge.node, Config(drones=["drone2"])),
    ):
        pass
    assert bridge.session.tokens == []


def test_telemetry_is_taken_on_the_putting_thread_and_cameras_on_zenoh_s():
    bridge = HostingBridge()
    with hosted_gateway(bridge.node, Config()) as gateway:
        bridge.bridge.driver.feed(bridge.bridge.core.on_started)
        state_key = ros_key("/drone/mavros/state", "mavros_msgs/msg/State")
        ((payload, _meta),) = bridge.session.publishers[state_key].sent
        assert cdr.decode("mavros_msgs/msg/State", payload)["mode"] == ""
        image_key = ros_key("/drone/cam_frontal/image_raw", "sensor_msgs/msg/Image")
        bridge.session.publishers[image_key].matching_status.matching = True
        gateway.follow_demand()
        image = Image(header=Header(stamp=5.0), height=1, width=2, step=6, data=bytes(6))
        bridge.node.publisher(registry.IMAGE_RAW, camera="cam_frontal").put(image)
        assert len(bridge.session.publishers[image_key].sent) == 1
    direct = dict(bridge.subscribed[2:])  # after the bridge's own: setpoints, beats
    assert direct[registry.STATE.key("drone")] is True
    assert direct[registry.LOCAL_POSE.key("drone")] is True
    assert direct[registry.IMAGE_RAW.key("drone", camera="cam_frontal")] is False
    telemetry = [e for e in ENTITIES.values() if e.direction == "out" and "image" not in e.name]
    assert sum(flag is True for flag in direct.values()) == len(telemetry)


def test_a_ros2_node_needs_the_bridge_s_command_lease_and_commands_under_its_own_name():
    bridge = HostingBridge(command_lease=True)
    lease = bridge.bridge.core.lease
    with hosted_gateway(bridge.node, Config()) as gateway:
        assert gateway is not None and gateway.commander == "ros2_gateway"  # not "drone1"
        assert bridge.lease("take", "alice").granted
        now_ns = int(bridge.bus.clock.time() * 1e9)
        bridge.ros_setpoint(1.0, now_ns)
        assert lease.refused_setpoints == 1  # forwarded by the gateway, refused by the bridge
        arming = gateway.serve("drone", ENTITIES["mavros/cmd/arming"], ARM)
        assert arming == {"success": False, "result": 2} and lease.refused_commands == 1
        assert bridge.lease("release", "alice").granted
        bridge.ros_setpoint(1.0, now_ns, sequence=2)
        assert lease.refused_setpoints == 1
        assert lease.holder(bridge.bus.clock.monotonic()) == "ros2_gateway"
        assert bridge.bridge.core.failsafe.target.velocity.x == 1.0


def test_a_burst_held_on_the_ros2_side_is_refused_by_the_bridge_s_late_rule():
    bridge = HostingBridge()
    core = bridge.bridge.core
    with hosted_gateway(bridge.node, Config()):
        for i in range(30):  # 1 s at 30 Hz, each sent as it arrives (ROS 2 source stamps)
            bridge.bus.clock.advance_to(bridge.bus.clock.monotonic() + 1 / 30)
            bridge.ros_setpoint(0.0, int(bridge.bus.clock.time() * 1e9), sequence=i)
        assert core.setpoint_delay.refused == 0
        held_since = bridge.bus.clock.time()
        bridge.bus.clock.advance_to(bridge.bus.clock.monotonic() + 1.0)  # the ROS 2 link stalls
        for i in range(30):  # what was queued meanwhile arrives at once: stamped 1 s ago
            bridge.ros_setpoint(2.0, int((held_since + i / 30) * 1e9), sequence=100 + i)
        assert core.setpoint_delay.refused == 30
        assert core.failsafe.target.velocity.x == 0.0  # the held command never flew


@pytest.mark.parametrize("schema", [MavlinkConfig, TelloConfig])
def test_a_bridge_config_has_no_gateway_section(schema):
    """The gateway beside a bridge is a service of its own in the bridge's process
    (process.py, runtime/host.py), with its own config: the bridge's names no ROS 2 key."""
    with pytest.raises(ConfigError, match="ros2"):
        load_config(schema, overrides=["ros2.domain_id=3"])
