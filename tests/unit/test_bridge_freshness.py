"""Duplicated, late and reordered MAVLink datagrams are never used as new (issue 12 item 7)."""

from __future__ import annotations

from dronewrapper_bridge_mavlink.freshness import REBOOT_JUMP_MS, SILENCE_RESET_S, Freshness
from dronewrapper_bridge_mavlink.sources import TAKEOVER_SILENCE_S, AutopilotSources

A = ("127.0.0.1", 14580)
B = ("127.0.0.1", 14581)


def pose(f: Freshness, seq: int, boot_ms: int, now: float = 0.0, address=A) -> bool:
    payload = f"{seq}:{boot_ms}".encode()  # the bytes differ whenever the content does
    return f.check(address, 1, 1, seq, "LOCAL_POSITION_NED", boot_ms, now, payload).new


def test_a_duplicated_datagram_is_dropped():
    f = Freshness()
    assert pose(f, 10, 1000)
    assert not pose(f, 10, 1000)
    assert pose(f, 11, 1020)
    assert f.duplicates == 1


def test_a_late_datagram_is_dropped_and_loss_is_fine():
    f = Freshness()
    assert pose(f, 10, 1000)
    assert pose(f, 12, 1040)
    assert not pose(f, 11, 1020)  # arrived after 12: older than what was published
    assert pose(f, 100, 2800)  # 88 lost: a forward step
    assert f.stale == 1


def test_a_sender_that_never_advances_seq_still_gets_new_messages_through():
    f = Freshness()
    assert pose(f, 0, 1000)
    assert pose(f, 0, 1020)
    assert not pose(f, 0, 1020)  # the same bytes again: a duplicate


def test_seq_wraps_around():
    f = Freshness()
    assert pose(f, 254, 1000)
    assert pose(f, 255, 1020)
    assert pose(f, 0, 1040)
    assert pose(f, 1, 1060)
    assert not pose(f, 255, 1020)


def test_time_boot_ms_never_goes_back_within_a_type():
    f = Freshness()
    assert pose(f, 1, 5000)
    assert not pose(f, 100, 4980)  # a far-late datagram beyond the seq window
    assert not pose(f, 200, 5000)  # same sample again
    # other types keep their own clock
    assert f.check(A, 1, 1, 201, "ATTITUDE", 4990, 0.0).new
    # messages without time_boot_ms only go through the seq check
    assert f.check(A, 1, 1, 202, "HEARTBEAT", None, 0.0).new


def test_a_reboot_or_a_silent_sender_starts_afresh():
    f = Freshness()
    assert pose(f, 50, 600_000)
    assert pose(f, 120, 600_000 - REBOOT_JUMP_MS - 1)  # clock went far back: rebooted
    g = Freshness()
    assert pose(g, 50, 9000, now=0.0)
    assert pose(g, 45, 100, now=SILENCE_RESET_S + 0.1)  # restarted: seq and clock reset


def test_senders_are_separate():
    f = Freshness()
    assert pose(f, 10, 1000, address=A)
    assert pose(f, 10, 1000, address=B)
    assert f.check(A, 1, 2, 10, "LOCAL_POSITION_NED", 1000, 0.0).new  # another component


def test_a_second_autopilot_with_the_same_system_id_is_flagged_once_and_ignored():
    s = AutopilotSources()
    assert s.check(A, 1, 0.0).accept
    first = s.check(B, 1, 0.1)
    assert not first.accept and "second autopilot with system id 1" in first.flag
    assert "127.0.0.1:14581" in first.flag
    again = s.check(B, 1, 0.2)
    assert not again.accept and again.flag == ""
    assert s.check(A, 1, 0.3).accept and s.owner(1) == A
    assert s.check(B, 2, 0.3).accept  # another system id is another aircraft
    assert s.intruder_messages == 2


def test_a_restarted_autopilot_on_a_new_port_takes_over_after_silence():
    s = AutopilotSources()
    assert s.check(A, 1, 0.0).accept
    verdict = s.check(B, 1, TAKEOVER_SILENCE_S + 0.1)
    assert verdict.accept and "now speaks from 127.0.0.1:14581" in verdict.flag
    assert s.owner(1) == B
    assert s.check(None, 1, 5.0).accept  # serial / TCP: no address, one peer
