"""Network tier: the drone and a laptop in two network namespaces joined by a slow link.

The drone namespace runs the router, the simulated Iris and its bridge
(`compose/sim_iris.yaml`); the laptop namespace runs an SDK app that reads both cameras, raw
(the worst case) or as JPEG (a remote SDK's default). The link is shaped with ``tbf`` to 20
Mbit/s, then 5 Mbit/s (no Wi-Fi carries two raw 640x480 cameras at 30 Hz, ~440 Mbit/s). Control
must not suffer: the pose's age (its stamp against this machine's clock, shared by both
namespaces) stays under 200 ms at the 95th percentile, and take-off and landing work.
"""

from __future__ import annotations

import contextlib
import json
import subprocess
import sys
import time
from collections.abc import Iterator

import pytest
from shaped_link import DRONE_ADDRESS, Link, is_root, shaped_link

from support import REPO, Process, wait_for

pytestmark = [
    pytest.mark.network,
    pytest.mark.skipif(not is_root(), reason="network namespaces need root (CI runs as root)"),
]

POSE_AGE_P95_S = 0.2


def read_events(probe: subprocess.Popen, on_reshape, timeout: float) -> list[dict]:
    events = []
    deadline = time.monotonic() + timeout
    for line in probe.stdout:
        event = json.loads(line)
        events.append(event)
        if event["event"] == "reshape":
            on_reshape()
        if event["event"] == "landed" or time.monotonic() > deadline:
            break
    return events


@pytest.fixture(scope="module")
def drone(tmp_path_factory) -> Iterator[tuple[Link, str]]:
    """The shaped link and the drone graph on it, shared by the raw and JPEG cases: each case
    flies its own take-off and landing, and the link is reshaped to 20 Mbit/s before each."""
    log_dir = tmp_path_factory.mktemp("slow_link")
    with shaped_link(20) as link:
        endpoint = f"tcp/{DRONE_ADDRESS}:7447"
        graph = Process(
            link.argv(
                link.drone,
                [
                    sys.executable,
                    "-m",
                    "dronewrapper",
                    "up",
                    "compose/sim_iris.yaml",
                    "--router",
                    endpoint,
                    "--insecure",  # plain TCP on a test link: transport behaviour, not security
                ],
            ),
            log_dir / "graph.log",
        )
        try:
            wait_for(lambda: "all processes ready" in graph.output(), 90, what="drone graph")
            yield link, endpoint
            assert graph.alive(), graph.output()[-3000:]
        finally:
            graph.stop(30)


@pytest.mark.parametrize("images", ["raw", "jpeg"])
def test_control_survives_a_slow_link_with_cameras_on(tmp_path, drone, images):
    link, endpoint = drone
    link.shape(20)
    with contextlib.ExitStack() as stack:
        errors = stack.enter_context(open(tmp_path / "probe.err", "w"))
        probe = subprocess.Popen(
            link.argv(
                link.laptop, [sys.executable, "tests/network/laptop_probe.py", endpoint, images]
            ),
            cwd=REPO,
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            stderr=errors,
            text=True,
        )

        def to_five_mbit() -> None:
            link.shape(5)
            probe.stdin.write("go\n")
            probe.stdin.flush()

        try:
            events = read_events(probe, to_five_mbit, timeout=240)
            assert probe.wait(60) == 0, (tmp_path / "probe.err").read_text()[-3000:]
        finally:
            if probe.poll() is None:
                probe.kill()
    by_name = {}
    for event in events:
        by_name.setdefault(event["event"], []).append(event)
    fast, slow = by_name["ages"]
    print(f"{images}: pose age at 20 Mbit/s: {fast}\n{images}: pose age at 5 Mbit/s: {slow}")
    assert fast["p95"] < POSE_AGE_P95_S and slow["p95"] < POSE_AGE_P95_S
    assert by_name["took_off"][0]["z"] > 1.3
    assert "landed" in by_name
    if images == "jpeg":  # JPEG frames do cross 20 Mbit/s (about 10 Mbit/s for two cameras)
        assert fast["frames"]["frontal"] >= 2 * 6.0  # at least 2 fps while sampling 6 s
