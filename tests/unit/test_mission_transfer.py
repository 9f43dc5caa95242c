"""The MAVLink mission protocol's ground side (mission_transfer.py), on real pymavlink messages:
lost items, duplicate requests, timeouts, a refused item, downloads and clears."""

from __future__ import annotations

import math

from pymavlink.dialects.v20 import common as mavlink

from dronewrapper_bridge_mavlink.mission_transfer import (
    FENCE,
    MISSION,
    Clear,
    Download,
    Item,
    Upload,
)
from dronewrapper_bridge_mavlink.outgoing import (
    MissionCount,
    MissionItemInt,
    MissionRequestInt,
    Send,
    encode,
)

TARGET = (1, 1)


def items(n: int) -> list[Item]:
    return [Item(frame=3, command=16, x=473977000 + i, y=85456000, z=10.0) for i in range(n)]


def request(seq: int, mission_type: int = MISSION) -> mavlink.MAVLink_message:
    return mavlink.MAVLink_mission_request_int_message(255, 191, seq, mission_type)


def ack(result: int = mavlink.MAV_MISSION_ACCEPTED, mission_type: int = MISSION):
    return mavlink.MAVLink_mission_ack_message(255, 191, result, mission_type)


def names(sends: list[Send]) -> list[str]:
    """The MAVLink names of the messages (``mission_count`` ...), as they go on the wire."""
    return [encode(message).get_type().lower() for message in sends]


def item_seqs(sends: list[Send]) -> list[int]:
    return [message.seq for message in sends if isinstance(message, MissionItemInt)]


def item_seqs_asked(sends: list[Send]) -> list[int]:
    return [message.seq for message in sends if isinstance(message, MissionRequestInt)]


def test_upload_in_order_sends_count_then_each_item_asked_and_ends_on_accept():
    up = Upload(items(3), TARGET, 0.0)
    first = up.due(0.0)
    assert names(first) == ["mission_count"]
    assert first[0] == MissionCount(1, 1, 3, MISSION)
    for seq in range(3):
        up.on_message(request(seq), 0.1 * seq)
        assert item_seqs(up.due(0.1 * seq)) == [seq]
    up.on_message(ack(), 0.5)
    assert up.done and up.error == "" and up.transferred == 3


def test_upload_item_fields_are_those_of_mission_item_int():
    up = Upload(items(1), TARGET, 0.0)
    up.due(0.0)
    up.on_message(request(0), 0.0)
    (message,) = up.due(0.0)
    msg = encode(message)
    assert (msg.seq, msg.frame, msg.command, msg.x, msg.z) == (0, 3, 16, 473977000, 10.0)


def test_upload_lost_count_is_resent_after_the_timeout():
    up = Upload(items(2), TARGET, 0.0, timeout=1.0, attempts=3)
    assert names(up.due(0.0)) == ["mission_count"]
    assert up.due(0.9) == []
    assert names(up.due(1.0)) == ["mission_count"]


def test_upload_lost_item_is_resent_when_the_autopilot_asks_again():
    up = Upload(items(2), TARGET, 0.0)
    up.due(0.0)
    up.on_message(request(0), 0.1)
    assert item_seqs(up.due(0.1)) == [0]  # this item is lost on the link
    up.on_message(request(0), 0.6)  # the autopilot asks again
    assert item_seqs(up.due(0.6)) == [0]
    up.on_message(request(1), 0.7)
    assert item_seqs(up.due(0.7)) == [1]
    up.on_message(ack(), 0.8)
    assert up.done and not up.error and up.transferred == 2


def test_upload_lost_last_item_is_resent_on_our_timeout():
    up = Upload(items(1), TARGET, 0.0, timeout=1.0)
    up.due(0.0)
    up.on_message(request(0), 0.1)
    assert item_seqs(up.due(0.1)) == [0]
    assert item_seqs(up.due(1.1)) == [0]  # no ACK within 1 s: the item again


def test_upload_duplicate_request_is_answered_without_counting_twice():
    up = Upload(items(3), TARGET, 0.0)
    up.due(0.0)
    for seq in (0, 1, 1, 2):
        up.on_message(request(seq), 0.1)
    assert item_seqs(up.due(0.1)) == [0, 1, 1, 2]
    assert up.transferred == 2
    up.on_message(ack(), 0.2)
    assert up.transferred == 3 and not up.error


def test_upload_request_beyond_the_count_and_other_types_are_ignored():
    up = Upload(items(2), TARGET, 0.0)
    up.due(0.0)
    up.on_message(request(5), 0.1)
    up.on_message(request(0, FENCE), 0.1)
    up.on_message(ack(mavlink.MAV_MISSION_ERROR, FENCE), 0.1)
    assert up.due(0.1) == [] and not up.done


def test_upload_times_out_with_a_partial_count_after_its_attempts():
    up = Upload(items(4), TARGET, 0.0, timeout=1.0, attempts=3)
    up.due(0.0)
    up.on_message(request(0), 0.1)
    up.on_message(request(1), 0.2)
    up.due(0.2)
    for t in (1.2, 2.2, 3.2):
        up.due(t)
    assert up.done
    assert "1 of 4" in up.error and "3 attempt(s)" in up.error
    assert up.transferred == 1  # items 0 and 1 asked: item 0 taken, item 1 pending
    assert up.wake_at() == math.inf


def test_upload_refused_item_ends_with_the_autopilots_reason_and_the_partial_count():
    up = Upload(items(3), TARGET, 0.0)
    up.due(0.0)
    up.on_message(request(0), 0.1)
    up.on_message(request(1), 0.2)
    up.on_message(ack(mavlink.MAV_MISSION_INVALID_PARAM5_X), 0.3)
    assert up.done
    assert "MAV_MISSION_INVALID_PARAM5_X" in up.error
    assert "1 of 3" in up.error


def test_upload_accept_before_every_item_was_asked_is_partial():
    up = Upload(items(3), TARGET, 0.0)
    up.due(0.0)
    up.on_message(request(0), 0.1)
    up.on_message(ack(), 0.2)
    assert up.done and "0 of 3" in up.error


def test_upload_of_nothing_ends_on_the_accept():
    up = Upload([], TARGET, 0.0)
    assert names(up.due(0.0)) == ["mission_count"]
    up.on_message(ack(), 0.1)
    assert up.done and not up.error


def test_download_asks_each_item_then_acks():
    down = Download(TARGET, 0.0)
    assert names(down.due(0.0)) == ["mission_request_list"]
    down.on_message(mavlink.MAVLink_mission_count_message(255, 191, 2, MISSION), 0.1)
    assert names(down.due(0.1)) == ["mission_request_int"]
    for seq in range(2):
        fields = (255, 191, seq, 3, 16, 0, 1, 0, 0, 0, math.nan, 10 + seq, 20, 5.0, MISSION)
        down.on_message(mavlink.MAVLink_mission_item_int_message(*fields), 0.2)
    sends = down.due(0.2)
    assert names(sends) == ["mission_request_int", "mission_ack"]
    assert down.done and not down.error
    assert [item.x for item in down.items] == [10, 11]


def test_download_lost_item_is_asked_again_and_a_duplicate_kept_once():
    down = Download(TARGET, 0.0, timeout=1.0)
    down.due(0.0)
    down.on_message(mavlink.MAVLink_mission_count_message(255, 191, 1, MISSION), 0.1)
    down.due(0.1)
    assert names(down.due(1.2)) == ["mission_request_int"]  # the item was lost
    fields = (255, 191, 0, 3, 16, 0, 1, 0, 0, 0, math.nan, 10, 20, 5.0, MISSION)
    down.on_message(mavlink.MAVLink_mission_item_int_message(*fields), 1.3)
    down.on_message(mavlink.MAVLink_mission_item_int_message(*fields), 1.3)
    assert len(down.items) == 1 and down.done


def test_download_takes_the_first_count_only():
    down = Download(TARGET, 0.0, timeout=1.0)
    down.due(0.0)
    down.on_message(mavlink.MAVLink_mission_count_message(255, 191, 2, MISSION), 0.1)
    assert item_seqs_asked(down.due(0.1)) == [0]
    fields = (255, 191, 0, 3, 16, 0, 1, 0, 0, 0, math.nan, 10, 20, 5.0, MISSION)
    down.on_message(mavlink.MAVLink_mission_item_int_message(*fields), 0.2)
    assert item_seqs_asked(down.due(0.2)) == [1]
    # our re-sent MISSION_REQUEST_LIST answered late: neither a new count nor a new request
    down.on_message(mavlink.MAVLink_mission_count_message(255, 191, 1, MISSION), 0.3)
    assert down.count == 2 and down.due(0.3) == [] and not down.done
    fields = (255, 191, 1, 3, 16, 0, 1, 0, 0, 0, math.nan, 11, 20, 5.0, MISSION)
    down.on_message(mavlink.MAVLink_mission_item_int_message(*fields), 0.4)
    assert down.done and not down.error and [item.x for item in down.items] == [10, 11]


def test_download_refused_ends_with_the_autopilots_reason():
    down = Download(TARGET, 0.0)
    down.due(0.0)
    down.on_message(ack(mavlink.MAV_MISSION_ACCEPTED), 0.1)  # not an answer to a download
    assert not down.done
    down.on_message(ack(mavlink.MAV_MISSION_DENIED, FENCE), 0.1)  # another mission type's
    assert not down.done
    down.on_message(ack(mavlink.MAV_MISSION_DENIED), 0.2)
    assert down.done and "refused by the autopilot: MAV_MISSION_DENIED" in down.error
    assert down.due(5.0) == []  # nothing re-sent after the refusal


def test_download_without_an_answer_times_out():
    down = Download(TARGET, 0.0, timeout=0.5, attempts=2)
    down.due(0.0)
    down.due(0.5)
    down.due(1.0)
    assert down.done and "no answer" in down.error


def test_clear_until_acknowledged():
    clear = Clear(TARGET, 0.0, timeout=1.0)
    assert names(clear.due(0.0)) == ["mission_clear_all"]
    assert names(clear.due(1.0)) == ["mission_clear_all"]
    clear.on_message(ack(), 1.1)
    assert clear.done and not clear.error


def test_clear_refused():
    clear = Clear(TARGET, 0.0)
    clear.on_message(ack(mavlink.MAV_MISSION_DENIED), 0.1)
    assert clear.done and "MAV_MISSION_DENIED" in clear.error
