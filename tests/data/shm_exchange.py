"""Two local peers exchange frames over a router: 640x480 ones, then 300 of the Tello's 960x720
(their header grows as ``seq`` passes 127 and 255); print the SHM segments mapped and the number
of puts that fell back from shared memory, exit."""

from __future__ import annotations

import os
import sys
import time

from dronewrapper.msgs import Header, Image, registry
from dronewrapper.runtime.shm import mapped_segments
from support import client_node, wait_for

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
    tello = os.urandom(960 * 720 * 3)
    for seq in range(300):
        header = Header(stamp=time.time(), frame_id="cam_frontal", seq=seq)
        pub.put(Image(header=header, height=720, width=960, step=2880, data=tello))
        time.sleep(0.002)
    wait_for(lambda: (m := latest.value) is not None and m.header.seq == 299, 10, what="frame 299")
    print(f"fallbacks {a.shm_writer.fallbacks}")
    print("\n".join(sorted(mapped_segments(os.getpid()))))
