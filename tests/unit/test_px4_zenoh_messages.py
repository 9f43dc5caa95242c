"""The PX4 Zenoh bridge's px4_msgs definitions against rosbags (an independent implementation):
every type's RIHS01 hash and CDR bytes computed from the same field lists. Against the firmware
itself: tests/unit/test_px4_zenoh_firmware.py."""

from __future__ import annotations

import math

import numpy as np
import pytest
from rosbags.typesys import Stores, get_types_from_msg, get_typestore

from dronewrapper_bridge_px4_zenoh import px4_msgs
from dronewrapper_ros2_codec import cdr, interfaces
from dronewrapper_ros2_codec.typehash import type_hash


@pytest.fixture(scope="module")
def store():
    typestore = get_typestore(Stores.ROS2_JAZZY)
    types = {}
    for short, text in px4_msgs.FIELDS.items():
        types.update(get_types_from_msg(text, px4_msgs.full_name(short)))
    typestore.register(types)
    return typestore


@pytest.mark.parametrize("short", sorted(px4_msgs.FIELDS))
def test_hash_equals_rosbags(store, short):
    name = px4_msgs.full_name(short)
    assert type_hash(name) == store.hash_rihs01(name)


def _sample(name: str) -> dict:
    """A value with every field set to something other than zero (deterministic)."""
    value = {}
    for k, f in enumerate(interfaces.message(name).fields):
        if f.base == "bool":
            one = k % 2 == 0
        elif f.base.startswith("float"):
            one = 0.25 * (k + 1)
        else:
            one = (k % 7) + 1
        value[f.name] = [one] * f.size if f.kind == interfaces.ARRAY else one
    return value


_NUMPY = {"float32": np.float32, "float64": np.float64, "uint8": np.uint8}


@pytest.mark.parametrize("short", sorted(px4_msgs.FIELDS))
def test_cdr_bytes_equal_rosbags(store, short):
    name = px4_msgs.full_name(short)
    value = _sample(name)
    theirs = {}
    for f in interfaces.message(name).fields:
        v = value[f.name]
        theirs[f.name] = np.array(v, dtype=_NUMPY[f.base]) if f.kind == interfaces.ARRAY else v
    msg = store.types[name](**theirs)
    ours = cdr.encode(name, value)
    assert ours == bytes(store.serialize_cdr(msg, name))
    back = cdr.decode(name, ours)
    for key, v in value.items():
        if isinstance(v, float):
            assert math.isclose(back[key], v, rel_tol=1e-6)


def test_a_firmware_definition_cannot_be_redefined_with_other_fields():
    name = px4_msgs.full_name("VehicleAttitude")
    interfaces.define({name: px4_msgs.FIELDS["VehicleAttitude"]})  # the same text: allowed
    with pytest.raises(ValueError, match="already defined"):
        interfaces.define({name: "uint64 timestamp\n"})
