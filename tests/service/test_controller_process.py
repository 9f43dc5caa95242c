"""The controller's command line, in-process (the logic is tested on the fake bus in
test_controller_node.py; a real process stopped by SIGINT in
tests/integration/test_controller_sigint.py)."""

from __future__ import annotations

import pytest

import dronewrapper_controller
from dronewrapper.runtime.service import run_service
from dronewrapper_controller.config import Config
from dronewrapper_controller.node import run
from support import REPO

CONFIG = REPO / "services/controller/dronewrapper_controller" / "config" / "iris_sim.yaml"


def main(*argv: str) -> int:
    """What ``python -m dronewrapper_controller ARGV`` runs, in this process."""
    return run_service("controller", dronewrapper_controller.__doc__, Config, run, list(argv))


def test_help_names_the_flags(capsys):
    with pytest.raises(SystemExit) as exit_:
        main("--help")
    out = capsys.readouterr().out
    assert exit_.value.code == 0 and "--config" in out and "--connect" in out


def test_bad_config_exits_2_naming_the_key(tmp_path, capsys):
    bad = tmp_path / "controller.yaml"
    bad.write_text(CONFIG.read_text() + "\nyaw_rat: {kp: 1}\n")
    assert main("--config", str(bad)) == 2
    assert "yaw_rat" in capsys.readouterr().err
