"""rmw_zenoh's key expressions, liveliness tokens, QoS field and attachment, against the
examples of rmw_zenoh's docs/design.md and against zenoh-ros2-sdk's own builders."""

from __future__ import annotations

import pytest

from dronewrapper_ros2_codec import attachment
from dronewrapper_ros2_codec.mismatch import disagreements
from dronewrapper_ros2_codec.names import (
    BEST_EFFORT,
    PUBLISHER,
    SUBSCRIBER,
    TRANSIENT_LOCAL,
    NodeName,
    mangle,
    parse_endpoint,
    qos_text,
    topic_key,
)

STRING_HASH = "RIHS01_df668c740482bbd48fb39d76a70dfd4bd59db1288021743503259e948f6b1a18"


def test_design_md_examples():
    talker = NodeName(0, "8b20917502ee955ac4476e0266340d5c", 0, "", "talker")
    assert talker.endpoint_token(
        10, PUBLISHER, "/chatter", "std_msgs/msg/String", STRING_HASH, qos_text(depth=7)
    ) == (
        "@ros2_lv/0/8b20917502ee955ac4476e0266340d5c/0/10/MP/%/%/talker/%chatter/"
        f"std_msgs::msg::dds_::String_/{STRING_HASH}/::,7:,:,:,,"
    )
    listener = NodeName(0, "aac3178e146ba6f1fc6e6a4085e77f21", 0, "", "listener")
    assert listener.token() == "@ros2_lv/0/aac3178e146ba6f1fc6e6a4085e77f21/0/0/NN/%/%/listener"
    assert topic_key(0, "/chatter", "std_msgs/msg/String", STRING_HASH) == (
        f"0/chatter/std_msgs::msg::dds_::String_/{STRING_HASH}"
    )


def test_names_keep_inner_slashes_in_keys_and_mangle_them_in_tokens():
    assert topic_key(7, "/drone/mavros/cmd/arming/", "mavros_msgs/srv/CommandBool", "H") == (
        "7/drone/mavros/cmd/arming/mavros_msgs::srv::dds_::CommandBool_/H"
    )
    assert mangle("/drone/mavros/state") == "%drone%mavros%state"
    assert mangle("") == "%"


def test_qos_field_writes_only_what_differs_from_rmw_zenoh_defaults():
    assert qos_text() == "::,:,:,:,,"
    assert qos_text(depth=10) == "::,10:,:,:,,"
    assert qos_text(reliability=BEST_EFFORT, depth=5) == "2::,5:,:,:,,"
    assert qos_text(durability=TRANSIENT_LOCAL, depth=1) == ":1:,1:,:,:,,"


def test_parse_endpoint_reads_tokens_back_and_ignores_nodes():
    node = NodeName(0, "z1", 1, "/drone", "mavros")
    token = node.endpoint_token(
        4,
        SUBSCRIBER,
        "/drone/mavros/setpoint_raw/local",
        "mavros_msgs/msg/PositionTarget",
        "RIHS01_bb",
        qos_text(depth=10),
    )
    endpoint = parse_endpoint(token)
    assert endpoint is not None
    assert (endpoint.node, endpoint.topic, endpoint.kind) == (
        "/drone/mavros",
        "/drone/mavros/setpoint_raw/local",
        SUBSCRIBER,
    )
    assert endpoint.type_name == "mavros_msgs::msg::dds_::PositionTarget_"
    assert parse_endpoint(token + "/backends:x:y") == endpoint  # Lyrical/Rolling's 14th chunk
    assert parse_endpoint(node.token()) is None
    assert parse_endpoint("drone/alive/bridge") is None


@pytest.mark.parametrize("raw", [None, b"", b"commander=alice", bytes(33)])
def test_other_attachments_are_refused(raw):
    with pytest.raises(attachment.AttachmentError):
        attachment.unpack(raw)


def test_a_humble_peer_is_named_as_a_mismatch():
    ours = NodeName(0, "gw", 0, "/drone", "mavros").endpoint_token(
        1, PUBLISHER, "/drone/mavros/state", "mavros_msgs/msg/State", "RIHS01_aa", "::,10:,:,:,,"
    )
    humble = NodeName(0, "ros", 0, "/", "echo").endpoint_token(
        1,
        SUBSCRIBER,
        "/drone/mavros/state",
        "mavros_msgs/msg/State",
        "TypeHashNotSupported",
        "::,10:,:,:,,",
    )
    other = NodeName(0, "ros", 0, "/", "echo").endpoint_token(
        2, SUBSCRIBER, "/other", "mavros_msgs/msg/State", "TypeHashNotSupported", "::,:,:,:,,"
    )
    found = disagreements(parse_endpoint(t) for t in (ours, humble, other))
    assert len(found) == 1 and found[0].involves("gw")
    text = found[0].describe()
    assert "/drone/mavros/state" in text and "RIHS01_aa" in text
    assert "/echo subscribes" in text and "ROS 2 Humble" in text
    same = disagreements(parse_endpoint(t) for t in (ours, ours.replace("/1/MP", "/2/MS")))
    assert same == []
