"""What the ROS 2 gateway says about what it presents, on the fake bus in bus time: a router
it cannot reach and a drone whose state never comes are each named once after the grace time,
and their arrival once; its declarations are one INFO line (each key at DEBUG)."""

from __future__ import annotations

import logging

from ros2_session import RosSession

from dronewrapper.msgs import registry
from dronewrapper.msgs.mavros import State
from dronewrapper.runtime.fake import FakeBus, FakeNode
from dronewrapper_ros2_gateway.config import Config
from dronewrapper_ros2_gateway.entities import ENTITIES, PORTS
from dronewrapper_ros2_gateway.node import Gateway, log_started
from dronewrapper_ros2_gateway.presence import GRACE_S, PresenceWatch


class Said:
    def __init__(self) -> None:
        self.lines: list[tuple[int, str]] = []

    def __call__(self, level: int, text: str) -> None:
        self.lines.append((level, text))

    def take(self) -> list[tuple[int, str]]:
        lines, self.lines = self.lines, []
        return lines


def test_no_router_is_said_once_after_the_grace_time_and_its_arrival_once():
    bus = FakeBus(start=100.0)
    node = FakeNode("ros2_gateway", bus, ports=PORTS)
    said = Said()
    watch = PresenceWatch(node, ["drone"], said)
    bus.link_gap(True)
    bus.run_until(100.0 + GRACE_S - 0.1)
    watch.tick()
    assert said.take() == []  # still within the grace time
    bus.run_until(100.0 + GRACE_S)
    watch.tick()
    watch.tick()
    ((level, text),) = said.take()
    assert level == logging.WARNING
    assert text.startswith(f"no router reached at the default router after {GRACE_S:g} s")
    bus.link_gap(False)
    bus.schedule(bus.clock.monotonic() + 0.1, registry.STATE.key("drone"), State(connected=True))
    bus.run_until(bus.clock.monotonic() + 0.2)
    watch.tick()
    assert said.take() == [(logging.INFO, "router reached at the default router")]


def test_a_drone_that_sends_no_state_is_named_with_the_drones_online():
    bus = FakeBus(start=100.0)
    node = FakeNode("ros2_gateway", bus, ports=PORTS)
    bus.tokens.add(registry.ALIVE.key("drone1", service="bridge_mavlink"))
    said = Said()
    watch = PresenceWatch(node, ["drone1", "drone7"], said)
    bus.schedule(100.5, registry.STATE.key("drone1"), State(connected=True))
    bus.run_until(100.0 + GRACE_S)
    watch.tick()
    watch.tick()
    ((level, text),) = said.take()
    assert level == logging.WARNING
    assert text.startswith(
        f"no state from drone 'drone7' on drone7/mavros/state after {GRACE_S:g} s"
    )
    assert "(drones online: drone1;" in text
    bus.schedule(bus.clock.monotonic() + 0.1, registry.STATE.key("drone7"), State())
    bus.run_until(bus.clock.monotonic() + 0.2)
    watch.tick()
    assert said.take() == [(logging.INFO, "drone 'drone7': state arriving, presented")]


def test_the_declarations_are_one_info_line_and_each_key_at_debug(caplog):
    bus = FakeBus(start=100.0)
    node = FakeNode("ros2_gateway", bus, ports=PORTS)
    gateway = Gateway(node, Config(), RosSession())  # type: ignore[arg-type]
    with caplog.at_level(logging.DEBUG, logger="ros2_gateway"):
        gateway.start()
        log_started(gateway, "its own process")
    info = [r.getMessage() for r in caplog.records if r.levelno == logging.INFO]
    debug = [r.getMessage() for r in caplog.records if r.levelno == logging.DEBUG]
    assert len(info) == 1, info
    outs = sum(e.direction == "out" for e in ENTITIES.values())
    assert f": {outs} topics out, 1 in, " in info[0] and "--log-level DEBUG" in info[0]
    assert len(debug) == len(ENTITIES)
