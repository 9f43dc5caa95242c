"""A serial line's pace and transmit buffer, and MAVLink frames cut from a byte stream (pure)."""

import pytest
from pymavlink.dialects.v20 import common as mavlink

from dronewrapper_sim.serial_line import FrameCutter, SerialLine, frame_length, line_rate


def heartbeat_frame(seq: int = 0, signed: bool = False) -> bytes:
    mav = mavlink.MAVLink(None, srcSystem=1, srcComponent=1)
    mav.seq = seq
    if signed:
        mav.signing.secret_key = bytes(32)
        mav.signing.sign_outgoing = True
    return mavlink.MAVLink_heartbeat_message(2, 12, 0, 0, 3, 3).pack(mav)


def test_a_line_carries_a_tenth_of_its_baud_in_bytes_a_second():
    assert line_rate(57600) == 5760.0
    assert line_rate(921600) == 92160.0
    with pytest.raises(ValueError, match="baud"):
        line_rate(0)


def test_bytes_leave_at_the_line_rate_and_no_faster():
    line = SerialLine(57600, buffer_bytes=100_000, now=0.0)
    assert line.offer(bytes(5760 * 2), 0.0)
    assert len(line.take(0.5)) == 2880  # half a second: half of 5760
    assert len(line.take(1.0)) == 2880
    assert line.take(1.0) == b""  # no time passed, nothing more
    assert len(line.take(3.0)) == 5760  # what was left, not more
    assert line.carried == 11520


def test_an_idle_line_saves_up_no_bytes():
    line = SerialLine(57600, now=0.0)
    line.take(100.0)  # idle for 100 s
    line.offer(bytes(500), 100.0)
    assert len(line.take(100.0)) <= 1  # not 576 000 bytes of credit
    assert line.next_byte_in(100.0) == pytest.approx(1 / 5760, abs=1 / 5760)


def test_a_frame_that_does_not_fit_the_buffer_is_dropped_whole():
    line = SerialLine(57600, buffer_bytes=100, now=0.0)
    assert line.offer(bytes(60), 0.0)
    assert not line.offer(bytes(60), 0.0)  # 120 > 100: dropped, not cut
    assert (line.dropped_frames, line.dropped_bytes, line.queued) == (1, 60, 60)
    line.take(0.01)  # 57.6 bytes left: room again
    assert line.offer(bytes(60), 0.01)


def test_frame_lengths_of_mavlink_1_2_and_signed_2():
    plain, signed = heartbeat_frame(), heartbeat_frame(signed=True)
    assert frame_length(plain[:3]) == len(plain) == 21
    assert frame_length(signed[:3]) == len(signed) == 34
    assert frame_length(bytes([0xFE, 9, 0])) == 17
    assert frame_length(b"\x00\x01\x02") is None
    assert frame_length(plain[:2]) is None


def test_frames_are_cut_whole_from_any_chunking_and_garbage_is_skipped():
    frames = [heartbeat_frame(i, signed=i % 2 == 1) for i in range(5)]
    stream = b"\x00junk" + b"".join(frames)
    for chunk in (1, 7, 64, len(stream)):
        cutter = FrameCutter()
        out = []
        for i in range(0, len(stream), chunk):
            out += cutter.feed(stream[i : i + chunk])
        assert out == frames
        assert cutter.skipped == 5


def test_each_frame_waits_behind_those_queued_before_it():
    line = SerialLine(57600, buffer_bytes=1024, now=0.0)
    for size in (576, 288, 144):  # 0.1 s, 0.05 s and 0.025 s of the line
        assert line.offer(bytes(size), 0.0)
    line.take(0.05)  # 288 bytes: none whole yet
    assert list(line.delays) == []
    line.take(0.1)  # the first frame's 576 bytes are over
    line.take(0.2)  # and the two behind it
    assert list(line.delays) == pytest.approx([0.1, 0.2, 0.2])
