"""The PX4 Zenoh bridge's message layer against what real PX4 sent: tokens and samples recorded
from PX4 SIH (``px4_sitl_zenoh``, PX4 main 02e73e3b6f) on the ground, in
tests/data/px4_zenoh/sih_ground.json. Every topic the bridge uses is announced with the bridge's
type and hash, and each recorded payload decodes with the project's CDR codec into values a
landed, disarmed SIH quadrotor has."""

from __future__ import annotations

import json
import math
from pathlib import Path

import pytest

from dronewrapper.msgs.mavros import LANDED_STATE_ON_GROUND
from dronewrapper_bridge_px4_zenoh import telemetry, topics
from dronewrapper_bridge_px4_zenoh.versions import Versions
from dronewrapper_ros2_codec import attachment, cdr
from dronewrapper_ros2_codec.names import parse_endpoint

RECORDING = json.loads(
    (Path(__file__).resolve().parents[1] / "data" / "px4_zenoh" / "sih_ground.json").read_text()
)


def decoded(topic: topics.Px4Topic) -> dict:
    (key,) = [k for k in RECORDING["samples"] if topics.parse_key(k).topic == topic.name]
    payload = bytes.fromhex(RECORDING["samples"][key]["payload"])
    return cdr.decode(topic.type_name, payload)


def test_every_topic_the_bridge_uses_is_announced_in_the_bridges_version():
    versions = Versions()
    for token in RECORDING["tokens"]:
        assert versions.learn(parse_endpoint(token)) is None, token
    assert {t.name for t in topics.TOPICS if versions.usable(t)} == set(topics.BY_NAME)


def test_every_recorded_key_is_the_key_the_bridge_builds():
    versions = Versions()
    for key in RECORDING["samples"]:
        assert versions.key(topics.BY_NAME[topics.parse_key(key).topic]) == key


def test_attachments_are_rmw_zenohs_33_bytes_with_px4s_boot_time():
    for sample in RECORDING["samples"].values():
        meta = attachment.unpack(bytes.fromhex(sample["attachment"]))
        # PX4 writes microseconds since boot where rmw_zenoh has nanoseconds since 1970
        assert 1e6 < meta.timestamp_ns < 600e6 and meta.sequence > 0


def test_recorded_telemetry_is_a_landed_disarmed_quadrotor_at_zurich():
    status = decoded(topics.VEHICLE_STATUS)
    state = telemetry.state(status, connected=True, failsafe="", commander="")
    assert (state.armed, state.mode, state.autopilot) == (False, "AUTO.LOITER", "px4")
    q = telemetry.attitude_enu_flu(decoded(topics.ATTITUDE))
    assert math.isclose(sum(c * c for c in q), 1.0, rel_tol=1e-5)
    position = telemetry.local_position(decoded(topics.LOCAL_POSITION))
    assert position is not None and abs(position[2]) < 1.0
    land = telemetry.extended_state(decoded(topics.LAND_DETECTED), 0.0)
    assert land.landed_state == LANDED_STATE_ON_GROUND
    fix = telemetry.global_position(decoded(topics.GLOBAL_POSITION), 0.0)
    assert fix.latitude == pytest.approx(47.3977, abs=1e-3)
    assert fix.longitude == pytest.approx(8.5456, abs=1e-3)
    battery = telemetry.battery(decoded(topics.BATTERY), 0.0)
    assert 14.0 < battery.voltage < 17.0 and 0.0 <= battery.percentage <= 1.0
