"""The registry's ``publishers`` are true: each process it names declares the topic in its
``PORTS`` (:mod:`dronewrapper.runtime.ports`), and no process declares a topic the registry does
not say it publishes. A node given its ports refuses anything outside them
(``tests/node_contract.py``), so what is declared is what the process can do.
"""

from __future__ import annotations

from typing import Any

import pytest

from dronewrapper.client.drone_client import CLIENT_PORTS
from dronewrapper.drone import WRAPPER_PORTS
from dronewrapper.mavlink_forward import PORTS as MAVLINK_FORWARD
from dronewrapper.msgs.registry import SERVICES, TOPICS
from dronewrapper.runtime.ports import Ports
from dronewrapper_bridge_mavlink.node import PORTS as BRIDGE_MAVLINK
from dronewrapper_bridge_px4_zenoh.node import PORTS as BRIDGE_PX4_ZENOH
from dronewrapper_bridge_tello.node import PORTS as BRIDGE_TELLO
from dronewrapper_camera_victure.node import PORTS as CAMERA_VICTURE
from dronewrapper_controller.node import PORTS as CONTROLLER
from dronewrapper_ground_station.node import PORTS as STATION
from dronewrapper_perception.node import PORTS as PERCEPTION
from dronewrapper_ros2_gateway.entities import PORTS as ROS2_GATEWAY
from dronewrapper_sim.cli import PORTS as SIM

DECLARED: dict[str, tuple[Ports, ...]] = {
    "bridge": (BRIDGE_MAVLINK, BRIDGE_PX4_ZENOH, BRIDGE_TELLO),
    "bridge_tello": (BRIDGE_TELLO,),
    "camera_victure": (CAMERA_VICTURE,),
    "perception": (PERCEPTION,),
    "controller": (CONTROLLER,),
    "sim": (SIM,),
    "teleop": (STATION,),
    "ros2_gateway": (ROS2_GATEWAY,),
    "gcs": (MAVLINK_FORWARD,),
    "sdk": (CLIENT_PORTS, WRAPPER_PORTS),
}
"""A publisher's name in the registry -> the ports of the processes (or SDK parts) it stands for
("bridge" is any bridge: each publishes the telemetry its aircraft has)."""
UNDECLARED = {"replay": "the recorder's replay (tools)", "tests": "test scripts"}
"""Publishers the registry names that run on a node without ports, and what they are."""
SERVERS = {"bridge": (BRIDGE_MAVLINK, BRIDGE_PX4_ZENOH, BRIDGE_TELLO), "sim": (SIM,)}
"""A service's ``server`` in the registry -> the ports of the processes that serve it."""


def _names_of(ports: Ports) -> set[str]:
    return {name for name, declared in DECLARED.items() if ports in declared}


def test_every_publisher_the_registry_names_is_declared_or_known():
    named = {p for topic in TOPICS.values() for p in topic.publishers}
    assert named <= set(DECLARED) | set(UNDECLARED), sorted(named - set(DECLARED) - set(UNDECLARED))
    assert not set(DECLARED) & set(UNDECLARED)


@pytest.mark.parametrize(
    ("name", "process"),
    [(name, p) for name, topic in TOPICS.items() for p in topic.publishers if p in DECLARED],
)
def test_each_publisher_the_registry_names_declares_the_topic(name, process):
    topic = TOPICS[name]
    declaring = [ports.process for ports in DECLARED[process] if topic in ports.publishes]
    assert declaring, (
        f"the registry says {process} publishes {name} ({topic.template}), but none of "
        f"{[p.process for p in DECLARED[process]]} declares it"
    )


@pytest.mark.parametrize(
    "ports",
    sorted({p for ps in DECLARED.values() for p in ps}, key=lambda p: p.process),
    ids=lambda p: p.process,
)
def test_no_process_declares_a_topic_the_registry_does_not_list_it_for(ports: Ports):
    names = _names_of(ports)
    unlisted = sorted(t.template for t in ports.publishes if not names & set(t.publishers))
    assert unlisted == [], f"{ports.process} ({sorted(names)}) publishes, unlisted: {unlisted}"


@pytest.mark.parametrize("server", sorted(SERVERS))
def test_each_server_serves_what_the_registry_says_and_nothing_else(server):
    listed = {s for s in SERVICES.values() if s.server == server}
    served: set[Any] = set().union(*(p.serves for p in SERVERS[server]))
    assert {s.template for s in listed - served} == set(), f"{server} serves none of these"
    assert {s.template for s in served - listed} == set(), f"the registry's server is not {server}"


def test_what_is_called_or_subscribed_has_a_server_or_a_publisher():
    everyone = {p for ps in DECLARED.values() for p in ps}
    for ports in everyone:
        for topic in ports.subscribes:
            assert topic.publishers, f"{ports.process} subscribes to {topic.template}: no publisher"
        for service in ports.calls:
            assert service.server in SERVERS, f"{ports.process} calls {service.template}"
