"""`dronewrapper alive` and `dronewrapper doctor` against a real router and a slow bridge."""

from __future__ import annotations

import threading
import time

import pytest

from dronewrapper.msgs import registry
from dronewrapper.msgs.geometry import PoseStamped
from dronewrapper.msgs.mavros import ExtendedState, State
from dronewrapper.msgs.std import Header
from support import client_node, python_module, wait_for

pytestmark = pytest.mark.integration


def test_alive_and_doctor_name_the_drone_and_what_is_wrong(router, spawn):
    """A bridge that publishes its State and landed state but its pose at 5 Hz (the registry
    says 30) and no battery: alive shows the drone's kind and mode; doctor passes the router,
    names the slow pose and the missing battery, and exits 1."""
    with client_node(router, name="bridge_fake") as node:
        state = node.publisher(registry.STATE)
        extended = node.publisher(registry.EXTENDED_STATE)
        pose = node.publisher(registry.LOCAL_POSE)
        node.announce()
        stop = threading.Event()

        def publish() -> None:
            tick = 0
            while not stop.wait(0.02):
                now = time.time()
                tick += 1
                if tick % 10 == 0:  # 5 Hz
                    pose.put(PoseStamped(header=Header(stamp=now)))
                if tick % 25 == 0:  # 2 Hz
                    state.put(
                        State(
                            header=Header(stamp=now),
                            connected=True,
                            mode="POSCTL",
                            autopilot="tello",
                        )
                    )
                    extended.put(ExtendedState(header=Header(stamp=now), landed_state=1))

        thread = threading.Thread(target=publish, daemon=True)
        thread.start()
        try:
            alive = spawn(python_module("dronewrapper", "alive", "--connect", router), "alive")
            wait_for(lambda: not alive.alive(), 60, what="alive to finish")
            assert alive.proc.returncode == 0
            assert "drone 'drone' (tello): connected, mode POSCTL, disarmed" in alive.output()
            assert "  drone/alive/bridge_fake" in alive.output()

            doctor = spawn(
                python_module("dronewrapper", "doctor", "--connect", router, "--seconds", "3"),
                "doctor",
            )
            wait_for(lambda: not doctor.alive(), 90, what="doctor to finish")
            out = doctor.output()
            assert doctor.proc.returncode == 1, out
            assert f"ok   router {router} reachable" in out
            assert "warn drone/mavros/local_position/pose:" in out
            assert "expected >= 30 Hz" in out
            assert "FAIL drone/mavros/battery: - (declared 1 Hz): nothing arrived" in out
            assert "ok   drone/mavros/state" in out
            assert "Mbit/s through the router" in out
        finally:
            stop.set()
            thread.join(2)


def test_doctor_without_a_router_says_how_to_start_one(spawn):
    doctor = spawn(
        python_module("dronewrapper", "doctor", "--connect", "tcp/127.0.0.1:9", "--no-bandwidth"),
        "doctor",
    )
    wait_for(lambda: not doctor.alive(), 60, what="doctor to give up")
    assert doctor.proc.returncode == 1
    assert (
        "FAIL router: no router at tcp/127.0.0.1:9 (connection refused): "
        "start one with `dronewrapper up compose/GRAPH.yaml`" in doctor.output()
    )
    assert ".rs:" not in doctor.output()
