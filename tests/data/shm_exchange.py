"""Two local peers exchange 640x480 frames over a router, print the SHM segments mapped, exit."""

from __future__ import annotations

import os
import sys
import time

from dronewrapper.msgs import Header, Image, registry
from dronewrapper.runtime.shm import mapped_segments
from support import client_node

router = sys.argv[1]
frame = os.urandom(640 * 480 * 3)
with client_node(router, name="a") as a, client_node(router, name="b") as b:
    latest = b.latest(registry.IMAGE_RAW, camera="cam_frontal")
    pub = a.publisher(registry.IMAGE_RAW, camera="cam_frontal")
    time.sleep(0.5)
    for _ in range(20):
        pub.put(
            Image(header=Header.now("cam_frontal"), height=480, width=640, step=1920, data=frame)
        )
        time.sleep(0.02)
    msg = latest.wait(10)
    assert bytes(msg.data) == frame and isinstance(msg.data, memoryview)
    print("\n".join(sorted(mapped_segments(os.getpid()))))
