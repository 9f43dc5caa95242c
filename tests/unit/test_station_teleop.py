"""The teleop dead-man and the latest-only video slot (time injected, no sockets)."""

from __future__ import annotations

import json

from dronewrapper.msgs.sensor import CompressedImage
from dronewrapper.msgs.std import Header
from dronewrapper_ground_station.frames import pack
from dronewrapper_ground_station.teleop import DeadMan


def test_deadman_expires_once_after_the_timeout() -> None:
    deadman = DeadMan(0.5)
    assert not deadman.expired(100.0)
    deadman.renew(100.0, owner="page")
    assert deadman.active
    assert not deadman.expired(100.5)
    assert deadman.expired(100.51)
    assert not deadman.active and not deadman.expired(101.0)


def test_renewals_keep_it_alive() -> None:
    deadman = DeadMan(0.5)
    for k in range(20):
        deadman.renew(k * 0.05, owner="page")
        assert not deadman.expired(k * 0.05 + 0.04)


def test_release_says_whether_to_stop() -> None:
    deadman = DeadMan(0.5)
    assert deadman.release() is False
    deadman.renew(1.0, owner="page")
    assert deadman.owner == "page"
    assert deadman.release() is True
    assert deadman.owner is None and not deadman.expired(10.0)


def test_pack_is_length_header_then_jpeg() -> None:
    frame = CompressedImage(header=Header(stamp=12.5), format="jpeg", data=b"\xff\xd8jpeg")
    header = json.dumps({"seq": 1}).encode()
    data = pack(frame, header)
    n = int.from_bytes(data[:4], "big")
    assert json.loads(data[4 : 4 + n]) == {"seq": 1}
    assert data[4 + n :] == b"\xff\xd8jpeg"
