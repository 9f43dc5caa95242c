"""Every example in examples/ runs against the simulator (compose/sim_iris.yaml) and does its job.

The examples take the router from ``DRONEWRAPPER_CONNECT`` (the paper's listing has no
arguments), so each runs unchanged as a child process, while the test watches the aircraft
through its own DroneWrapper (which only reads, never commands).
"""

from __future__ import annotations

import subprocess
import sys
import threading
import time
from collections.abc import Iterator

import cv2
import pytest

from dronewrapper import DroneWrapper
from dronewrapper.msgs.mavros import LANDED_STATE_ON_GROUND
from dronewrapper_compose.launcher import Launcher
from support import REPO, free_endpoint

pytestmark = pytest.mark.integration

EXAMPLES = REPO / "examples"


def run_example(name: str, router: str, *args: str, timeout: float = 120) -> str:
    proc = subprocess.run(
        [sys.executable, str(EXAMPLES / name), *args],
        capture_output=True,
        text=True,
        timeout=timeout,
        env={**_env(), "DRONEWRAPPER_CONNECT": router},
        cwd=REPO,
    )
    out = proc.stdout + proc.stderr
    assert proc.returncode == 0, f"{name} exited {proc.returncode}:\n{out[-4000:]}"
    return out


def _env() -> dict[str, str]:
    import os

    return {k: v for k, v in os.environ.items() if not k.startswith("DRONEWRAPPER_")}


@pytest.fixture(scope="module")
def watcher(sim_iris) -> Iterator[DroneWrapper]:
    with DroneWrapper("drone", sim_iris, timeout=30, cameras=()) as drone:
        yield drone


class Recorder(threading.Thread):
    """Samples the watched drone at 20 Hz while an example runs."""

    def __init__(self, drone: DroneWrapper) -> None:
        super().__init__(daemon=True)
        self.drone = drone
        self.stop = threading.Event()
        self.samples: list[tuple[float, float, float]] = []  # (time s, yaw rate, altitude)

    def run(self) -> None:
        while not self.stop.wait(0.05):
            z = float(self.drone.get_position()[2])
            self.samples.append((time.monotonic(), self.drone.get_yaw_rate(), z))

    def seconds_where(self, condition) -> float:
        """Total time (s) between consecutive samples during which ``condition(rate)`` held."""
        pairs = zip(self.samples, self.samples[1:], strict=False)
        return sum(b[0] - a[0] for a, b in pairs if condition(a[1]) and condition(b[1]))

    def __enter__(self) -> Recorder:
        self.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self.stop.set()
        self.join(2)


def test_paper_listing(sim_iris, watcher):
    source = (EXAMPLES / "paper_listing.py").read_text()
    assert "drone = DroneWrapper()" in source and "drone.set_cmd_vel(az=1)" in source
    with Recorder(watcher) as rec:
        run_example("paper_listing.py", sim_iris)
    assert max(z for *_, z in rec.samples) == pytest.approx(2.5, abs=0.3)
    spinning = rec.seconds_where(lambda rate: rate > 0.8)
    assert spinning > 3.5, f"spun at ~1 rad/s for {spinning:.1f} s of the listing's 5 s"
    assert watcher.get_landed_state() == LANDED_STATE_ON_GROUND
    assert not watcher.get_state().armed


def test_square(sim_iris, watcher):
    out = run_example("square.py", sim_iris, "--side", "1", "--height", "1")
    assert out.count("corner reached") == 4
    assert "landed" in out
    assert watcher.get_landed_state() == LANDED_STATE_ON_GROUND


def test_mission(sim_iris, watcher):
    out = run_example("mission.py", sim_iris, "--side", "6", "--height", "3", timeout=240)
    assert "uploaded 4 waypoints" in out and "mission: reached 4 of 4" in out
    assert watcher.get_landed_state() == LANDED_STATE_ON_GROUND
    x, y, _ = watcher.get_position()
    assert (x**2 + y**2) ** 0.5 < 1.0  # back home


def test_save_frames(sim_iris, tmp_path):
    out_dir = tmp_path / "frames"
    argv = ["--count", "3", "--rate", "10", "--ventral", "--out", str(out_dir)]
    out = run_example("save_frames.py", sim_iris, *argv)
    files = sorted(p.name for p in out_dir.iterdir())
    assert files == [f"{cam}_{i:04d}.png" for cam in ("frontal", "ventral") for i in range(3)]
    for path in out_dir.iterdir():
        image = cv2.imread(str(path))
        assert image is not None and image.ndim == 3 and image.std() > 1.0
    assert "captured" in out


def test_swarm_of_three(tmp_path):
    """The fleet the example's docstring starts (compose/sim_fleet.yaml: three simulated Iris
    with cameras off, a process for each sim and each bridge), brought up in this process."""
    names = ["drone1", "drone2", "drone3"]
    router = free_endpoint()
    with (
        open(tmp_path / "sim_fleet.log", "w") as log,
        Launcher.from_file("sim_fleet", router=router, variables={"drones": "3"}, out=log) as graph,
    ):
        out = run_example("swarm.py", router, "--connect", router, "--side", "0.5", timeout=240)
    assert graph.exit_code == 0, (tmp_path / "sim_fleet.log").read_text()[-3000:]
    assert "swarm of 3: drone1, drone2, drone3" in out
    for ns, height in zip(names, ("1", "1.5", "2"), strict=True):
        assert f"{ns}: flew its square at {height} m and landed" in out
