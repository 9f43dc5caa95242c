"""COMMAND_LONG retries and COMMAND_ACK matching with de-duplication (PX4 double acks)."""

from __future__ import annotations

from pymavlink.dialects.v20.common import (
    MAV_CMD_COMPONENT_ARM_DISARM,
    MAV_CMD_DO_SET_MODE,
    MAV_RESULT_ACCEPTED,
    MAV_RESULT_DENIED,
    MAV_RESULT_IN_PROGRESS,
    MAV_RESULT_TEMPORARILY_REJECTED,
)

from dronewrapper_bridge_mavlink.commands import (
    RESULT_NO_ACK,
    AckRouter,
    PendingCommand,
    command_long,
    result_name,
)

TEMPORARILY_REJECTED = MAV_RESULT_TEMPORARILY_REJECTED
DENIED = MAV_RESULT_DENIED


def pending(command=MAV_CMD_DO_SET_MODE, attempts=3, timeout=1.0, expected_acks=1):
    return PendingCommand(
        command_long(command, 1, 6, 0),
        attempts=attempts,
        ack_timeout=timeout,
        expected_acks=expected_acks,
        final_ack_timeout=1.0,
    )


def test_first_send_then_retries_with_confirmation_increments():
    p = pending()
    first = p.due(0.0)
    assert first is not None and first.confirmation == 0 and first.params[:3] == (1.0, 6.0, 0.0)
    assert p.due(0.5) is None  # not yet time to retry
    second = p.due(1.0)
    third = p.due(2.0)
    assert (second.confirmation, third.confirmation) == (1, 2)
    assert p.due(3.0) is None  # out of attempts
    assert not p.finished(2.5)
    assert p.finished(3.0) and p.result == RESULT_NO_ACK


def test_ack_completes_and_duplicate_ack_is_dropped():
    router = AckRouter(dedup_window=0.3)
    p = pending()
    router.register(p)
    p.due(0.0)
    assert router.on_ack(MAV_CMD_DO_SET_MODE, MAV_RESULT_ACCEPTED, 0.05) == "matched"
    # a repeated ack of a command acked once (e.g. answering a retry) arrives right after
    assert router.on_ack(MAV_CMD_DO_SET_MODE, MAV_RESULT_ACCEPTED, 0.06) == "duplicate"
    assert p.finished(0.06) and p.result == MAV_RESULT_ACCEPTED
    router.release(p, 0.07)
    assert router.on_ack(MAV_CMD_DO_SET_MODE, DENIED, 0.2) == "duplicate"
    assert router.duplicates == 2
    # a new DO_SET_MODE is held back until late duplicates have passed
    assert router.quiet_until(MAV_CMD_DO_SET_MODE) == 0.07 + 0.3


def test_duplicate_does_not_complete_the_next_command():
    router = AckRouter(dedup_window=0.3)
    p1 = pending()
    router.register(p1)
    p1.due(0.0)
    router.on_ack(MAV_CMD_DO_SET_MODE, MAV_RESULT_ACCEPTED, 0.01)
    router.release(p1, 0.02)
    p2 = pending()
    router.register(p2)
    start = max(0.02, router.quiet_until(MAV_CMD_DO_SET_MODE))
    p2.due(start)
    assert not p2.done  # nothing left over from p1 could have completed it
    assert router.on_ack(MAV_CMD_DO_SET_MODE, DENIED, start + 0.05) == "matched"
    assert p2.result == DENIED


def test_unsolicited_acks_counted_and_other_commands_unaffected():
    router = AckRouter()
    p = pending(MAV_CMD_COMPONENT_ARM_DISARM)
    router.register(p)
    p.due(0.0)
    assert router.on_ack(MAV_CMD_DO_SET_MODE, MAV_RESULT_ACCEPTED, 0.1) == "unsolicited"
    assert not p.done and router.unsolicited == 1


def test_lost_first_ack_retry_succeeds():
    p = pending(attempts=5, timeout=0.5)
    p.due(0.0)
    assert not p.finished(0.5)
    assert p.due(0.5).confirmation == 1
    p.on_ack(MAV_RESULT_ACCEPTED, 0.6)
    assert p.finished(0.6) and p.result == MAV_RESULT_ACCEPTED and p.sent == 2


def test_in_progress_waits_longer_without_resending():
    p = PendingCommand(command_long(22), attempts=2, ack_timeout=1.0, in_progress_timeout=5.0)
    p.due(0.0)
    p.on_ack(MAV_RESULT_IN_PROGRESS, 0.1)
    assert p.due(1.5) is None and not p.finished(1.5)
    p.on_ack(MAV_RESULT_ACCEPTED, 3.0)
    assert p.finished(3.0) and p.result == MAV_RESULT_ACCEPTED


def test_in_progress_then_silence_is_no_ack():
    p = PendingCommand(command_long(22), attempts=1, ack_timeout=1.0, in_progress_timeout=2.0)
    p.due(0.0)
    p.on_ack(MAV_RESULT_IN_PROGRESS, 0.5)
    assert not p.finished(2.0)
    assert p.finished(2.6) and p.result == RESULT_NO_ACK


def test_px4_double_ack_the_second_is_the_answer():
    """PX4: ACCEPTED from the MAVLink receiver, then the commander's refusal 11 ms later."""
    router = AckRouter()
    p = pending(expected_acks=2)
    router.register(p)
    p.due(0.0)
    assert router.on_ack(MAV_CMD_DO_SET_MODE, MAV_RESULT_ACCEPTED, 0.010) == "matched"
    assert not p.finished(0.011) and not p.confirmed  # provisional: wait for the real answer
    assert p.due(0.5) is None  # and never re-send meanwhile
    assert router.on_ack(MAV_CMD_DO_SET_MODE, TEMPORARILY_REJECTED, 0.021) == "matched"
    assert p.finished(0.021) and p.result == TEMPORARILY_REJECTED and p.confirmed


def test_px4_double_ack_both_accepted_is_confirmed():
    p = pending(expected_acks=2)
    p.due(0.0)
    p.on_ack(MAV_RESULT_ACCEPTED, 0.01)
    p.on_ack(MAV_RESULT_ACCEPTED, 0.02)
    assert p.finished(0.02) and p.result == MAV_RESULT_ACCEPTED and p.confirmed and p.acks == 2


def test_px4_double_ack_missing_second_ends_accepted_but_unconfirmed():
    p = pending(expected_acks=2)
    p.due(0.0)
    p.on_ack(MAV_RESULT_ACCEPTED, 0.01)
    assert not p.finished(1.0)
    assert p.finished(1.02) and p.result == MAV_RESULT_ACCEPTED and not p.confirmed


def test_a_first_refusal_is_final_even_when_two_acks_are_expected():
    p = pending(expected_acks=2)
    p.due(0.0)
    p.on_ack(DENIED, 0.01)
    assert p.finished(0.01) and p.result == DENIED and p.confirmed


def test_result_names():
    assert result_name(1) == "TEMPORARILY_REJECTED" and result_name(-1) == "NO_ACK"
