"""Issue 12 items 5-7, 10 and 11 at the bridge, over real UDP MAVLink and a real router:
strict requests change nothing on the wire, duplicated or reordered datagrams are never
republished, a second autopilot with the same system id is flagged and ignored (what changed
while the link was down is reported when it returns: tests/unit/test_bridge_core.py)."""

from __future__ import annotations

import time

import msgspec
import pytest
from autopilot_peer import AutopilotPeer
from bridge_rig import bridge_rig

from dronewrapper.msgs import registry
from dronewrapper.msgs.mavros import ParamSet, ParamValue
from dronewrapper.runtime import ServiceError
from support import wait_for


def raw_call(user, service, fields: dict) -> str:
    """Call with a hand-made payload; returns the error reply's text (fails on an OK reply)."""
    replies = list(
        user.session.get(service.key("drone"), payload=msgspec.msgpack.encode(fields), timeout=10)
    )
    assert len(replies) == 1
    assert replies[0].err is not None, "the request was accepted"
    return replies[0].err.payload.to_bytes().decode("utf-8", "replace")


def test_an_empty_arming_request_arms_nothing(router):
    with bridge_rig(router) as rig:
        t0 = time.monotonic()
        assert "missing required field `value`" in raw_call(rig.user, registry.ARMING, {})
        assert "unknown field `force`" in raw_call(
            rig.user, registry.ARMING, {"value": False, "force": 1}
        )
        assert "missing required field" in raw_call(rig.user, registry.TAKEOFF, {})
        assert "missing required field" in raw_call(rig.user, registry.LAND, {})
        assert "CommandTOL.min_pitch" in raw_call(
            rig.user,
            registry.TAKEOFF,
            {"min_pitch": float("nan"), "yaw": 0.0, "latitude": 0.0, "longitude": 0.0,
             "altitude": 2.0},
        )  # fmt: skip
        time.sleep(0.3)
        assert rig.peer.actuating(t0) == []


def test_param_set_out_of_its_type_is_a_bad_request_and_writes_nothing(router):
    """The wiring of a refused write (every kind of misfit: tests/unit/test_bridge_core.py)."""
    param, value = "COM_RC_IN_MODE", ParamValue(integer=2**31)
    named = "value.integer=2147483648 outside"
    with bridge_rig(router) as rig:
        t0 = time.monotonic()
        with pytest.raises(ServiceError, match="param/set") as err:
            rig.user.call(registry.PARAM_SET, ParamSet(param_id=param, value=value), timeout=10)
        assert named in err.value.message and param in err.value.message
        assert err.value.code == "bad_request"
        assert rig.peer.actuating(t0) == []


def test_duplicated_and_reordered_datagrams_are_never_republished(router):
    with bridge_rig(router, telemetry=False) as rig:
        peer = rig.peer
        t0 = time.monotonic()
        for i in range(40):
            with peer.exclusive():
                peer.north = float(i)
                data = peer.pack(peer.pose())
                peer.send_raw(data)
                peer.send_raw(data)  # 100 % duplication
            time.sleep(0.005)
        wait_for(
            lambda: any(p.pose.position.y == 39.0 for p in rig.poses.values(t0)),
            10,
            what="every pose once",
        )
        time.sleep(0.2)
        ys = [p.pose.position.y for p in rig.poses.values(t0)]
        assert ys == [float(i) for i in range(40)]  # each once, in order
        # reordered: the newer one arrives first, the older one is dropped
        t1 = time.monotonic()
        with peer.exclusive():
            peer.north = 100.0
            older = peer.pack(peer.pose())
            time.sleep(0.01)
            peer.north = 101.0
            newer = peer.pack(peer.pose())
            peer.send_raw(newer)
            peer.send_raw(older)
            time.sleep(0.01)  # a later time_boot_ms: a new sample
            peer.north = 102.0
            peer.send(peer.pose())  # a marker: everything before it has been handled
        wait_for(
            lambda: any(p.pose.position.y == 102.0 for p in rig.poses.values(t1)),
            10,
            what="the marker pose",
        )
        assert [p.pose.position.y for p in rig.poses.values(t1)] == [101.0, 102.0]
        assert rig.bridge.core.freshness.duplicates >= 40 and rig.bridge.core.freshness.stale >= 1


def test_a_second_autopilot_with_the_same_system_id_is_flagged_and_ignored(router):
    with bridge_rig(router) as rig:
        intruder = AutopilotPeer(_port(rig), system=1)
        intruder.north = 500.0
        try:
            flagged = wait_for(lambda: rig.text_containing("second autopilot with system id 1"), 10)
            assert f"{intruder.address[0]}:{intruder.address[1]}" in flagged
            t0 = time.monotonic()
            wait_for(lambda: len(rig.poses.values(t0)) >= 25, 10, what="poses after the flag")
            assert all(p.pose.position.y != 500.0 for p in rig.poses.values())
            heard_before = len(intruder.received)
            time.sleep(1.5)  # >= one of the bridge's 1 Hz heartbeats
            assert len(intruder.received) == heard_before  # replies go to the autopilot only
            assert rig.bridge.core.connected and rig.bridge.core.sources.intruder_messages > 0
        finally:
            intruder.close()


def _port(rig) -> int:
    return int(rig.bridge.config.connection.rsplit(":", 1)[1])
