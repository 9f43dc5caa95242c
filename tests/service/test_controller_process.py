"""The controller as a process: --help, a bad config exits 2, SIGINT exits 0."""

from __future__ import annotations

import subprocess

from support import REPO, python_module, wait_for

CONFIG = REPO / "services" / "controller" / "config" / "iris_sim.yaml"


def test_help_names_the_service():
    out = subprocess.run(
        python_module("dronewrapper_controller", "--help"),
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert out.returncode == 0 and "--config" in out.stdout and "--connect" in out.stdout


def test_bad_config_exits_2_naming_the_key(tmp_path):
    bad = tmp_path / "controller.yaml"
    bad.write_text(CONFIG.read_text() + "\nyaw_rat: {kp: 1}\n")
    out = subprocess.run(
        python_module("dronewrapper_controller", "--config", str(bad)),
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert out.returncode == 2 and "yaw_rat" in out.stderr


def test_sigint_while_waiting_for_the_bridge_exits_0(router, spawn):
    proc = spawn(
        python_module(
            "dronewrapper_controller", "--config", str(CONFIG), "--connect", router,
            "--set", "ready_timeout=60",
        ),
        name="controller",
    )  # fmt: skip
    wait_for(lambda: "waiting for the bridge" in proc.output(), 30, what="controller start")
    assert proc.stop() == 0
