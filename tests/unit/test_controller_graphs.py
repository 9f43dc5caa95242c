"""The follow-app graphs resolve; every --config/--set they pass loads in the process schema."""

from __future__ import annotations

import importlib
import importlib.util

import pytest
from graph_argv import config_args, graph_argvs

from dronewrapper.runtime.config import load_config
from dronewrapper_compose.graph import REPO, load_graph

GRAPHS = [
    "sim_follow_color",
    "sim_follow_person",
    "px4_real_follow_person",
    "px4_real_follow_person_secure",
    "webcam_follow_color",
]

# module run by the graph -> "module:ConfigClass" of its strict config schema
SCHEMAS = {
    "dronewrapper_controller": "dronewrapper_controller.config:Config",
    "dronewrapper_camera_victure": "dronewrapper_camera_victure.config:Config",
    "dronewrapper_bridge_mavlink": "dronewrapper_bridge_mavlink.node:Config",
    "dronewrapper_perception": "dronewrapper_perception.config:Config",
}


def schema_for(module: str):
    path = SCHEMAS.get(module)
    if path is None:
        return None
    mod, _, cls = path.partition(":")
    return getattr(importlib.import_module(mod), cls)


@pytest.mark.parametrize("name", GRAPHS)
def test_graph_resolves_and_configs_load(name):
    checked = 0
    for spec, argv in graph_argvs(name, router="tcp/127.0.0.1:1"):
        assert "--connect" in argv and "tcp/127.0.0.1:1" in argv
        schema = schema_for(spec.module or "")
        if schema is not None:
            load_config(schema, *config_args(argv))
            checked += 1
    assert checked >= 3


@pytest.mark.parametrize(
    ("name", "mode"), [("sim_follow_color", "follow_color"), ("sim_follow_person", "follow_person")]
)
def test_sim_graphs_pick_the_mode_and_take_a_scenario(name, mode):
    from dronewrapper_controller.config import Config

    variables = {"scenario": "beacon_abrupt", "on_exit": "stop"}
    argvs = {spec.name: argv for spec, argv in graph_argvs(name, variables=variables)}
    assert argvs["sim"][argvs["sim"].index("--scenario") + 1] == "beacon_abrupt"
    config = load_config(Config, *config_args(argvs["controller"]))
    assert config.mode == mode and config.on_exit == "stop"


@pytest.mark.parametrize("path", sorted((REPO / "compose").glob("*.yaml")), ids=lambda p: p.stem)
def test_every_module_a_graph_runs_exists(path):
    """No graph names a module that is gone (the USB-camera stop-gap, replaced by
    camera_victure, was still named by the secure PX4 graph)."""
    modules = [spec.module for spec in load_graph(path).processes if spec.module]
    missing = [m for m in modules if importlib.util.find_spec(m) is None]
    assert not missing, f"{path.name} runs modules that do not exist: {missing}"
