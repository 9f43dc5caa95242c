"""Mode changes as real PX4 answers them (issue 12, items 1-3), bridge in-process over real UDP.

The scripted PX4 of test_bridge_node.py acknowledges DO_SET_MODE twice like the real one: its
MAVLink receiver's ACCEPTED at once, then the commander's result (a refusal with STATUSTEXT for
a mode it cannot enter). The SDK runs against the bridge where the rule is about what a caller
of ``set_mode()`` / ``takeoff()`` sees. The rules themselves are tested at the core, in given
time (tests/unit/test_bridge_core_contract.py); these prove they reach an SDK caller.
"""

from __future__ import annotations

import pytest
from test_bridge_node import (  # the scripted autopilot and its rig
    AUTO_LOITER,
    OFFBOARD,
    make_rig,
)

from dronewrapper import CommandRefused, DroneWrapper
from support import wait_for

REFUSED_TEXT = "Switching to Offboard is currently not available"


@pytest.fixture
def rig(router):
    yield from make_rig(router, autopilot=12)


def flying_offboard(bridge, fake) -> None:
    fake.custom_mode, fake.armed, fake.landed_state = OFFBOARD, True, 2
    fake.position_ned = (1.0, 1.0, -3.0)
    wait_for(lambda: bridge.core.failsafe.mode == "OFFBOARD" and bridge.core.failsafe.airborne, 10)


def test_refused_mode_reaches_sdk_set_mode(rig, router):
    bridge, fake, _user = rig
    flying_offboard(bridge, fake)
    with DroneWrapper("drone", router, timeout=20, cameras=()) as drone:
        with pytest.raises(CommandRefused, match="Switching to Position is currently not"):
            drone.set_mode("POSCTL")
        assert drone.get_state().mode == "OFFBOARD"


def test_takeoff_does_not_arm_before_px4_really_accepts_offboard(rig, router):
    """The commander's refusal (second ack) stops take-off before any arming command."""
    _bridge, fake, _user = rig
    fake.refuse_modes[OFFBOARD] = REFUSED_TEXT
    drone = DroneWrapper("drone", router, timeout=20, cameras=())
    with drone, pytest.raises(CommandRefused, match=REFUSED_TEXT):
        drone.takeoff(h=2.0, timeout=20)
    assert fake.commands_named(176) and not fake.commands_named(400)
    assert not fake.armed and fake.custom_mode == AUTO_LOITER
