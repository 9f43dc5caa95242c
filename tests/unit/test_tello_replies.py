"""In-order reply matching without ids: lost, late, duplicate and unsolicited replies."""

from __future__ import annotations

from dronewrapper_bridge_tello.replies import Pending, ReplyMatcher, is_ok, is_read, is_status


def send(matcher: ReplyMatcher, pending: Pending, now: float) -> None:
    assert pending.due(now)
    matcher.sent(pending, now)


def test_replies_go_to_commands_in_order():
    m = ReplyMatcher()
    a, b = Pending("speed 50"), Pending("battery?")
    send(m, a, 0.0)
    send(m, b, 0.01)
    assert m.on_reply("ok", 0.02) is a
    assert m.on_reply("87", 0.03) is b
    assert (a.reply, b.reply) == ("ok", "87")


def test_a_value_skips_a_command_whose_reply_was_lost():
    m = ReplyMatcher()
    a, b = Pending("speed 50"), Pending("battery?")
    send(m, a, 0.0)
    send(m, b, 0.0)
    assert m.on_reply("87", 0.1) is b  # 'ok' for a was lost: a value cannot answer it
    assert a.reply is None and m.lost == 1


def test_error_texts_answer_any_command():
    m = ReplyMatcher()
    a = Pending("battery?")
    send(m, a, 0.0)
    assert m.on_reply("error Not joystick", 0.1) is a
    assert is_status("out of range") and is_status("unknown command: foo")
    assert not is_ok("error Motor stop") and is_ok("ok\r\n")
    assert is_read("battery?") and not is_read("takeoff")


def test_retry_then_late_duplicate_is_not_the_next_commands_answer():
    m = ReplyMatcher()
    a = Pending("speed 50", timeout=1.0, attempts=3)
    send(m, a, 0.0)
    assert not a.due(0.5) and not a.finished(0.5)
    send(m, a, 1.0)  # no reply within 1 s: re-sent
    assert m.on_reply("ok", 1.2) is a  # the late reply to the first send
    assert m.on_reply("ok", 1.21) is None and m.duplicates == 1  # the second send's reply
    m.forget(a)
    b = Pending("speed 60")
    send(m, b, 1.5)
    assert m.on_reply("ok", 1.6) is b


def test_forget_drops_the_slots_of_an_abandoned_command():
    m = ReplyMatcher()
    a = Pending("speed 50", timeout=0.5, attempts=1)
    send(m, a, 0.0)
    assert a.finished(0.6) and a.reply is None
    m.forget(a)
    b = Pending("speed 60")
    send(m, b, 1.0)
    assert m.on_reply("ok", 1.1) is b


def test_stale_slots_expire_and_unsolicited_replies_are_counted():
    m = ReplyMatcher(stale_after=2.0)
    a = Pending("speed 50", timeout=1.0)
    send(m, a, 0.0)
    assert m.on_reply("ok", 3.5) is None  # 3.5 s > 1 s timeout + 2 s
    assert m.lost == 1 and m.unsolicited == 1 and m.waiting() == 0


def test_long_commands_wait_their_own_timeout():
    m = ReplyMatcher(stale_after=2.0)
    takeoff = Pending("takeoff", timeout=20.0, attempts=1)
    send(m, takeoff, 0.0)
    assert m.on_reply("ok", 7.0) is takeoff


def test_retry_schedule():
    p = Pending("command", timeout=1.0, attempts=2)
    assert p.due(0.0) and not p.due(0.9) and p.wake_at(0.5) == 1.0
    assert p.due(1.0) and not p.due(2.5)
    assert not p.finished(1.5) and p.finished(2.0) and p.sent == 2
