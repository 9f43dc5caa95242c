"""The camera_victure service running in this process for a test: on the fake bus, or on a
real Zenoh router (tests/integration)."""

from __future__ import annotations

import threading
import time

from dronewrapper.msgs import registry
from dronewrapper.runtime.config import load_config
from dronewrapper.runtime.fake import FakeBus, FakeNode
from dronewrapper_camera_victure.config import Config
from dronewrapper_camera_victure.node import run
from support import ASSETS, REPO, client_node, wait_for

VIDEO = ASSETS / "video" / "vtest.avi"
CALIBRATION = REPO / "services" / "dronewrapper_camera_victure" / "config" / "victure_640x480.yaml"


class Running:
    """``run(node, config)`` on a thread, with a tester node subscribed to what it publishes:
    on the fake bus (no network: every frame published is received), or on a real Zenoh
    router when ``router`` is given."""

    def __init__(self, overrides: list[str], factory=None, *, router: str = "") -> None:
        self.config = load_config(Config, None, overrides)
        self.router = router
        if router:
            self.tester = client_node(router, name="tester", mode="client")
            self.node = client_node(router, name="camera_victure", mode="client")
        else:
            bus = FakeBus()
            self.tester, self.node = FakeNode("tester", bus), FakeNode("camera_victure", bus)
        camera = self.config.camera
        self.raw: list = []
        self.tester.subscribe(registry.IMAGE_RAW, self.raw.append, camera=camera)
        self.jpeg = self.tester.latest(registry.IMAGE_COMPRESSED, camera=camera)
        self.info = self.tester.latest(registry.CAMERA_INFO, camera=camera)
        self.status = self.tester.latest(registry.CAMERA_STATUS, camera=camera)
        self.result: list[int] = []
        kwargs = {"factory": factory} if factory else {}
        self.thread = threading.Thread(
            target=lambda: self.result.append(run(self.node, self.config, **kwargs)), daemon=True
        )

    def __enter__(self) -> Running:
        if self.router:
            time.sleep(0.2)  # let the subscriptions reach the router before frames flow
        self.thread.start()
        return self

    def __exit__(self, *exc) -> None:
        self.node.stop()
        self.thread.join(15)
        self.node.close()
        self.tester.close()

    def wait_status(self, predicate, timeout: float, what: str):
        """The first CameraStatus that satisfies ``predicate``."""
        wait_for(
            lambda: self.status.value is not None and predicate(self.status.value),
            timeout,
            what=what,
        )
        return self.status.value
