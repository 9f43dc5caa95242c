"""The toy aircraft (tests/fake_aircraft.py) on a real Zenoh router, ticked by its own thread.

:class:`FakeBridge` is a :class:`~fake_aircraft.FakeAircraft` on a client session: telemetry
at 20 Hz stamped with wall-clock time, a silent frontal camera key (the SDK subscribes on
demand), simulated objects' poses, PX4's and ArduPilot's modes only, a climb and a landing at
4 m/s, OFFBOARD only once a setpoint stream has arrived. It records every setpoint with its
monotonic arrival time. It lets the SDK, the controller and the ground station tests check
their side of the contract on the wire (order of calls, keys, masks, rates, error messages) in
a fraction of a second per test.
"""

from __future__ import annotations

import math
import threading
import time

from dronewrapper.msgs.mavros import PositionTarget, SetMode, SetModeResult
from dronewrapper.runtime import Ratekeeper
from fake_aircraft import FakeAircraft
from support import client_node, wait_for

MODES = ("OFFBOARD", "POSCTL", "AUTO.LOITER", "AUTO.LAND", "GUIDED")
"""The modes this bridge knows; another is refused (result 4, ``unknown mode NAME``)."""
RATE_HZ = 20
"""Its ticks (telemetry, motion) a second."""
SPEED = 4.0
"""Its climb and landing speed (m/s)."""
STREAM_WAIT_S = 5.0
"""How long SET_MODE OFFBOARD waits for a first setpoint (s; the real bridge primes for > 1 s
before asking and waits up to 3 s more for a stream; generous here for a busy machine)."""


class FakeBridge(FakeAircraft):
    """A PX4-like bridge in one thread on the router at ``endpoint`` (see the module doc).

    ``flying``: start armed in OFFBOARD at ``position``'s altitude (2 m when that is 0), else on
    the ground in POSCTL. ``objects``: simulated object poses (name -> x, y, z in m, ENU)
    published each tick. ``name``: the node's name (its liveliness token).
    """

    def __init__(
        self,
        endpoint: str,
        ns: str = "drone",
        *,
        connected: bool = True,
        autopilot: str = "px4",
        flying: bool = False,
        position: tuple[float, float, float] = (1.0, 0.0, 0.0),
        objects: dict[str, tuple[float, float, float]] | None = None,
        name: str = "bridge_fake",
    ) -> None:
        self.lock = threading.Lock()
        self.setpoints: list[tuple[float, PositionTarget]] = []  # (monotonic arrival s, msg)
        super().__init__(
            client_node(endpoint, name=name, namespace=ns, mode="client"),
            time.time,
            flying=flying,
            autopilot=autopilot,
            position=position,
            climb_rate=SPEED,
            landing_speed=SPEED,
            ground_mode="POSCTL",
            modes=MODES,
            offboard_needs_stream=True,
            camera="cam_frontal",
            objects=objects,
        )
        self.connected = connected
        self.node.announce()
        self.thread = threading.Thread(target=self._run, daemon=True)
        self.thread.start()

    def _on_setpoint(self, sp: PositionTarget) -> None:
        with self.lock:
            self.setpoints.append((time.monotonic(), sp))
            super()._on_setpoint(sp)

    def _set_mode(self, req: SetMode) -> SetModeResult:
        """As the real bridge: give the setpoint stream a moment to arrive before OFFBOARD."""
        deadline = time.monotonic() + STREAM_WAIT_S
        while req.custom_mode == "OFFBOARD" and not self.streamed and time.monotonic() < deadline:
            time.sleep(0.01)
        return super()._set_mode(req)

    def wait(self, done, seconds: float) -> None:
        """Poll ``done()`` while the aircraft's own thread flies it (up to ``seconds``)."""
        deadline = time.monotonic() + seconds
        while not done() and time.monotonic() < deadline:
            time.sleep(0.01)

    # what the tests read
    def setpoints_since(self, t0: float) -> list[PositionTarget]:
        """The setpoints that arrived at or after ``t0`` (monotonic s)."""
        with self.lock:
            return [msg for t, msg in self.setpoints if t >= t0]

    def wait_quiet(self, quiet: float = 0.5, timeout: float = 10.0) -> None:
        """Wait until no setpoint has arrived for ``quiet`` s (fails if the stream goes on).

        Setpoints already in flight when a stream stops still arrive meanwhile.
        """

        def silent_for() -> float:
            with self.lock:
                last = self.setpoints[-1][0] if self.setpoints else -math.inf
            return time.monotonic() - last

        wait_for(lambda: silent_for() >= quiet, timeout, what="the setpoint stream to stop")

    def _run(self) -> None:
        rate = Ratekeeper(RATE_HZ, stop=self.node.stop_event)
        while rate.sleep():
            try:
                self.tick(time.time())
            except Exception:  # the session closed under it
                return

    def close(self) -> None:
        self.node.close()
        self.thread.join(5)
