"""The node contract on the fake bus: FakeNode keeps every promise Node keeps (the same checks
run on a real router in tests/integration/test_runtime_node_contract.py)."""

from __future__ import annotations

from node_contract import PORTS, check_node, check_ports

from dronewrapper.msgs import registry
from dronewrapper.msgs.control import ControllerStatus
from dronewrapper.runtime.fake import FakeBus, FakeNode


def settled(predicate, what: str) -> None:
    """The fake bus delivers on the publishing thread: what was sent has arrived."""
    assert predicate(), what


def test_fake_node_keeps_the_node_contract():
    bus = FakeBus(start=50.0)
    check_node(FakeNode("a", bus), FakeNode("b", bus), settled)


def test_a_fake_node_with_ports_refuses_what_they_do_not_declare():
    bus = FakeBus(start=50.0)
    check_ports(FakeNode("limited", bus, ports=PORTS), FakeNode("free", bus), settled)


def test_a_link_gap_on_the_fake_bus_stops_delivery_and_is_heard_by_publishers():
    bus = FakeBus()
    a, b = FakeNode("a", bus), FakeNode("b", bus)
    heard: list[bool] = []
    got: list = []
    pub = a.publisher(registry.CONTROLLER_STATUS)
    pub.on_matching(heard.append)
    b.subscribe(registry.CONTROLLER_STATUS, got.append)
    bus.link_gap(True)
    pub.put(ControllerStatus())
    assert not b.linked() and not pub.watched() and got == []
    bus.link_gap(False)
    pub.put(ControllerStatus())
    assert heard == [True, False, True] and len(got) == 1


def test_a_fake_node_sleeps_in_bus_time_delivering_what_is_scheduled():
    bus = FakeBus(start=10.0)
    node = FakeNode("a", bus)
    holder = node.latest(registry.CONTROLLER_STATUS)
    bus.schedule(10.5, registry.CONTROLLER_STATUS.key("drone"), ControllerStatus())
    assert holder.wait(2.0) is not None and bus.clock() == 10.5  # woke on the delivery
    assert node.sleep(1.0) and bus.clock() == 11.5
