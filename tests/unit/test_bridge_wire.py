"""The bridge cuts MAVLink bytes into frames by their headers and sorts them by id before any
decoding (dronewrapper_bridge_mavlink.wire), on frames pymavlink itself encodes: MAVLink 1,
MAVLink 2, MAVLink 2 signed, ids above 255, and a byte stream cut anywhere."""

from __future__ import annotations

import random

from pymavlink.dialects.v20 import common as mavlink

from dronewrapper_bridge_mavlink.core import BridgeCore
from dronewrapper_bridge_mavlink.wire import (
    FrameCutter,
    SequenceGaps,
    cut_datagram,
    message_id,
    wanted_ids,
)

KEY = bytes(range(32))


def encoder(*, signed: bool = False) -> mavlink.MAVLink:
    mav = mavlink.MAVLink(None, srcSystem=1, srcComponent=1)
    if signed:
        mav.signing.secret_key = KEY
        mav.signing.sign_outgoing = True
        mav.signing.link_id = 3
        mav.signing.timestamp = 1_000_000
    return mav


def frames_of(mav: mavlink.MAVLink, *, v1: bool = False) -> list[bytes]:
    """A PX4-like mix: what the bridge reads and what it never reads."""
    return [
        bytes(msg.pack(mav, force_mavlink1=v1))
        for msg in (
            mavlink.MAVLink_heartbeat_message(2, 12, 0x81, 0, 4, 3),
            mavlink.MAVLink_local_position_ned_message(1000, 1.0, 2.0, -3.0, 0.1, 0.2, 0.3),
            mavlink.MAVLink_altitude_message(1000, 1, 2, 3, 4, 5, 6),
            mavlink.MAVLink_vfr_hud_message(1.0, 2.0, 90, 50, 3.0, 0.1),
            mavlink.MAVLink_statustext_message(6, b"hello"),
            mavlink.MAVLink_attitude_quaternion_message(1000, 1, 0, 0, 0, 0, 0, 0),
        )
    ]


def ids(frames) -> list[int]:
    return [frame.msg_id for frame in frames]


EXPECTED = [
    mavlink.MAVLINK_MSG_ID_HEARTBEAT,
    mavlink.MAVLINK_MSG_ID_LOCAL_POSITION_NED,
    mavlink.MAVLINK_MSG_ID_ALTITUDE,
    mavlink.MAVLINK_MSG_ID_VFR_HUD,
    mavlink.MAVLINK_MSG_ID_STATUSTEXT,
    mavlink.MAVLINK_MSG_ID_ATTITUDE_QUATERNION,
]


def test_a_datagram_of_mavlink2_frames_is_cut_into_each_frame_with_its_id() -> None:
    raw = frames_of(encoder())
    frames = cut_datagram(b"".join(raw), FrameCutter())
    assert ids(frames) == EXPECTED
    assert [f.data for f in frames] == raw  # each frame exactly as it came


def test_mavlink1_frames_are_cut_too() -> None:
    raw = frames_of(encoder(), v1=True)
    assert all(frame[0] == 0xFE for frame in raw)
    assert ids(cut_datagram(b"".join(raw), FrameCutter())) == EXPECTED


def test_signed_frames_keep_their_13_signature_bytes_and_still_verify() -> None:
    raw = frames_of(encoder(signed=True))
    assert all(frame[2] & 0x01 for frame in raw)  # pymavlink marked them signed
    frames = cut_datagram(b"".join(raw), FrameCutter())
    assert ids(frames) == EXPECTED
    receiver = mavlink.MAVLink(None)
    receiver.signing.secret_key = KEY
    for frame in frames:  # the cut frame decodes with its signature checked
        msg = receiver.decode(bytearray(frame.data))
        assert msg._signed and msg.get_msgId() == frame.msg_id


def test_a_message_id_above_255_is_read_from_the_id_bytes_after_the_first() -> None:
    msg = mavlink.MAVLink_gimbal_manager_status_message(1000, 0, 1, 255, 190, 0, 0)
    frame = bytes(msg.pack(encoder()))
    assert mavlink.MAVLINK_MSG_ID_GIMBAL_MANAGER_STATUS == 281  # 0x19 0x01: two id bytes
    assert message_id(frame) == 281
    assert message_id(frame[:7] + bytes([0x2C, 0x01, 0x02]) + frame[10:]) == 0x02012C


def test_a_stream_cut_at_every_byte_gives_the_same_frames_in_order() -> None:
    raw = b"".join(frames_of(encoder(signed=True)) + frames_of(encoder(), v1=True))
    for cut in range(1, len(raw)):
        cutter = FrameCutter()
        frames = cutter.feed(raw[:cut]) + cutter.feed(raw[cut:])
        assert ids(frames) == EXPECTED * 2, cut
        assert cutter.pending == 0 and cutter.skipped == 0


def test_a_stream_in_random_small_reads_loses_nothing() -> None:
    raw = b"".join(frames_of(encoder()) * 20)
    rng = random.Random(7)
    cutter, frames, at = FrameCutter(), [], 0
    while at < len(raw):
        step = rng.randint(1, 40)
        frames += cutter.feed(raw[at : at + step])
        at += step
    assert ids(frames) == EXPECTED * 20


def test_noise_before_a_frame_is_skipped_and_counted() -> None:
    raw = frames_of(encoder())
    cutter = FrameCutter()
    frames = cutter.feed(b"\x00\x01garbage" + raw[0]) + cutter.feed(b"\x55" + raw[1])
    assert ids(frames) == EXPECTED[:2]
    assert cutter.skipped == len(b"\x00\x01garbage") + 1


def test_a_truncated_datagram_yields_its_whole_frames_and_counts_the_rest() -> None:
    raw = frames_of(encoder())
    cutter = FrameCutter()
    frames = cut_datagram(raw[0] + raw[1][:7], cutter)
    assert ids(frames) == EXPECTED[:1]
    assert cutter.skipped == 7
    assert ids(cut_datagram(raw[2], cutter)) == EXPECTED[2:3]  # no carry-over from before


def test_the_bridge_decodes_what_it_reads_and_drops_what_it_never_reads() -> None:
    wanted = wanted_ids(BridgeCore.read_messages(), mavlink)
    for name in ("HEARTBEAT", "LOCAL_POSITION_NED", "ATTITUDE_QUATERNION", "COMMAND_ACK"):
        assert getattr(mavlink, f"MAVLINK_MSG_ID_{name}") in wanted
    for name in ("ALTITUDE", "VFR_HUD", "POSITION_TARGET_LOCAL_NED"):
        assert getattr(mavlink, f"MAVLINK_MSG_ID_{name}") not in wanted  # streams.py stops them
    assert wanted_ids(["NO_SUCH_MESSAGE", "HEARTBEAT"], mavlink) == {0}


def test_gaps_in_each_senders_sequence_count_the_frames_lost_read_or_not() -> None:
    mav, frames = encoder(), []
    for seq in range(12):  # one sender, seq 0..11
        mav.seq = seq
        frames.append(frames_of(mav)[seq % 6])
    gaps = SequenceGaps()
    kept = frames[:3] + frames[5:9] + frames[10:]  # 2 + 1 lost
    assert [gaps.add(f) for f in kept] == [0, 0, 0, 2, 0, 0, 0, 1, 0]
    other = mavlink.MAVLink(None, srcSystem=7, srcComponent=1)
    assert gaps.add(bytes(frames_of(other)[0])) == 0  # another sender starts its own count
    wrapped = bytearray(frames[0])
    wrapped[4] = 1  # after seq 11 of sender (1, 1): 1 means 245 lost (mod 256)
    assert gaps.add(wrapped) == 245
    assert gaps.lost == 248
