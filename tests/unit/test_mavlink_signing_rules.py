"""MAVLink 2 signing's rules, each held on real signed frames (pymavlink packs them).

:func:`verify_signed_frame` (the MAC, the replay check on a stream's timestamps, the window
for a new stream's first timestamp, the timestamp moving only on a valid frame) and the bridge
link's parser as ``MavLink.open`` sets it up (that check wired in as ``check_signature``, and
only RADIO_STATUS passing unsigned). The link is opened on a telemetry-log file, so its parser
is the real one and no socket is involved.
"""

from __future__ import annotations

import os

import pytest
from mavlink_signer import encoder

os.environ.setdefault("MAVLINK20", "1")

from pymavlink.dialects.v20 import common as mavlink

from dronewrapper.security.mavlink_signing import REPLAY_WINDOW, verify_signed_frame
from dronewrapper_bridge_mavlink.link import UNSIGNED_ALLOWED, MavLink

KEY = bytes(range(32))
OTHER_KEY = bytes(32 - i for i in range(32))
T0 = 600_000_000_000  # 10 µs units since 2015: about 2017, our clock before any frame


def signer(key: bytes = KEY, timestamp: int = T0, link_id: int = 0, system: int = 1):
    """A pymavlink encoder that signs what it packs with ``key`` from ``timestamp`` on."""
    return encoder(key, timestamp, system=system, link_id=link_id)


def heartbeat(mav) -> bytes:
    return mavlink.MAVLink_heartbeat_message(2, 12, 0, 0, 4, 3).pack(mav)


def receiver(timestamp: int = T0):
    """Our side's signing state: the key, our clock, no stream heard yet."""
    mav = mavlink.MAVLink(None)
    mav.signing.secret_key = KEY
    mav.signing.timestamp = timestamp
    return mav.signing


def verify(signing, frame: bytes, system: int = 1) -> bool:
    return verify_signed_frame(signing, frame, system, 1)


def forged(frame: bytes) -> bytes:
    """``frame`` with the last byte of its MAC changed."""
    return frame[:-1] + bytes([frame[-1] ^ 0x01])


# ---- verify_signed_frame


def test_a_genuine_frame_passes_and_moves_the_streams_timestamp():
    signing = receiver()
    frame = heartbeat(signer(timestamp=T0 + 10))
    assert verify(signing, frame)
    assert signing.stream_timestamps[(0, 1, 1)] == T0 + 10
    assert signing.timestamp == T0 + 10


def test_a_wrong_mac_is_refused():
    signing = receiver()
    assert not verify(signing, forged(heartbeat(signer())))
    assert not verify(signing, heartbeat(signer(key=OTHER_KEY)))  # another key's MAC
    assert signing.stream_timestamps == {}


def test_a_replayed_or_older_frame_of_a_stream_is_refused():
    signing = receiver()
    mav = signer(timestamp=T0 + 100)
    first, second = heartbeat(mav), heartbeat(mav)
    assert verify(signing, first)
    assert not verify(signing, first)  # the same frame again
    assert verify(signing, second)
    assert not verify(signing, heartbeat(signer(timestamp=T0 + 50)))  # older than the last
    assert verify(signing, heartbeat(signer(timestamp=T0 + 50, system=2)), system=2)  # own


def test_a_new_streams_first_timestamp_must_be_within_a_minute_of_ours():
    signing = receiver(timestamp=T0 + 2 * REPLAY_WINDOW)
    too_old = heartbeat(signer(timestamp=T0 + REPLAY_WINDOW - 1))
    assert not verify(signing, too_old)
    assert (0, 1, 1) not in signing.stream_timestamps
    assert verify(signing, heartbeat(signer(timestamp=T0 + REPLAY_WINDOW + 1)))


def test_a_forged_frame_from_the_future_does_not_block_the_genuine_stream():
    signing = receiver()
    assert not verify(signing, forged(heartbeat(signer(timestamp=T0 + 10**9))))
    assert verify(signing, heartbeat(signer(timestamp=T0 + 5)))


# ---- the bridge's link, as MavLink.open sets its parser up


@pytest.fixture
def link(tmp_path):
    key_file = tmp_path / "mavlink.key"
    key_file.write_text(KEY.hex())
    log = tmp_path / "empty.tlog"
    log.write_bytes(b"")
    link = MavLink(str(log), signing_key_file=str(key_file))
    link.open()
    link.mav.signing.timestamp = T0  # our clock, as the frames below were made
    yield link
    link.close()


def accepted(link: MavLink, frame: bytes) -> list[str]:
    """The types of the messages the link's parser delivers from ``frame``."""
    try:
        msgs = link.mav.parse_buffer(frame) or []
    except mavlink.MAVError:
        return []
    return [m.get_type() for m in msgs if m.get_type() != "BAD_DATA"]


def test_the_link_takes_genuine_frames_and_drops_forged_ones(link):
    assert accepted(link, heartbeat(signer(timestamp=T0 + 1))) == ["HEARTBEAT"]
    assert accepted(link, forged(heartbeat(signer(timestamp=T0 + 2)))) == []
    assert link.rejected == 1


def test_the_links_check_keeps_a_forged_future_frame_from_blocking_the_stream(link):
    # pymavlink's own check records the timestamp before the MAC: the genuine frame after
    # this forged one would look replayed
    assert accepted(link, forged(heartbeat(signer(timestamp=T0 + 10**9)))) == []
    assert accepted(link, heartbeat(signer(timestamp=T0 + 5))) == ["HEARTBEAT"]


def test_only_radio_status_passes_the_link_unsigned(link):
    plain = mavlink.MAVLink(None, srcSystem=1, srcComponent=1)
    radio = mavlink.MAVLink_radio_status_message(200, 190, 80, 50, 40, 0, 0).pack(plain)
    assert accepted(link, radio) == ["RADIO_STATUS"]
    assert accepted(link, heartbeat(plain)) == []
    ack = mavlink.MAVLink_command_ack_message(400, 0, 0, 0, 255, 190).pack(plain)
    assert accepted(link, ack) == []
    assert link.rejected == 2
    assert frozenset({mavlink.MAVLINK_MSG_ID_RADIO_STATUS}) == UNSIGNED_ALLOWED
