"""MAVLink 2 message signing as PX4 applies it (the policy; the bytes are pymavlink's).

Before a key is provisioned nothing is checked. Once one is (the key file on the SD card, here
``signing_key_file``, or a SETUP_SIGNING message), every incoming message must carry a valid
signature whose timestamp is newer than the last one of its stream (link id, system,
component) and at most a minute older than ours; others are dropped and counted. Exceptions,
as in PX4: HEARTBEAT and RADIO_STATUS may stay unsigned, and SETUP_SIGNING is accepted
unsigned only while no key is set (the first provisioning, over USB in real life). A key
change is refused while armed; an all-zero key in a signed SETUP_SIGNING turns signing off.
"""

from __future__ import annotations

from dataclasses import dataclass

from pymavlink.dialects.v20 import common as mavlink

UNSIGNED_ALWAYS = frozenset({mavlink.MAVLINK_MSG_ID_HEARTBEAT, mavlink.MAVLINK_MSG_ID_RADIO_STATUS})
KEY_BYTES = 32


@dataclass(frozen=True)
class SetupDecision:
    """What a SETUP_SIGNING did: ``accepted``, the key in force after it, and why."""

    accepted: bool
    key: bytes | None
    reason: str


class SigningPolicy:
    """The autopilot's signing key and what may pass without a valid signature."""

    def __init__(self, key: bytes | None = None) -> None:
        if key is not None and len(key) != KEY_BYTES:
            raise ValueError(f"a MAVLink signing key is {KEY_BYTES} bytes, got {len(key)}")
        self.key = key

    def allow_unsigned(self, msg_id: int) -> bool:
        """Whether a message without a valid signature may pass (a key is set)."""
        return msg_id in UNSIGNED_ALWAYS

    def setup_signing(self, new_key: bytes, *, signed: bool, armed: bool) -> SetupDecision:
        """Apply a SETUP_SIGNING carrying ``new_key`` (``signed``: it had a valid signature)."""
        if armed:
            return SetupDecision(False, self.key, "refused while armed")
        if len(new_key) != KEY_BYTES:
            return SetupDecision(False, self.key, f"key must be {KEY_BYTES} bytes")
        if self.key is not None and not signed:
            return SetupDecision(False, self.key, "a key is set: SETUP_SIGNING must be signed")
        if not any(new_key):
            self.key = None
            return SetupDecision(True, None, "signing disabled")
        first = self.key is None
        self.key = bytes(new_key)
        return SetupDecision(True, self.key, "key provisioned" if first else "key changed")
