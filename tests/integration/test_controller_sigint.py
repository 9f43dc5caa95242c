"""The controller as a real process on a loopback router: SIGINT while it waits for the bridge
exits 0 (its command line and logic are tested in tests/service/test_controller_*.py)."""

from __future__ import annotations

from support import REPO, python_module, wait_for

CONFIG = REPO / "services/controller/dronewrapper_controller" / "config" / "iris_sim.yaml"


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
