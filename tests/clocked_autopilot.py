"""The simulator's PX4-like autopilot as bridge_mavlink's link, in process, on the node's clock.

:class:`ClockedAutopilot` has the surface of :class:`~dronewrapper_bridge_mavlink.link.MavLink`
the bridge uses (``open``, ``send``, ``recv_batch``, ``counts`` ...) but no socket: what the
bridge sends is packed into real MAVLink bytes and parsed again at the autopilot, and what the
autopilot sends comes back the same way. The autopilot's physics moves (at 250 Hz) to the
clock's ``monotonic()`` whenever the link is used, and ``recv_batch`` waits through the clock,
so the real ``Bridge`` (its receive, stream and link-status threads included) runs on a fake
bus's virtual time with nothing swapped. Ground truth is the autopilot's own state.
"""

from __future__ import annotations

import os
import threading
from typing import Any

os.environ.setdefault("MAVLINK20", "1")

from pymavlink.dialects.v20 import common as mavlink

from dronewrapper.runtime.clock import Clock
from dronewrapper_bridge_mavlink.link import LinkCounts, Received
from dronewrapper_bridge_mavlink.outgoing import Send, encode
from dronewrapper_sim.px4.autopilot import Autopilot, AutopilotConfig

PHYSICS_S = 1.0 / 250.0
"""One physics step (s)."""
POLL_S = 0.016
"""How often the autopilot's streams are polled, as its own loop does (s)."""
RATES = {
    mavlink.MAVLINK_MSG_ID_HEARTBEAT: 1.0,
    mavlink.MAVLINK_MSG_ID_ATTITUDE_QUATERNION: 20.0,
    mavlink.MAVLINK_MSG_ID_LOCAL_POSITION_NED: 20.0,
    mavlink.MAVLINK_MSG_ID_GLOBAL_POSITION_INT: 5.0,
    mavlink.MAVLINK_MSG_ID_EXTENDED_SYS_STATE: 5.0,
    mavlink.MAVLINK_MSG_ID_HOME_POSITION: 1.0,
    mavlink.MAVLINK_MSG_ID_SYS_STATUS: 1.0,
}
"""The onboard link's streams (Hz), kept low."""


class ClockedAutopilot:
    """The autopilot behind a bridge's link on ``clock`` (see the module doc); ``stop``: the
    bridge node's stop event (a waiting ``recv_batch`` returns when it is set); ``source``:
    the bridge's MAVLink system and component ids (its config's); ``ground_station``: the
    autopilot has a GCS link too (no streams), for :meth:`from_ground_station`."""

    def __init__(
        self,
        clock: Clock,
        stop: threading.Event,
        source: tuple[int, int] = (255, 191),
        config: AutopilotConfig | None = None,
        ground_station: bool = False,
    ) -> None:
        links: dict[str, dict[int, float]] = {"onboard": dict(RATES)}
        if ground_station:
            links["gcs"] = {}
        self.autopilot = Autopilot(config or AutopilotConfig(), link_rates=links)
        self.truth: list[tuple[float, tuple[float, float, float], str]] = []  # t, pose, mode
        self.tap = None
        self.peer: Any = None
        self.rejected = 0
        self.sent = 0
        self.received: list[tuple[float, Any]] = []  # (clock's monotonic s, message) sent to it
        self._clock, self._stop = clock, stop
        self._t0 = clock.monotonic()
        self._polled = 0.0  # autopilot time of the last poll
        self._lock = threading.Lock()  # sends come from several threads
        self._open = False
        self._inbox: list[Any] = []  # parsed at the bridge, not yet received
        self._bytes_in = self._bytes_out = 0
        self._bridge_out = mavlink.MAVLink(None, srcSystem=source[0], srcComponent=source[1])
        self._autopilot_out = mavlink.MAVLink(None, srcSystem=1, srcComponent=1)
        self._at_autopilot = mavlink.MAVLink(None)
        self._at_bridge = mavlink.MAVLink(None)

    def open(self) -> None:
        self._open = True

    def close(self) -> None:
        self._open = False

    @property
    def is_open(self) -> bool:
        return self._open

    def counts(self) -> LinkCounts:
        return LinkCounts(self._bytes_in, self._bytes_out, 0)

    def write_raw(self, frame: bytes) -> None:
        raise OSError("no ground station on this link")

    def send(self, message: Send) -> bool:
        """One of the bridge's messages, as bytes to the autopilot; its replies queued."""
        with self._lock:
            self._catch_up()
            data = encode(message).pack(self._bridge_out)
            self._bridge_out.seq = (self._bridge_out.seq + 1) % 256
            self._bytes_out += len(data)
            for parsed in self._at_autopilot.parse_buffer(data) or []:
                self.received.append((self._clock.monotonic(), parsed))
                self._to_bridge(self.autopilot.handle("onboard", parsed))
            self.sent += 1
        return True

    def from_ground_station(self, msg: Any) -> list[Any]:
        """``msg`` (packed by a ground station's ``MAVLink``) handled on the autopilot's GCS
        link at the clock's now; the autopilot's replies to it."""
        with self._lock:
            self._catch_up()
            return self.autopilot.handle("gcs", msg)

    def recv_batch(self, timeout: float) -> list[Received]:
        """What the autopilot sent by the next poll (or ``timeout``), waited for on the clock."""
        self._clock.wait(self._stop, min(timeout, POLL_S))
        with self._lock:
            self._catch_up()
            inbox, self._inbox = self._inbox, []
        return [Received(msg, None) for msg in inbox]

    def _catch_up(self) -> None:
        """Physics up to the clock's now, the streams polled on the way (under the lock)."""
        now = self._clock.monotonic() - self._t0
        while self.autopilot.time_s + PHYSICS_S <= now:
            self.autopilot.step(PHYSICS_S)
            if self.autopilot.time_s - self._polled >= POLL_S:
                self._polled = self.autopilot.time_s
                self._to_bridge(self.autopilot.poll()["onboard"])
                state = self.autopilot.state
                pose = (state.x, state.y, state.z)
                self.truth.append((self.autopilot.time_s, pose, self.autopilot.mode.name))

    def _to_bridge(self, msgs: list[Any]) -> None:
        for msg in msgs:
            data = msg.pack(self._autopilot_out)
            self._autopilot_out.seq = (self._autopilot_out.seq + 1) % 256
            self._bytes_in += len(data)
            self._inbox.extend(self._at_bridge.parse_buffer(data) or [])
