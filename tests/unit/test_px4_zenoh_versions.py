"""Message versions learned from PX4's own announcements: a token with the bridge's hash makes a
topic usable, a doctored one (another hash, another type) is refused with a message naming the
topic and both versions, and keys are read and written as PX4's zenoh module spells them."""

from __future__ import annotations

from dronewrapper_bridge_px4_zenoh import topics
from dronewrapper_bridge_px4_zenoh.versions import Versions
from dronewrapper_ros2_codec.names import PUBLISHER, SUBSCRIBER, parse_endpoint
from dronewrapper_ros2_codec.typehash import type_hash

ZID = "1f2e3d4c5b6a79881f2e3d4c5b6a7988"
MEASURED_KEY = (
    "0/fmu/out/vehicle_status/px4_msgs::msg::dds_::VehicleStatus_/"
    "RIHS01_b98c704379561e2bfa2a83902bea00bb14357240659617df3a8be1e209747e97"
)


def token(kind: str, topic: str, type_name: str, type_hash: str) -> str:
    """A liveliness token as PX4's zenoh module writes it (node px4_<guid>, QoS depth 7)."""
    mangled = topic.replace("/", "%")
    return (
        f"@ros2_lv/0/{ZID}/0/11/{kind}/%/%/px4_aabbccddeeff/{mangled}/{type_name}/"
        f"{type_hash}/::,7:,:,:,,"
    )


def test_the_measured_key_is_the_one_the_bridge_builds():
    versions = Versions()
    assert versions.key(topics.VEHICLE_STATUS) == MEASURED_KEY
    key = topics.parse_key(MEASURED_KEY)
    assert key is not None
    assert (key.domain, key.topic) == (0, "/fmu/out/vehicle_status")
    assert key.type_name == "px4_msgs::msg::dds_::VehicleStatus_"
    assert versions.check(key.topic, key.type_name, key.type_hash) is None
    assert versions.usable(topics.VEHICLE_STATUS)
    assert topics.parse_key("drone/mavros/state") is None


def test_a_token_with_the_known_hash_makes_the_topic_usable():
    versions = Versions()
    status = topics.VEHICLE_STATUS
    assert not versions.usable(status)
    endpoint = parse_endpoint(
        token(
            PUBLISHER,
            status.name,
            "px4_msgs::msg::dds_::VehicleStatus_",
            type_hash(status.type_name),
        )
    )
    assert versions.learn(endpoint) is None
    assert versions.usable(status)


def test_a_doctored_hash_is_refused_naming_topic_expected_and_seen():
    versions = Versions()
    command = topics.COMMAND
    doctored = "RIHS01_" + "0" * 64
    endpoint = parse_endpoint(
        token(SUBSCRIBER, command.name, "px4_msgs::msg::dds_::VehicleCommand_", doctored)
    )
    mismatch = versions.learn(endpoint)
    assert mismatch is not None and not versions.usable(command)
    text = str(mismatch)
    assert "/fmu/in/vehicle_command" in text
    assert doctored in text and type_hash(command.type_name) in text
    assert "px4_msgs::msg::dds_::VehicleCommand_" in text
    assert versions.mismatches == {command.name: mismatch}


def test_another_type_on_a_known_topic_is_refused_naming_both_types():
    versions = Versions()
    endpoint = parse_endpoint(
        token(
            PUBLISHER,
            "/fmu/out/vehicle_attitude",
            "px4_msgs::msg::dds_::VehicleOdometry_",
            "RIHS01_ab",
        )
    )
    text = str(versions.learn(endpoint))
    assert "VehicleOdometry_" in text and "VehicleAttitude_" in text


def test_a_mismatch_clears_when_the_firmware_announces_the_known_version():
    versions = Versions()
    status = topics.VEHICLE_STATUS
    dds = "px4_msgs::msg::dds_::VehicleStatus_"
    assert versions.check(status.name, dds, "RIHS01_" + "1" * 64) is not None
    assert versions.check(status.name, dds, type_hash(status.type_name)) is None
    assert versions.mismatches == {} and versions.usable(status)


def test_other_domains_and_topics_are_not_the_bridges_business():
    versions = Versions(domain=3)
    other_domain = parse_endpoint(token(PUBLISHER, "/fmu/out/vehicle_status", "x", "y"))
    assert versions.learn(other_domain) is None
    assert versions.check("/fmu/out/sensor_combined", "x", "y") is None
    assert versions.mismatches == {}
    assert topics.VEHICLE_STATUS.any_version(3) == "3/fmu/out/vehicle_status/*/*"
