"""The bridge's command guard: the lease applied to setpoints and commands (time injected)."""

from __future__ import annotations

import pytest

from dronewrapper.msgs.lease import LeaseRequest
from dronewrapper.runtime import ServiceError
from dronewrapper.runtime.caller import commander_attachment, handling
from dronewrapper.runtime.clock import VirtualClock
from dronewrapper.security.guard import CommandGuard


def as_commander(name: str):
    return handling(commander_attachment(name))


def test_off_admits_everyone():
    guard = CommandGuard(enabled=False, ttl_s=10.0)
    with as_commander("anyone"):
        assert guard.admit_setpoint()
        guard.admit_command("arming")
        assert guard.handle_lease(LeaseRequest(action="take")).granted
    assert guard.holder() == ""


def test_holder_only_until_taken_over():
    clock, changes = VirtualClock(monotonic=100.0), []
    guard = CommandGuard(enabled=True, ttl_s=10.0, on_change=lambda: changes.append(1), clock=clock)
    with as_commander("alice"):
        assert guard.admit_setpoint()
    assert guard.holder() == "alice" and changes == [1]
    with as_commander("carol"):
        assert not guard.admit_setpoint()
        with pytest.raises(ServiceError, match="'alice' holds the command lease") as refused:
            guard.admit_command("arming")
        assert refused.value.code == "lease"
        assert not guard.handle_lease(LeaseRequest(action="take")).granted
        reply = guard.handle_lease(LeaseRequest(action="take_over"))
    assert (reply.granted, reply.holder, reply.previous) == (True, "carol", "alice")
    assert guard.holder() == "carol" and len(changes) == 2
    assert (guard.refused_setpoints, guard.refused_commands) == (1, 1)
    with as_commander("alice"):
        assert not guard.admit_setpoint()
    clock.advance_to(clock() + 10.0)  # carol silent for the ttl: the lease lapses
    assert guard.holder() == ""
    with as_commander("alice"):
        assert guard.admit_setpoint()
        with pytest.raises(ValueError, match="action"):
            guard.handle_lease(LeaseRequest(action="steal"))
        assert guard.handle_lease(LeaseRequest(action="release")).granted
    assert guard.holder() == ""


def test_commands_without_a_name_are_one_anonymous_commander():
    guard = CommandGuard(enabled=True, ttl_s=10.0, clock=VirtualClock(monotonic=100.0))
    assert guard.admit_setpoint()  # e.g. the on-board controller (no attachment)
    assert guard.holder() == "anonymous"
    with as_commander("alice"):
        assert not guard.admit_setpoint()
