"""Our rmw_zenoh names, tokens, attachment and service type hashes against zenoh-ros2-sdk's own
builders: a second, independent implementation of the protocol. zenoh-ros2-sdk imports GitPython,
which runs ``git`` when imported, so these comparisons live in the integration tier."""

from __future__ import annotations

from pathlib import Path

import pytest

from dronewrapper_ros2_codec import attachment, interfaces
from dronewrapper_ros2_codec.names import PUBLISHER, NodeName
from dronewrapper_ros2_codec.typehash import type_hash

pytestmark = pytest.mark.integration

UPSTREAM = Path(__file__).resolve().parents[1] / "data" / "ros2_interfaces"


@pytest.mark.parametrize("service", sorted(interfaces.SERVICES))
def test_service_hash_equals_zenoh_ros2_sdk(service):
    from zenoh_ros2_sdk.utils import compute_service_type_hash

    request, response = (UPSTREAM / f"{service}.srv").read_text().split("---")
    deps = {"mavros_msgs/msg/ParamValue": (UPSTREAM / "mavros_msgs/msg/ParamValue.msg").read_text()}
    assert type_hash(service) == compute_service_type_hash(service, request, response, deps)


def test_tokens_equal_zenoh_ros2_sdk():
    from zenoh_ros2_sdk.entity import EndpointEntity, EntityKind, NodeEntity
    from zenoh_ros2_sdk.keyexpr import endpoint_liveliness_keyexpr, node_liveliness_keyexpr

    theirs_node = NodeEntity(
        domain_id=3,
        session_id="abc1",
        node_id=2,
        node_name="mavros",
        namespace="/drone",
        enclave="",
    )
    ours = NodeName(3, "abc1", 2, "/drone", "mavros")
    assert ours.token() == node_liveliness_keyexpr(theirs_node)
    theirs = EndpointEntity(
        node=theirs_node,
        entity_id=5,
        kind=EntityKind.PUBLISHER,
        name="/drone/mavros/state",
        dds_type_name="mavros_msgs::msg::dds_::State_",
        type_hash="RIHS01_aa",
        qos="::,10:,:,:,,",
        gid=bytes(16),
    )
    assert ours.endpoint_token(
        5, PUBLISHER, "/drone/mavros/state", "mavros_msgs/msg/State", "RIHS01_aa", "::,10:,:,:,,"
    ) == endpoint_liveliness_keyexpr(theirs)


def test_attachment_is_33_bytes_and_reads_as_zenoh_ros2_sdk_reads_it():
    from zenoh_ros2_sdk.attachment import Attachment

    raw = attachment.pack(42, 1_700_000_000_000_000_000, bytes(range(16)))
    assert len(raw) == 33 and raw[16] == 16
    theirs = Attachment.from_bytes(raw)
    assert (theirs.sequence_id, theirs.timestamp_ns, theirs.gid) == (
        42,
        1_700_000_000_000_000_000,
        bytes(range(16)),
    )
    back = attachment.unpack(Attachment(7, 8, bytes(16)).to_bytes())
    assert (back.sequence, back.timestamp_ns) == (7, 8)
