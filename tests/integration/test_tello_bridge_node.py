"""bridge_tello's node wiring: the Bridge in-process against a scripted Tello over real UDP.

Only the wiring is checked here (the three sockets, the threads, the lock around the core, the
Zenoh side: the fake bus, or a real router for the command lease carried as an attachment).
Every rule of the contract is tested on the pure core in tests/unit/test_tello_core.py.
The scripted Tello (tests/tello_peer.py) answers from a script and records every datagram.
"""

from __future__ import annotations

import time
from collections.abc import Iterator
from typing import Any

import pytest
from targets import velocity
from tello_bridge_rig import running_bridge
from tello_peer import ScriptedTello

from dronewrapper.msgs import registry
from dronewrapper.msgs.lease import LeaseRequest
from dronewrapper.msgs.mavros import (
    CommandTOL,
    ParamGet,
    ParamSet,
)
from dronewrapper.runtime import ServiceError, call_service
from dronewrapper.runtime.caller import commander_attachment
from dronewrapper_bridge_tello.node import Bridge
from support import wait_for

pytestmark = pytest.mark.integration


@pytest.fixture
def tello_and_bridge(request) -> Iterator[tuple[ScriptedTello, Bridge, Any]]:
    """The bridge on the fake bus (the Tello link stays real UDP)."""
    with running_bridge(getattr(request, "param", [])) as running:
        yield running


def test_services_setpoints_and_replies_travel_over_real_udp(tello_and_bridge):
    """A take-off and a land through the sockets and threads, a streamed setpoint as rc text on
    the wire and then the stop, a refusal with the Tello's text and a read's value."""
    tello, bridge, user = tello_and_bridge
    assert user.call(registry.TAKEOFF, CommandTOL.takeoff(), timeout=30).success
    pub = user.publisher(registry.SETPOINT_RAW_LOCAL)
    # forward 0.3, left 0.2, up 0.1 m/s, CCW 0.4 rad/s -> a -20, b 30, c 10, d -23
    target = velocity(0.3, 0.2, 0.1, 0.4)
    start = time.monotonic()
    while time.monotonic() - start < 0.5:
        pub.put(target)
        time.sleep(0.05)
    stopped = time.monotonic()
    wait_for(lambda: (0, 0, 0, 0) in {s for _, s in tello.rcs(stopped)}, 5, what="a stop")
    assert (-20, 30, 10, -23) in {s for _, s in tello.rcs(start)}
    wait_for(lambda: bridge.core.failsafe.state == "hold", 5, what="failsafe hold")
    tello.script["speed 50"] = "out of range"
    reply = user.call(registry.PARAM_SET, ParamSet.of("SPEED", 50))
    assert not reply.success and "out of range" in reply.message
    reply = user.call(registry.PARAM_GET, ParamGet(param_id="BATTERY"))
    assert reply.success and reply.value.real == 80.0
    assert user.call(registry.LAND, CommandTOL.land(), timeout=30).success
    assert not tello.flying


def test_a_second_bridge_on_the_same_address_fails_loudly(tello_and_bridge):
    _, bridge, user = tello_and_bridge
    with pytest.raises(OSError):
        Bridge(user, bridge.config)
    assert bridge.core.connected


def test_command_lease_one_commander_at_a_time(router):
    """On a real router: the commander travels as a Zenoh attachment (the wiring)."""
    with running_bridge(["command_lease=true"], router) as (tello, bridge, user):

        def call(service, request, who: str):
            return call_service(
                user.session, service, request, ns="drone", timeout=30,
                attachment=commander_attachment(who),
            )  # fmt: skip

        assert call(registry.TAKEOFF, CommandTOL.takeoff(), "alice").success
        with pytest.raises(ServiceError, match="holds the command lease"):
            call(registry.LAND, CommandTOL.land(), "bob")
        assert tello.flying  # bob's land never reached the Tello
        taken = call(registry.COMMAND_LEASE, LeaseRequest(action="take_over"), "bob")
        assert taken.granted and taken.holder == "bob" and taken.previous == "alice"
        wait_for(lambda: bridge.state_message().commander == "bob", 5, what="State.commander")
        assert call(registry.LAND, CommandTOL.land(), "bob").success
