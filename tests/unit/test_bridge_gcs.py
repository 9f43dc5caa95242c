"""Ground-station forwarding, pure parts: URLs, batching for Zenoh."""

import pytest

from dronewrapper.mavlink_forward import parse_udp
from dronewrapper_bridge_mavlink.gcs import BATCH_S, GcsForwarder, is_loopback, parse_gcs_url


def test_gcs_url_forms():
    assert parse_gcs_url("udp:127.0.0.1:14550") == ("127.0.0.1", 14550)
    for bad in ("tcp:127.0.0.1:5760", "udp:127.0.0.1", "udp::14550", "udp:h:99999", "14550"):
        with pytest.raises(ValueError, match="udp:HOST:PORT"):
            parse_gcs_url(bad)
    assert parse_udp("127.0.0.1:14550") == ("127.0.0.1", 14550)
    with pytest.raises(ValueError, match="HOST:PORT"):
        parse_udp("14550")


def test_loopback():
    assert is_loopback("127.0.0.1") and is_loopback("localhost") and is_loopback("::1")
    assert not is_loopback("192.168.1.20") and not is_loopback("qgc.local")


def test_frames_for_zenoh_are_batched_and_frames_back_go_to_the_autopilot():
    published, written = [], []
    forwarder = GcsForwarder(written.append, None, published.append)
    forwarder.from_autopilot(b"\xfd\x01")
    forwarder.from_autopilot(b"\xfd\x02")
    forwarder.flush(0.0)  # too young: a batch is at most BATCH_S old, not sent at once
    assert published == []
    forwarder._batch_since = 0.0
    forwarder.flush(BATCH_S)
    assert [batch.frames for batch in published] == [[b"\xfd\x01", b"\xfd\x02"]]
    forwarder.flush(10.0)  # nothing new: nothing sent
    assert len(published) == 1
    from dronewrapper.msgs.mavlink import MavlinkFrames

    forwarder.from_zenoh(MavlinkFrames(frames=[b"a", b"b"]))
    assert written == [b"a", b"b"] and forwarder.from_gcs == 2
