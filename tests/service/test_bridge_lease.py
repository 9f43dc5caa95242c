"""Both bridges' cores on the fake bus behind the shared bridge wiring (BridgeNode): each
request and setpoint reaches the core with its commander, and the core's lease decides."""

from __future__ import annotations

import logging

import pytest
from targets import velocity

from dronewrapper.envelope import Envelope
from dronewrapper.errors import CommandRefused
from dronewrapper.msgs import registry
from dronewrapper.msgs.flight import CancelRequest
from dronewrapper.msgs.lease import LeaseRequest
from dronewrapper.msgs.mavros import (
    CommandBool,
    CommandTOL,
)
from dronewrapper.msgs.mission import (
    EnvelopeSet,
    MissionControl,
    Waypoint,
    WaypointClear,
    WaypointPush,
    WaypointSetCurrent,
)
from dronewrapper.runtime import ServiceError
from dronewrapper.runtime.caller import commander_attachment, handling
from dronewrapper.runtime.fake import FakeBus, FakeNode
from dronewrapper_bridge_base.bridge_node import BridgeNode
from dronewrapper_bridge_mavlink import node as mavlink_node
from dronewrapper_bridge_mavlink.config import Config as MavlinkConfig
from dronewrapper_bridge_mavlink.core import BridgeCore
from dronewrapper_bridge_tello import node as tello_node
from dronewrapper_bridge_tello.config import Config as TelloConfig
from dronewrapper_bridge_tello.core import TelloCore

FORWARD = velocity(0.5)


class Wired(BridgeNode):
    """A core on the bridge wiring, its sends recorded instead of going to an aircraft."""

    def send(self, out) -> None:
        self.sent = [*getattr(self, "sent", []), *out.sends]


def wired(kind: str) -> tuple[FakeBus, Wired]:
    bus = FakeBus(start=1_700_000_000.0)
    if kind == "mavlink":
        core = BridgeCore(MavlinkConfig(command_lease=True))
        module = mavlink_node
    else:
        core = TelloCore(TelloConfig(command_lease=True, video=False))
        module = tello_node
    node = FakeNode("bridge", bus, ports=module.PORTS)
    publishers = {topic: node.publisher(topic) for topic in module.PUBLISHED}
    bridge = Wired(node, core, publishers, logging.getLogger(kind))
    module.serve_services(bridge)  # as the bridge's start() does
    return bus, bridge


def ask(user: FakeNode, service, request, commander: str):
    return user.call(service, request, attachment=commander_attachment(commander))


@pytest.mark.parametrize("kind", ["mavlink", "tello"])
def test_a_non_holders_requests_and_setpoints_are_refused_until_it_takes_over(kind):
    bus, bridge = wired(kind)
    user = FakeNode("apps", bus)
    assert ask(user, registry.COMMAND_LEASE, LeaseRequest(action="take"), "alice").granted
    for service, request in (
        (registry.ARMING, CommandBool(value=True)),
        (registry.TAKEOFF, CommandTOL.takeoff(2.0)),
        (registry.LAND, CommandTOL.land()),
    ):
        with pytest.raises(ServiceError, match="'alice' holds the command lease") as error:
            ask(user, service, request, "bob")
        assert error.value.code == "lease"
        with pytest.raises(ServiceError) as error:  # alice's reaches the aircraft's side
            ask(user, service, request, "alice")
        assert error.value.code == "unavailable"  # no aircraft connected
    with handling(commander_attachment("bob")):
        bridge.on_setpoint(FORWARD)
    assert bridge.core.lease.refused_setpoints == 1
    reply = ask(user, registry.COMMAND_LEASE, LeaseRequest(action="take_over"), "bob")
    assert (reply.granted, reply.previous) == (True, "alice")
    states = bus.published[registry.STATE.key("drone")]
    assert states[-1].msg.commander == "bob"
    with handling(commander_attachment("bob")):
        bridge.on_setpoint(FORWARD)
    assert bridge.core.lease.refused_setpoints == 1
    with pytest.raises(ServiceError) as error:
        ask(user, registry.ARMING, CommandBool(value=True), "bob")
    assert error.value.code == "unavailable"


@pytest.mark.parametrize("kind", ["mavlink", "tello"])
def test_a_non_holders_cancel_is_refused_and_the_holders_is_answered(kind):
    _, bridge = wired(kind)
    user = FakeNode("apps", bridge.node.bus)
    assert ask(user, registry.COMMAND_LEASE, LeaseRequest(action="take"), "alice").granted
    with pytest.raises(ServiceError, match="'alice' holds the command lease") as error:
        ask(user, registry.FLIGHT_CANCEL, CancelRequest(), "bob")
    assert error.value.code == "lease"
    reply = ask(user, registry.FLIGHT_CANCEL, CancelRequest(), "alice")
    assert not reply.success and "nothing to cancel" in reply.message


HERE = Waypoint(x_lat=0.0, y_long=0.0, z_alt=1.0)
MISSION_REQUESTS = {
    "mavlink": [
        (registry.MISSION_PUSH, WaypointPush(waypoints=[HERE])),
        (registry.MISSION_CLEAR, WaypointClear()),
        (registry.MISSION_SET_CURRENT, WaypointSetCurrent(wp_seq=0)),
        (registry.MISSION_CONTROL, MissionControl(action="start")),
        (registry.GEOFENCE_PUSH, WaypointClear()),
    ],
    "tello": [
        (
            registry.MISSION_PUSH,
            WaypointPush(waypoints=[Waypoint(frame=4, x_lat=0, y_long=0, z_alt=1)]),
        ),
        (registry.MISSION_CLEAR, WaypointClear()),
        (registry.MISSION_CONTROL, MissionControl(action="start")),
    ],
}


@pytest.mark.parametrize("kind", ["mavlink", "tello"])
def test_only_the_lease_holder_may_change_the_envelope(kind):
    bus, bridge = wired(kind)
    user = FakeNode("apps", bus)
    before = bridge.core.missions.envelope
    assert ask(user, registry.COMMAND_LEASE, LeaseRequest(action="take"), "alice").granted
    wide = EnvelopeSet(envelope=Envelope(max_altitude=500.0, max_distance=5000.0))
    with pytest.raises(ServiceError, match="'alice' holds the command lease") as error:
        ask(user, registry.ENVELOPE_SET, wide, "bob")
    assert error.value.code == "lease"
    assert bridge.core.missions.envelope == before
    reply = ask(user, registry.ENVELOPE_SET, wide, "alice")
    assert reply.success and bridge.core.missions.envelope.max_altitude == 500.0


@pytest.mark.parametrize("kind", ["mavlink", "tello"])
def test_only_the_lease_holder_may_push_clear_or_fly_a_mission(kind):
    bus, bridge = wired(kind)
    user = FakeNode("apps", bus)
    assert ask(user, registry.COMMAND_LEASE, LeaseRequest(action="take"), "alice").granted
    for service, request in MISSION_REQUESTS[kind]:
        with pytest.raises(ServiceError, match="'alice' holds the command lease") as error:
            ask(user, service, request, "bob")
        assert error.value.code == "lease", service.key("drone")
    assert bridge.core.missions.waypoints == []  # bob's push kept nothing
    for service, request in MISSION_REQUESTS[kind]:
        try:  # alice's reach the bridge's side (no aircraft: refused there, if at all)
            ask(user, service, request, "alice")
        except ServiceError as exc:
            assert exc.code != "lease", (service.key("drone"), exc)


@pytest.mark.parametrize("kind", ["mavlink", "tello"])
def test_a_spoofed_commander_name_is_refused(kind):
    """On a secure graph a certificate's commands travel on keys bound to its name (the
    router's access control lets alice put and query only under ``@by/alice``): alice
    claiming "carol" in her attachment is still alice, and carol's lease holds."""
    bus, bridge = wired(kind)
    carol = FakeNode("carol_app", bus, bound_name="carol")
    alice = FakeNode("alice_app", bus, bound_name="alice")
    assert ask(carol, registry.COMMAND_LEASE, LeaseRequest(action="take"), "carol").granted
    with pytest.raises(ServiceError) as error:
        ask(alice, registry.ARMING, CommandBool(value=True), "carol")
    assert error.value.code == "lease"
    assert error.value.message.startswith("'carol' holds the command lease; 'alice' must")
    setpoints = alice.publisher(registry.SETPOINT_RAW_LOCAL)
    assert setpoints.key == "drone/mavros/setpoint_raw/local/@by/alice"
    setpoints.put(FORWARD, attachment=commander_attachment("carol"))
    assert bridge.core.lease.refused_setpoints == 1  # the bridge heard it, as alice's
    reply = ask(alice, registry.COMMAND_LEASE, LeaseRequest(action="release"), "carol")
    assert not reply.granted and reply.holder == "carol"  # nor may she release carol's lease
    with pytest.raises(ServiceError) as error:  # carol's own reach the aircraft's side
        ask(carol, registry.ARMING, CommandBool(value=True), "carol")
    assert error.value.code == "unavailable"


def test_a_lease_refusal_names_the_command_once():
    """The bridge's refusal is the reason; the SDK names the command: "arming refused: 'alice'
    holds ...", never "arming refused: arming refused: ..."."""
    bus, _ = wired("mavlink")
    user = FakeNode("apps", bus)
    assert ask(user, registry.COMMAND_LEASE, LeaseRequest(action="take"), "alice").granted
    with pytest.raises(ServiceError) as error:
        ask(user, registry.ARMING, CommandBool(value=True), "bob")
    text = str(CommandRefused("arming", error.value.message))
    assert text.startswith("arming refused: 'alice' holds the command lease; 'bob' must take")
    assert text.count("refused") == 1
