"""The laptop side of the slow-link test: an SDK app with both cameras on.

Run inside the laptop namespace: ``python laptop_probe.py ENDPOINT raw|jpeg``. It prints one
JSON line per event. ``raw`` reads both cameras raw (the worst case: ~220 Mbit/s each, more than
the link); ``jpeg`` reads them as JPEG (what a remote SDK takes by default). Phase one: connect,
read frames continuously, sample the pose's age (our clock minus its ``header.stamp``; both
namespaces share this machine's clock) for a few seconds, take off. Then it prints ``{"event":
"reshape"}`` and waits for a line on stdin (the test changes the link), then samples again and
lands.
"""

from __future__ import annotations

import json
import statistics
import sys
import threading
import time

from dronewrapper import DroneWrapper, NoData
from dronewrapper.runtime import Node, ZenohOptions

SAMPLE_S = 6.0
CAMERAS = ("frontal", "ventral")


def say(**event: object) -> None:
    print(json.dumps(event), flush=True)


def pose_ages(drone: DroneWrapper, seconds: float) -> dict[str, float]:
    ages = []
    end = time.monotonic() + seconds
    while time.monotonic() < end:
        pose = drone.inputs.pose.value
        if pose is not None:
            ages.append(time.time() - pose.header.stamp)
        time.sleep(0.02)
    ages.sort()
    return {
        "p50": statistics.median(ages),
        "p95": ages[int(0.95 * (len(ages) - 1))],
        "max": ages[-1],
        "n": len(ages),
    }


def main(endpoint: str, jpeg: bool) -> int:
    # no shared memory: this "laptop" shares the drone's /dev/shm, a real one does not
    options = ZenohOptions(mode="client", connect=[endpoint], shared_memory=False)
    node = Node("laptop_probe", options, handle_signals=False, open_timeout=60)
    drone = DroneWrapper(
        "drone", endpoint, timeout=60, node=node, cameras=CAMERAS, compressed_images=jpeg
    )
    frames = dict.fromkeys(CAMERAS, 0)
    stop = threading.Event()

    def read_frames() -> None:
        last: dict[str, float] = {}
        while not stop.wait(0.02):
            for camera in CAMERAS:
                try:
                    _, stamp = drone.get_image(camera, with_stamp=True)
                except NoData:
                    continue
                if stamp != last.get(camera):
                    last[camera] = stamp
                    frames[camera] += 1

    reader = threading.Thread(target=read_frames, daemon=True)
    reader.start()
    say(event="connected")
    say(event="ages", phase=1, **pose_ages(drone, SAMPLE_S), frames=dict(frames))
    drone.takeoff(h=1.5, timeout=90)
    say(event="took_off", z=float(drone.get_position()[2]), frames=dict(frames))
    say(event="reshape")
    sys.stdin.readline()
    say(event="ages", phase=2, **pose_ages(drone, SAMPLE_S))
    drone.land(timeout=90)
    say(event="landed", frames=dict(frames))
    stop.set()
    reader.join(2)
    drone.close()
    node.close()
    return 0


if __name__ == "__main__":
    raise SystemExit(main(sys.argv[1], sys.argv[2] == "jpeg"))
