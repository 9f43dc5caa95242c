"""The paper's first listing flies the simulated Tello (compose/sim_tello.yaml) unchanged.

The same file as for the Iris (examples/paper_listing.py, only its import line differs from the
paper's): take off to 2.5 m, spin at 1 rad/s for 5 s, land. The test watches the flight from
the sim's ground truth, so the bridge's own estimate is not what is judged.
"""

from __future__ import annotations

import itertools
import math
import os
import random
import subprocess
import sys
import threading

import pytest

from dronewrapper.msgs import registry
from dronewrapper.msgs.mavros import LANDED_STATE_ON_GROUND
from support import (
    REPO,
    Process,
    client_node,
    free_endpoint,
    python_module,
    wait_for,
    wait_for_bridges,
)

pytestmark = pytest.mark.integration


def yaw_of(pose) -> float:
    q = pose.pose.orientation
    return math.atan2(2 * (q.w * q.z + q.x * q.y), 1 - 2 * (q.y * q.y + q.z * q.z))


def test_paper_listing_flies_the_simulated_tello(tmp_path):
    source = (REPO / "examples" / "paper_listing.py").read_text()
    assert "drone = DroneWrapper()" in source and "drone.set_cmd_vel(az=1)" in source
    router = free_endpoint()
    address = f"127.{random.randint(10, 250)}.{random.randint(0, 255)}.{random.randint(2, 250)}"
    graph = Process(
        python_module(
            "dronewrapper", "up", "compose/sim_tello.yaml", "--router", router,
            "--var", f"address={address}",
        ),
        tmp_path / "sim_tello.log",
    )  # fmt: skip
    try:
        wait_for_bridges(router, {"drone": graph})
        with client_node(router, name="watcher") as watcher:
            truth = watcher.latest(registry.SIM_GROUND_TRUTH)
            ext = watcher.latest(registry.EXTENDED_STATE)
            state = watcher.latest(registry.STATE)
            wait_for(lambda: state.value and state.value.connected, 30, what="Tello connected")
            samples: list[tuple[float, float, float]] = []
            stop = threading.Event()

            def record() -> None:
                while not stop.wait(0.05):
                    pose = truth.value  # (truth stamp, yaw, z), each pose once
                    if pose is not None and (not samples or pose.header.stamp > samples[-1][0]):
                        samples.append((pose.header.stamp, yaw_of(pose), pose.pose.position.z))

            recorder = threading.Thread(target=record, daemon=True)
            recorder.start()
            env = {k: v for k, v in os.environ.items() if not k.startswith("DRONEWRAPPER_")}
            proc = subprocess.run(
                [sys.executable, str(REPO / "examples" / "paper_listing.py")],
                capture_output=True,
                text=True,
                timeout=150,
                env={**env, "DRONEWRAPPER_CONNECT": router},
                cwd=REPO,
            )
            stop.set()
            recorder.join(2)
            out = proc.stdout + proc.stderr
            assert proc.returncode == 0, f"the listing exited {proc.returncode}:\n{out[-3000:]}"
            assert max(z for *_, z in samples) == pytest.approx(2.5, abs=0.3)
            spinning = 0.0  # seconds turning counter-clockwise at about 1 rad/s (truth)
            for (t0, y0, _), (t1, y1, _) in itertools.pairwise(samples):
                rate = math.remainder(y1 - y0, math.tau) / (t1 - t0) if t1 > t0 else 0.0
                spinning += (t1 - t0) if 0.7 < rate < 1.3 else 0.0
            assert spinning > 3.5, f"spun at ~1 rad/s for {spinning:.1f} s of the listing's 5 s"
            assert samples[-1][2] < 0.1
            assert ext.value.landed_state == LANDED_STATE_ON_GROUND and not state.value.armed
    finally:
        graph.stop(30)
