"""Images written straight into Zenoh shared memory: the bytes are exactly MessagePack's."""

from __future__ import annotations

import threading

import numpy as np
import pytest

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


@pytest.mark.parametrize("width, height", [(640, 480), (960, 720), (1280, 720)])
def test_frames_that_grow_by_a_byte_still_go_by_shared_memory(width, height):
    """A camera's frames grow by one byte of header as ``seq`` passes 127, 255 and 65535; the
    pool then holds only reclaimed chunks one byte too small, and each such frame must still
    go by shared memory (no silent fallback; the Tello's 960x720 frames did fall back)."""
    writer = ShmWriter(pool_bytes=16 * 1024 * 1024)
    pixels = bytes(width * height * 3)
    sizes = set()
    for seq in (*range(0, 300, 1), 65530, 65535, 65536, 65537, 2**32 - 1, 2**32):
        msg = Image(header=Header(stamp=12.5, frame_id="cam_frontal", seq=seq), height=height,
                    width=width, encoding="bgr8", step=width * 3, data=pixels)  # fmt: skip
        payload = writer.payload(msg)
        assert payload is not None, f"frame {seq} fell back from shared memory"
        sizes.add(len(split_message(msg)[0]))
        del payload  # sent: the reader released it
    assert len(sizes) >= 4  # the header did grow
    assert writer.fallbacks == 0


def test_frames_of_several_sizes_share_one_pool():
    writer = ShmWriter(pool_bytes=8 * 1024 * 1024)
    for i in range(60):
        side = 256 + 32 * (i % 5)
        data = bytes(side * side * 3)
        msg = Image(header=Header(stamp=1.0, seq=i), height=side, width=side, step=side * 3,
                    data=data)  # fmt: skip
        assert writer.payload(msg) is not None, f"frame {i} ({side}x{side}) fell back"
    assert writer.fallbacks == 0


def test_a_blocking_put_waits_for_a_reader_to_release_a_buffer():
    writer = ShmWriter(pool_bytes=1024 * 1024)  # room for one 900 kB frame
    held = [writer.payload(frame(PIXELS.tobytes()))]
    waiting = threading.Event()
    release = threading.Thread(target=lambda: (waiting.wait(5), held.clear()))
    release.start()
    waiting.set()
    assert writer.payload(frame(PIXELS.tobytes()), wait_s=5.0) is not None
    release.join(5)
    assert writer.fallbacks == 0
    held.append(writer.payload(frame(PIXELS.tobytes())))
    assert writer.payload(frame(PIXELS.tobytes()), wait_s=0.01) is None  # nobody releases
    assert writer.fallbacks == 1
