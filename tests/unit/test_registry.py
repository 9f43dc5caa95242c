"""The registry walks itself: unique keys, valid key expressions, every type round-trips."""

from __future__ import annotations

import itertools

import msgspec
import pytest
import zenoh
from msg_samples import sample

from dronewrapper.msgs import codec, registry
from dronewrapper.msgs.registry import LIVELINESS, SERVICES, TOPICS

ALL_TEMPLATES = [*TOPICS.values(), *SERVICES.values(), *LIVELINESS.values()]
PARTS = {"camera": "cam_frontal", "name": "target", "service": "bridge_mavlink"}


def concrete(entry) -> str:
    return entry.key("drone7", **{f: PARTS[f] for f in entry.fields if f != "ns"})


def test_templates_are_unique():
    templates = [e.template for e in ALL_TEMPLATES]
    assert len(templates) == len(set(templates))


@pytest.mark.parametrize("entry", ALL_TEMPLATES, ids=lambda e: e.template)
def test_keys_are_valid_key_expressions(entry):
    key = concrete(entry)
    assert str(zenoh.KeyExpr(key)) == key
    assert zenoh.KeyExpr(entry.wildcard()).intersects(zenoh.KeyExpr(key))
    assert "*" not in key and "$" not in key and not key.startswith("/")


@pytest.mark.parametrize("entry", ALL_TEMPLATES, ids=lambda e: e.template)
def test_key_match_round_trip(entry):
    key = concrete(entry)
    parts = entry.match(key)
    assert parts is not None
    assert entry.key(**parts) == key


def test_no_concrete_key_belongs_to_two_entries():
    for a, b in itertools.permutations(ALL_TEMPLATES, 2):
        assert b.match(concrete(a)) is None, (a.template, b.template)


@pytest.mark.parametrize("topic", TOPICS.values(), ids=lambda t: t.template)
def test_topic_metadata(topic):
    assert isinstance(topic.type, type) and issubclass(topic.type, msgspec.Struct)
    assert topic.rate_hz >= 0
    assert topic.publishers
    assert registry.topic_for_key(concrete(topic)) is topic


@pytest.mark.parametrize("service", SERVICES.values(), ids=lambda s: s.template)
def test_service_metadata(service):
    assert issubclass(service.request, msgspec.Struct)
    assert issubclass(service.reply, msgspec.Struct)
    assert service.request is not service.reply
    assert registry.service_for_key(concrete(service)) is service


MESSAGE_TYPES = sorted(
    {t.type for t in TOPICS.values()}
    | {s.request for s in SERVICES.values()}
    | {s.reply for s in SERVICES.values()},
    key=lambda t: t.__name__,
)


def has_all_defaults(msg_type) -> bool:
    return all(f.required is False for f in msgspec.structs.fields(msg_type))


@pytest.mark.parametrize("msg_type", MESSAGE_TYPES, ids=lambda t: t.__name__)
def test_every_type_decodes_what_it_encodes(msg_type):
    first = msg_type() if has_all_defaults(msg_type) else sample(msg_type, seed=0)
    for msg in (first, sample(msg_type, seed=1), sample(msg_type, seed=2)):
        data = codec.encode(msg)
        decoded = codec.decode(msg_type, data)
        assert type(decoded) is msg_type
        assert codec.encode(decoded) == data  # byte-exact (NaN defaults compare unequal)
        # self-describing: a generic MessagePack reader sees the field names
        assert set(msgspec.msgpack.decode(data)) == set(msg_type.__struct_fields__)


@pytest.mark.parametrize("msg_type", MESSAGE_TYPES, ids=lambda t: t.__name__)
def test_every_type_rejects_garbage(msg_type):
    for garbage in (b"", b"\xc1", codec.encode([1, 2, 3]), codec.encode("text")):
        with pytest.raises((msgspec.DecodeError, msgspec.ValidationError)):
            codec.decode(msg_type, garbage)


def test_wrong_field_type_is_rejected_with_the_field_named():
    data = msgspec.msgpack.encode({"header": {"stamp": "noon"}})
    with pytest.raises(msgspec.ValidationError, match=r"\$\.header\.stamp"):
        codec.decode(registry.LOCAL_POSE.type, data)


@pytest.mark.parametrize("bad", ["", "a/b", "*", "**", "x y", "$"])
def test_key_fields_must_be_one_chunk(bad):
    with pytest.raises(ValueError, match="one chunk"):
        registry.LOCAL_POSE.key(bad)


def test_missing_key_field_is_named():
    with pytest.raises(ValueError, match="camera"):
        registry.IMAGE_RAW.key("drone")


def test_known_keys_match_design():
    assert registry.STATE.key("drone") == "drone/mavros/state"
    assert registry.SETPOINT_RAW_LOCAL.key("d2") == "d2/mavros/setpoint_raw/local"
    assert registry.IMAGE_COMPRESSED.key("drone", camera="cam_ventral") == (
        "drone/cam_ventral/image_raw/compressed"
    )
    assert registry.SIM_OBJECT_CMD_VEL.key(name="target") == "sim/objects/target/cmd_vel"
    assert registry.PARAM_SET.key("drone") == "drone/mavros/param/set"
    assert registry.ALIVE.key("drone", service="sim") == "drone/alive/sim"
