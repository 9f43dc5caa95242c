"""The Tello graphs exist under their fixed names, resolve, and every config they pass loads."""

from __future__ import annotations

import pytest
from graph_argv import config_args, graph_argvs

from dronewrapper.runtime.config import ConfigError, load_config
from dronewrapper_bridge_tello.node import Config as BridgeConfig
from dronewrapper_compose.graph import REPO
from dronewrapper_controller.config import Config as ControllerConfig
from dronewrapper_perception.config import Config as PerceptionConfig

GRAPHS = ["sim_tello", "sim_tello_follow_color", "sim_tello_follow_person", "tello_follow_person"]
SCHEMAS = {
    "dronewrapper_bridge_tello": BridgeConfig,
    "dronewrapper_controller": ControllerConfig,
    "dronewrapper_perception": PerceptionConfig,
}


@pytest.mark.parametrize("name", GRAPHS)
def test_tello_graph_resolves_and_configs_load(name):
    modules = []
    for spec, argv in graph_argvs(name, router="tcp/127.0.0.1:1"):
        modules.append(spec.module)
        schema = SCHEMAS.get(spec.module or "")
        if schema is not None:
            load_config(schema, *config_args(argv))
    assert "dronewrapper_bridge_tello" in modules
    assert ("dronewrapper_sim" in modules) == name.startswith("sim_")


def test_tello_controller_config_is_for_the_tello():
    config = load_config(
        ControllerConfig,
        str(REPO / "services/controller/dronewrapper_controller/config/tello.yaml"),
        [],
    )
    assert config.aircraft == "tello"


def test_bridge_config_is_strict_and_names_the_bad_key(tmp_path):
    bad = tmp_path / "b.yaml"
    bad.write_text("tello_adress: 1.2.3.4\n")
    with pytest.raises(ConfigError, match="tello_adress"):
        load_config(BridgeConfig, str(bad), [])
    with pytest.raises(ConfigError, match="rc_rate_hz"):
        load_config(BridgeConfig, None, ["rc_rate_hz=5"])
    with pytest.raises(ConfigError, match="max_stick"):
        load_config(BridgeConfig, None, ["scale.max_stick=300"])
    for shipped in ("sim.yaml", "tello.yaml"):
        load_config(
            BridgeConfig,
            str(REPO / "services/bridge_tello/dronewrapper_bridge_tello/config" / shipped),
            [],
        )
