"""Every ``--help`` reads as plain text: no reST markup (double backticks) from docstrings."""

from __future__ import annotations

import runpy
import sys

import pytest

from dronewrapper.cli import main

SUBCOMMANDS = [
    "router", "keys", "echo", "alive", "doctor", "mavlink-forward", "up", "install",
    "uninstall", "sim", "detect",
    "station", "record", "replay", "foxglove",
]  # fmt: skip
SERVICES = [
    "dronewrapper_bridge_mavlink", "dronewrapper_bridge_tello", "dronewrapper_camera_victure",
    "dronewrapper_controller", "dronewrapper_perception", "dronewrapper_ground_station",
]  # fmt: skip


@pytest.mark.parametrize(
    "argv", [[], *([c] for c in SUBCOMMANDS)], ids=lambda a: a[0] if a else "dronewrapper"
)
def test_dronewrapper_help_is_plain_text(argv, capsys):
    if argv:
        with pytest.raises(SystemExit) as done:
            main([*argv, "--help"])
        assert done.value.code == 0
    else:
        assert main(["--help"]) == 0
    out = capsys.readouterr().out
    assert out.strip() and "``" not in out, out


@pytest.mark.parametrize("module", SERVICES)
def test_service_help_is_plain_text(module, capsys, monkeypatch):
    monkeypatch.setattr(sys, "argv", [module, "--help"])
    monkeypatch.delitem(sys.modules, f"{module}.__main__", raising=False)  # run afresh
    with pytest.raises(SystemExit) as done:
        runpy.run_module(module, run_name="__main__")
    assert done.value.code == 0
    out = capsys.readouterr().out
    assert out.strip() and "``" not in out, out


def test_a_service_help_lists_its_config_keys_with_defaults_and_what_they_are(capsys):
    import msgspec

    from dronewrapper_ros2_gateway.config import Config

    with pytest.raises(SystemExit):
        main(["ros2", "--help"])
    out = capsys.readouterr().out
    keys = out[out.index("config keys (--set KEY=VALUE") :]
    for field in msgspec.structs.fields(Config):
        assert f"\n  {field.name} = " in keys, field.name
    assert "  domain_id = 0\n      the ROS_DOMAIN_ID of the ROS 2 graph (0-232)" in keys
