"""Images written straight into Zenoh shared memory: the bytes are exactly MessagePack's."""

from __future__ import annotations

import numpy as np

from dronewrapper.msgs import CompressedImage, Header, Image, PoseStamped, codec
from dronewrapper.runtime.shm_put import MIN_BYTES, ShmWriter, pixel_bytes, split_message

PIXELS = np.arange(480 * 640 * 3, dtype=np.uint32).astype(np.uint8).reshape(480, 640, 3)


def frame(data) -> Image:
    return Image(header=Header(stamp=12.5, frame_id="cam_frontal", seq=7), height=480,
                 width=640, encoding="bgr8", step=1920, data=data)  # fmt: skip


def test_head_plus_pixels_is_the_ordinary_encoding():
    for data in (PIXELS.tobytes(), memoryview(PIXELS).cast("B"), memoryview(PIXELS.tobytes())):
        msg = frame(data)
        head, pixels = split_message(msg)
        assert head + pixels == codec.encode(msg)
        assert len(head) < 200
    jpeg = CompressedImage(header=Header(stamp=1.0), format="jpeg", data=bytes(MIN_BYTES))
    head, pixels = split_message(jpeg)
    assert codec.decode(CompressedImage, head + pixels).data == jpeg.data


def test_bytes_are_not_copied_when_they_need_not_be():
    raw = PIXELS.tobytes()
    assert pixel_bytes(raw) is raw
    assert pixel_bytes(memoryview(raw)) is raw
    assert pixel_bytes(memoryview(raw)[10:]) == raw[10:]  # a part: copied
    assert pixel_bytes(memoryview(PIXELS).cast("B")) == raw


def test_small_or_dataless_messages_go_the_ordinary_way():
    assert split_message(frame(bytes(MIN_BYTES - 1))) is None
    assert split_message(PoseStamped()) is None
    assert ShmWriter().payload(PoseStamped()) is None


def test_payload_in_shared_memory_decodes_to_the_message():
    writer = ShmWriter(pool_bytes=4 * 1024 * 1024)
    msg = frame(memoryview(PIXELS).cast("B"))
    payload = writer.payload(msg)
    assert payload is not None and payload.as_shm() is not None
    got = codec.decode(Image, payload.to_bytes())
    assert got.header == msg.header and (got.width, got.height) == (640, 480)
    assert bytes(got.data) == PIXELS.tobytes()


def test_a_full_pool_falls_back_to_the_ordinary_put():
    writer = ShmWriter(pool_bytes=1024 * 1024)  # room for one 900 kB frame
    held = writer.payload(frame(PIXELS.tobytes()))
    assert held is not None
    assert writer.payload(frame(PIXELS.tobytes())) is None
    assert writer.fallbacks == 1
