"""Transport classes: declared per topic in the registry, applied as Zenoh QoS by the runtime."""

import pytest
import zenoh

from dronewrapper.msgs import mavros, registry, sensor
from dronewrapper.runtime.options import is_local_endpoint
from dronewrapper.runtime.qos import SERVICE_QOS, qos_for


def test_every_topic_has_a_known_class_and_images_are_the_only_streams():
    for name, topic in registry.TOPICS.items():
        assert topic.transport in registry.TRANSPORTS, name
        carries_frames = topic.type in (sensor.Image, sensor.CompressedImage)
        assert (topic.transport == registry.STREAM) == carries_frames, name


def test_commands_outrank_telemetry_which_outranks_images():
    order = [zenoh.Priority.INTERACTIVE_HIGH, zenoh.Priority.DATA_HIGH, zenoh.Priority.DATA_LOW]
    assert [
        qos_for(registry.SETPOINT_RAW_LOCAL)["priority"],
        qos_for(registry.LOCAL_POSE)["priority"],
        qos_for(registry.IMAGE_RAW)["priority"],
    ] == order
    assert qos_for(registry.IMAGE_RAW)["congestion_control"] == zenoh.CongestionControl.DROP
    # a bridge never stalls on a slow subscriber: telemetry drops rather than blocks
    assert qos_for(registry.STATE)["congestion_control"] == zenoh.CongestionControl.DROP
    assert qos_for(registry.SETPOINT_RAW_LOCAL)["express"] is True
    assert SERVICE_QOS["priority"] == zenoh.Priority.INTERACTIVE_HIGH


def test_a_topic_with_an_unknown_class_is_refused():
    with pytest.raises(ValueError, match="transport must be one of"):
        registry.Topic("x/{ns}", type=mavros.State, transport="fast")


@pytest.mark.parametrize(
    ("endpoint", "local"),
    [
        ("tcp/127.0.0.1:7447", True),
        ("tcp/localhost:7447", True),
        ("tcp/[::1]:7447", True),
        ("unixsock-stream//tmp/zenoh.sock", True),
        ("tcp/192.168.1.50:7447", False),
        ("tls/drone.local:7447", False),
        ("udp/10.0.0.2:7447", False),
    ],
)
def test_local_endpoints(endpoint, local):
    assert is_local_endpoint(endpoint) is local
