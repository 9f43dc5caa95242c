"""The camera_victure service running in this process for a test: on the fake bus in virtual
time, or on a real Zenoh router in real time (tests/integration)."""

from __future__ import annotations

import time

from dronewrapper.msgs import registry
from dronewrapper.runtime.clock import REAL, VirtualClock
from dronewrapper.runtime.config import load_config
from dronewrapper.runtime.fake import FakeBus, FakeNode
from dronewrapper_camera_victure.config import Config
from dronewrapper_camera_victure.node import CLOSE_WAIT_S, PORTS, run
from support import ASSETS, REPO, client_node, wait_for

VIDEO = ASSETS / "video" / "vtest.avi"
CALIBRATION = (
    REPO / "services/camera_victure/dronewrapper_camera_victure" / "config" / "victure_640x480.yaml"
)


class Running:
    """``run(node, config)`` on a thread, with a tester node subscribed to what it publishes.

    On the fake bus (no network: every frame published is received) the service runs in the
    virtual time of ``clock`` (a new :class:`VirtualClock` unless given; give the same one to a
    fake capture): :meth:`until` moves it, and what the test reads there is settled (every
    thread of the service waits). On a real Zenoh router (``router`` given) it runs in real time.
    """

    def __init__(
        self,
        overrides: list[str],
        factory=None,
        *,
        router: str = "",
        clock: VirtualClock | None = None,
    ) -> None:
        self.config = load_config(Config, None, overrides)
        self.router = router
        if router:
            self.clock = REAL
            self.tester = client_node(router, name="tester", mode="client")
            self.node = client_node(router, name="camera_victure", mode="client")
        else:
            self.clock = clock or VirtualClock()
            bus = FakeBus(clock=self.clock)
            self.tester, self.node = (
                FakeNode("tester", bus),
                FakeNode("camera_victure", bus, ports=PORTS),
            )
        camera = self.config.camera
        self.raw: list = []
        self.tester.subscribe(registry.IMAGE_RAW, self.raw.append, camera=camera)
        self.jpeg = self.tester.latest(registry.IMAGE_COMPRESSED, camera=camera)
        self.info = self.tester.latest(registry.CAMERA_INFO, camera=camera)
        self.status = self.tester.latest(registry.CAMERA_STATUS, camera=camera)
        self.result: list[int] = []
        kwargs = {"factory": factory} if factory else {}

        def service() -> None:
            self.result.append(run(self.node, self.config, **kwargs))

        self.thread = self.clock.thread(service, "camera-service")

    def __enter__(self) -> Running:
        if self.router:
            time.sleep(0.2)  # let the subscriptions reach the router before frames flow
        self.thread.start()
        return self

    def __exit__(self, *exc) -> None:
        self.node.stop()
        if isinstance(self.clock, VirtualClock):
            try:
                self.clock.run_until(
                    lambda: self.thread.finished, CLOSE_WAIT_S + 10, "the service to stop"
                )
            except AssertionError:
                if exc[0] is None:  # else the test's own failure is the one to report
                    raise
        self.thread.join(15)
        self.node.close()
        self.tester.close()

    def until(self, predicate, timeout: float, what: str):
        """Run until ``predicate()`` (at most ``timeout`` s of the service's time); its value."""
        if isinstance(self.clock, VirtualClock):
            self.clock.run_until(predicate, timeout, what)
            return predicate()
        return wait_for(predicate, timeout, what=what)

    def wait_status(self, predicate, timeout: float, what: str):
        """The first CameraStatus that satisfies ``predicate``."""
        self.until(
            lambda: self.status.value is not None and predicate(self.status.value), timeout, what
        )
        return self.status.value
