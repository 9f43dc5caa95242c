"""The unattended-action rule on the PX4 Zenoh bridge (bridge_px4_zenoh/watch.py), against a
recorded PX4 (tests/unit/px4_zenoh_rig.py) in given time: a go-to whose commander's process
stopped beating ends, once the go-to has ended, with PX4's return (or landing) asked once; a
live commander, a return, and a commander steering again are left alone."""

from __future__ import annotations

from px4_zenoh_rig import NAV_RTL, Px4Rig
from targets import position

from dronewrapper.msgs import registry
from dronewrapper.msgs.flight import TOO_LATE, GotoRequest, ReturnRequest
from dronewrapper_bridge_px4_zenoh import commands as cmds
from dronewrapper_bridge_px4_zenoh import flight

APP = "drone/alive/app"


def asked(rig: Px4Rig, command: int) -> list[float]:
    """The vehicle commands ``command`` written to PX4 so far (their param1s)."""
    return [c["param1"] for c in rig.commands() if c["command"] == command]


def beat(rig: Px4Rig) -> None:
    rig.core.on_alive({APP}, rig.now, rig.stamp)
    rig.drain()


def fly_to(rig: Px4Rig, x: float, **request: object):
    """A go-to (its commander ``APP``) from a hover at 3 m, reached 1 s later."""
    rig.flying_offboard(3.0)
    goto = GotoRequest(x=x, y=0.0, z=3.0, watch=APP, **request)
    op = rig.request(flight.goto_point(rig.core, goto), "goto")
    rig.run(1.0)
    return op


def test_a_go_to_whose_commander_died_returns_once_it_is_reached():
    rig = Px4Rig()
    asked_at = rig.now
    op = fly_to(rig, 4.0)
    rig.at(4.0, 0.0, 3.0)
    rig.run(0.1)
    assert op.done and op.reply.success, op.reply
    rig.run(asked_at + 4.9 - rig.now)  # the request is the commander's last beat
    assert asked(rig, cmds.NAV_RETURN_TO_LAUNCH) == []
    rig.run(0.3)
    assert len(asked(rig, cmds.NAV_RETURN_TO_LAUNCH)) == 1
    texts = [m.text for m in rig.published(registry.STATUSTEXT)]
    assert any("the commander of the goto (drone/alive/app) has been gone" in t for t in texts)
    rig.ack(cmds.NAV_RETURN_TO_LAUNCH)
    rig.vehicle(nav_state=NAV_RTL)
    rig.run(10.0)
    assert len(asked(rig, cmds.NAV_RETURN_TO_LAUNCH)) == 1  # once


def test_a_go_to_still_flying_is_left_to_end_then_lands_as_configured():
    rig = Px4Rig(unattended_action="land")
    op = fly_to(rig, 40.0, timeout=8.0)  # never reached: it times out, holding where it is
    rig.run(5.0)
    assert not op.done and asked(rig, cmds.NAV_LAND) == []  # gone, but the go-to flies on
    rig.run(2.5)
    assert op.done and op.reply.failure == TOO_LATE
    assert len(asked(rig, cmds.NAV_LAND)) == 1


def test_a_live_commander_a_steering_one_and_a_return_are_left_alone():
    rig = Px4Rig()
    op = fly_to(rig, 4.0)
    rig.at(4.0, 0.0, 3.0)
    for _ in range(12):
        beat(rig)
        rig.run(1.0)
    assert op.done and op.reply.success
    assert asked(rig, cmds.NAV_RETURN_TO_LAUNCH) == [] and asked(rig, cmds.NAV_LAND) == []

    rig = Px4Rig()
    fly_to(rig, 4.0)
    rig.at(4.0, 0.0, 3.0)
    rig.run(0.1)
    rig.setpoint(position(4.0, 0.0, 3.0))
    rig.run(10.0)  # the app steers again, then stops: the failsafe's landing, not this rule's
    assert asked(rig, cmds.NAV_RETURN_TO_LAUNCH) == []

    rig = Px4Rig()
    rig.flying_offboard(3.0)
    request = ReturnRequest(watch=APP, timeout=60.0)
    rig.request(flight.return_home(rig.core, request), "return")
    rig.ack(cmds.NAV_RETURN_TO_LAUNCH)
    rig.vehicle(nav_state=NAV_RTL)
    rig.run(20.0)  # its commander is gone: the return is left to finish
    assert len(asked(rig, cmds.NAV_RETURN_TO_LAUNCH)) == 1 and asked(rig, cmds.NAV_LAND) == []


def test_a_disarm_on_the_ground_ends_the_watch():
    rig = Px4Rig()
    fly_to(rig, 4.0)
    rig.at(4.0, 0.0, 3.0)
    rig.run(0.1)
    assert rig.core.unattended.what == "goto"
    rig.vehicle(armed=True, landed=True)  # on the ground, still armed: watched on
    assert rig.core.unattended.what == "goto"
    rig.vehicle(armed=False)
    assert rig.core.unattended.what == ""
    rig.run(10.0)
    assert asked(rig, cmds.NAV_RETURN_TO_LAUNCH) == [] and asked(rig, cmds.NAV_LAND) == []
