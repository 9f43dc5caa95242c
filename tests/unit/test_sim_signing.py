"""The simulated autopilot's signing policy (PX4's rules for SETUP_SIGNING)."""

from __future__ import annotations

import pytest
from pymavlink.dialects.v20 import common as mavlink

from dronewrapper_sim.px4.signing import SigningPolicy

KEY_A, KEY_B = bytes(range(32)), bytes(range(1, 33))


def test_first_key_unsigned_then_only_signed_never_armed():
    policy = SigningPolicy()
    assert not policy.setup_signing(KEY_A, signed=False, armed=True).accepted
    first = policy.setup_signing(KEY_A, signed=False, armed=False)
    assert first.accepted and first.key == KEY_A and first.reason == "key provisioned"
    assert not policy.setup_signing(KEY_B, signed=False, armed=False).accepted
    assert not policy.setup_signing(KEY_B, signed=True, armed=True).accepted
    assert policy.setup_signing(KEY_B, signed=True, armed=False).key == KEY_B
    off = policy.setup_signing(bytes(32), signed=True, armed=False)
    assert off.accepted and off.key is None and policy.key is None
    assert not policy.setup_signing(b"short", signed=False, armed=False).accepted


def test_only_heartbeat_and_radio_status_may_stay_unsigned():
    policy = SigningPolicy(KEY_A)
    assert policy.allow_unsigned(mavlink.MAVLINK_MSG_ID_HEARTBEAT) and policy.allow_unsigned(
        mavlink.MAVLINK_MSG_ID_RADIO_STATUS
    )
    assert not policy.allow_unsigned(76)  # COMMAND_LONG
    assert not policy.allow_unsigned(256)  # SETUP_SIGNING once a key is set
    with pytest.raises(ValueError, match="32 bytes"):
        SigningPolicy(b"short")
