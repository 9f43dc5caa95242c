"""Make the replay tier's recordings from the simulator (run by hand; the files are committed).

    .venv/bin/python tests/replay/record_sim.py            # every recording in RECORDINGS
    .venv/bin/python tests/replay/record_sim.py beacon_smooth

Each recording flies a follow graph on a private loopback router, waits until the controller is
tracking, then records the frontal camera (JPEG, a few frames per second), the telemetry,
ground truth, detections and controller status for a few seconds. ``holdout_teleop`` flies the
static-beacon scenario while this script steers the beacon along a path of its own (zig-zag and
a climb), a flight no tuning ever saw: it is the recording the tracker was never tuned on.
"""

from __future__ import annotations

import math
import subprocess
import sys
import threading
import time
from dataclasses import dataclass
from pathlib import Path

import zenoh

from dronewrapper.msgs import Twist, Vector3, codec, registry
from dronewrapper.msgs.control import CONTROLLER_TRACKING
from dronewrapper.runtime import ZenohOptions, open_session
from dronewrapper_compose.ports import free_port

REPO = Path(__file__).resolve().parents[2]
DATA = Path(__file__).resolve().parent / "data"
KEYS = [
    "drone/cam_frontal/image_raw",
    "drone/mavros/state",
    "drone/mavros/extended_state",
    "drone/mavros/local_position/pose",
    "drone/mavros/global_position/global",
    "drone/mavros/setpoint_raw/local",
    "drone/perception/detections",
    "drone/controller/status",
    "drone/sim/ground_truth",
    "sim/objects/*/pose",
]


@dataclass(frozen=True)
class Recording:
    """graph + scenario; ``start_when``: (object, y_min, y_max): start once the object is there
    walking north (ENU m)."""

    graph: str
    scenario: str
    seconds: float
    teleop: bool = False
    image_rate_hz: float = 6.0
    start_when: tuple[str, float, float] | None = None


RECORDINGS = {
    "beacon_smooth": Recording("sim_follow_color", "beacon_smooth", 3.0),
    "holdout_teleop": Recording("sim_follow_color", "beacon_static", 3.0, teleop=True),
    # person1 walks between the drone and the target: recorded from about 3 s before it
    # passes (the recorder takes a second to start), so a replay finds the target first
    "people_crossing_front": Recording(
        "sim_follow_person",
        "people_crossing_front",
        7.0,
        image_rate_hz=3.0,
        start_when=("person1", -5.0, -4.0),
    ),
}


def _wait_tracking(session: zenoh.Session, timeout: float) -> None:
    seen = threading.Event()

    def on_status(sample: zenoh.Sample) -> None:
        status = codec.decode(registry.CONTROLLER_STATUS.type, sample.payload.to_bytes())
        if status.state == CONTROLLER_TRACKING and status.target_visible:
            seen.set()

    sub = session.declare_subscriber(registry.CONTROLLER_STATUS.key(), on_status)
    try:
        if not seen.wait(timeout):
            raise TimeoutError(f"the controller did not track within {timeout:g} s")
    finally:
        sub.undeclare()


def _wait_object(session: zenoh.Session, name: str, y_min: float, y_max: float) -> None:
    there = threading.Event()

    last_y = [math.nan]

    def on_pose(sample: zenoh.Sample) -> None:
        y = codec.decode(registry.SIM_OBJECT_POSE.type, sample.payload.to_bytes()).pose.position.y
        if y_min <= y <= y_max and y > last_y[0]:  # there, and walking toward +y (north)
            there.set()
        last_y[0] = y

    sub = session.declare_subscriber(registry.SIM_OBJECT_POSE.key(name=name), on_pose)
    try:
        if not there.wait(60):
            raise TimeoutError(f"{name} did not reach y in [{y_min}, {y_max}] within 60 s")
    finally:
        sub.undeclare()


def _steer(session: zenoh.Session, stop: threading.Event) -> None:
    """The holdout path: the beacon weaves left-right and climbs, 0.6 m/s, 20 Hz commands."""
    pub = session.declare_publisher(registry.SIM_OBJECT_CMD_VEL.key(name="target"))
    t0 = time.monotonic()
    while not stop.wait(0.05):
        t = time.monotonic() - t0
        cmd = Twist(linear=Vector3(x=0.6 * math.sin(1.3 * t), y=0.25, z=0.15 * math.cos(0.7 * t)))
        pub.put(codec.encode(cmd))
    pub.undeclare()


def make(name: str) -> Path:
    spec = RECORDINGS[name]
    port = free_port()
    router = f"tcp/127.0.0.1:{port}"
    out = DATA / f"{name}.mcap"
    bin_ = REPO / ".venv" / "bin" / "dronewrapper"
    graph = subprocess.Popen(
        [
            *(str(bin_), "up", f"compose/{spec.graph}.yaml", "--router", router),
            *("--scenario", spec.scenario, "--duration", "120"),
        ],
        cwd=REPO,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    session = open_session(ZenohOptions(mode="client", connect=[router]), timeout=30)
    stop = threading.Event()
    try:
        _wait_tracking(session, 90)
        if spec.start_when is not None:
            _wait_object(session, *spec.start_when)
        steer = threading.Thread(target=_steer, args=(session, stop), daemon=True)
        if spec.teleop:
            steer.start()
        subprocess.run(
            [
                *(str(bin_), "record", *KEYS, "-o", str(out), "--connect", router),
                *("--duration", str(spec.seconds), "--compressed-images"),
                *("--jpeg-quality", "50", "--image-rate", str(spec.image_rate_hz)),
            ],
            cwd=REPO,
            check=True,
            timeout=spec.seconds + 60,
        )
    finally:
        stop.set()
        session.close()
        graph.terminate()
        try:
            graph.wait(60)
        except subprocess.TimeoutExpired:
            graph.kill()
            graph.wait()
    print(f"{out}: {out.stat().st_size / 1e3:.0f} KB")
    return out


if __name__ == "__main__":
    for name in sys.argv[1:] or list(RECORDINGS):
        make(name)
