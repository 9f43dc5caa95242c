"""Tello video: real H.264 (libx264) in 1460-byte datagrams -> frames; corruption survived."""

from __future__ import annotations

import av
import numpy as np

from dronewrapper_bridge_tello.video import (
    FrameAssembler,
    H264Decoder,
    VideoReceiver,
    starts_access_unit,
)

W, H = 320, 240


def scene(i: int, shade: int = 0) -> np.ndarray:
    """Image ``i`` of a moving gradient (``shade`` sets the red channel: another scene)."""
    img = np.zeros((H, W, 3), np.uint8)
    img[:, :, 1] = (np.arange(W) + 8 * i) % 256
    img[:, :, 2] = shade
    return img


def encode(n: int, shade: int = 0) -> list[bytes]:
    """``n`` access units of a moving gradient, Annex-B, as a Tello-like encoder makes them (a
    key frame every 10)."""
    codec = av.CodecContext.create("libx264", "w")
    codec.width, codec.height, codec.pix_fmt = W, H, "yuv420p"
    codec.framerate = 30
    codec.options = {"tune": "zerolatency", "preset": "ultrafast", "g": "10"}
    units = []
    for i in range(n):
        frame = av.VideoFrame.from_ndarray(scene(i, shade), format="bgr24")
        frame.pts = i
        units += [bytes(p) for p in codec.encode(frame)]
    return units


def datagrams(unit: bytes, chunk: int = 1460) -> list[bytes]:
    return [unit[i : i + chunk] for i in range(0, len(unit), chunk)] or [b""]


def test_frames_split_in_datagrams_are_reassembled_and_decoded():
    units = encode(20)
    asm, dec = FrameAssembler(), H264Decoder()
    out = []
    for unit in units:
        assert len(unit) % 1460 != 0
        for d in datagrams(unit):
            for frame in asm.feed(d):
                out += dec.decode(frame)
    assert len(out) == 20 and dec.counts.corrupt == 0
    img = out[-1].to_ndarray(format="bgr24")
    assert img.shape == (H, W, 3)


def test_corrupt_and_partial_units_are_counted_never_raised():
    units = encode(30)
    rng = np.random.default_rng(3)
    asm, dec = FrameAssembler(), H264Decoder()
    decoded = 0
    for i, unit in enumerate(units):
        if i in (5, 6):
            unit = unit[: len(unit) // 2]  # a partial frame (datagrams lost)
        elif i == 12:
            unit = bytes(rng.integers(0, 256, len(unit), dtype=np.uint8))  # garbage
        elif i == 15:
            unit = b"\x00\x00\x01" + b"\xff" * 40  # a broken NAL unit
        for d in datagrams(unit):
            for frame in asm.feed(d):
                decoded += len(dec.decode(frame))
    assert dec.counts.packets == 30
    assert decoded >= 20  # the stream recovers (at the latest on the next key frame)
    assert dec.counts.corrupt >= 1  # the garbage and the broken NAL unit at least
    assert dec.counts.decoded == decoded


def test_oversized_frames_are_dropped():
    asm = FrameAssembler(chunk=100, max_frame_bytes=1000)
    for _ in range(11):
        assert asm.feed(b"x" * 100) == []
    assert asm.oversized == 1
    assert asm.feed(b"y" * 10) == [b"y" * 10]  # a fresh start after the drop


def test_a_frame_of_a_whole_number_of_chunks_ends_at_the_next_access_unit():
    units = encode(12)
    chunk = 100
    # pad one P frame to a whole number of chunks with trailing zero bytes (allowed after a
    # NAL unit), so none of its datagrams is short
    unit = units[4]
    whole = -(-len(unit) // chunk) * chunk
    units[4] = unit + b"\x00" * (whole - len(unit) + chunk)
    asm, dec = FrameAssembler(chunk=chunk), H264Decoder()
    frames = []
    for unit in units:
        for d in datagrams(unit, chunk):
            frames += asm.feed(d)
    assert frames[4] == units[4]  # not merged with the next frame
    decoded = sum(len(dec.decode(f)) for f in frames)
    assert decoded == 12 and dec.counts.corrupt == 0


def test_decoding_starts_at_the_first_key_frame():
    units = encode(20)
    dec = H264Decoder()
    out = [(i, f) for i, unit in enumerate(units[3:], 3) for f in dec.decode(unit)]
    assert dec.counts.before_keyframe == 7 and dec.counts.corrupt == 0  # 3..9 wait for 10
    first, frame = out[0]
    assert first == 10 and len(out) == 10
    error = np.abs(frame.to_ndarray(format="bgr24").astype(int) - scene(10)).mean()
    assert error < 3.0  # a clean picture, not one predicted from nothing


def test_a_restarted_receiver_waits_for_the_new_streams_key_frame():
    # a real Tello's stream resumes where its encoder is: mid-GOP, P frames first
    old, new = encode(6), encode(12, shade=200)[3:]
    for restart in (True, False):
        receiver = VideoReceiver()
        for unit in old:
            for d in datagrams(unit):
                receiver.feed(d)
        if restart:
            receiver.restart()
        pictures = [p for unit in new for d in datagrams(unit) for p in receiver.feed(d)]
        error = np.abs(pictures[0].to_ndarray(format="bgr24").astype(int) - scene(3, 200))
        if restart:  # nothing until the key frame (image 10), then a clean picture
            assert len(pictures) == 2 and receiver.runs == 2
            assert receiver.counts.before_keyframe == 7
            error = np.abs(pictures[0].to_ndarray(format="bgr24").astype(int) - scene(10, 200))
            assert error.mean() < 3.0
        else:  # the new P frames predicted from the old stream's pictures: not the new scene
            assert error.mean() > 30.0


def test_access_unit_starts():
    units = encode(3)
    assert all(starts_access_unit(u) for u in units)
    assert not starts_access_unit(units[1][100:200])
    assert not starts_access_unit(b"\x00\x00\x01")
