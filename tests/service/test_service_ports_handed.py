"""Each service's entry point hands its declared ``PORTS`` to its node: ``run_service`` is run
with the node class swapped for one that records what it is given and opens nothing."""

from __future__ import annotations

import importlib
from typing import Any

import pytest

from dronewrapper.runtime import service
from dronewrapper.runtime.host import main_of

ENTRIES = {
    "dronewrapper_bridge_mavlink": "dronewrapper_bridge_mavlink.node",
    "dronewrapper_bridge_tello": "dronewrapper_bridge_tello.node",
    "dronewrapper_bridge_px4_zenoh": "dronewrapper_bridge_px4_zenoh.node",
    "dronewrapper_camera_victure": "dronewrapper_camera_victure.node",
    "dronewrapper_perception": "dronewrapper_perception.node",
    "dronewrapper_controller": "dronewrapper_controller.node",
    "dronewrapper_ground_station": "dronewrapper_ground_station.node",
    "dronewrapper_ros2_gateway": "dronewrapper_ros2_gateway.entities",
    "dronewrapper_ros2_gateway.cli": "dronewrapper_ros2_gateway.entities",
    "dronewrapper_sim": "dronewrapper_sim.cli",
}
"""A service's module (what ``python -m`` runs) -> the module declaring its ``PORTS``."""


@pytest.mark.parametrize("module", sorted(ENTRIES))
def test_the_entry_point_hands_its_ports_to_the_node(module, monkeypatch):
    given: list[Any] = []

    def no_node(name: str, options: Any, **kw: Any) -> Any:
        given.append(kw.get("ports"))
        raise ConnectionError("no session in this test")

    monkeypatch.setattr(service, "Node", no_node)
    assert main_of(module)([]) == 1
    assert given == [importlib.import_module(ENTRIES[module]).PORTS]
