"""bridge_tello's pure core facing a scripted Tello in given time, with real SDK strings.

No sockets, threads or clock: the rig moves time itself in small steps, feeds the core the
Tello's state strings (the real field order, 10 Hz, tests/tello_peer.py's format) and its
replies (from a script, after a given delay, or never), and records every SDK command the core
asks to send, so a test reads exactly what would have reached the Tello's port 8889.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

from tello_peer import STATE

from dronewrapper.msgs.mavros import PositionTarget
from dronewrapper_bridge_base.bridge_node import COMMANDS
from dronewrapper_bridge_base.operation import Operation
from dronewrapper_bridge_tello.config import Config
from dronewrapper_bridge_tello.core import TelloCore

T0 = 1000.0  # monotonic s at the rig's start
EPOCH = 1.7e9  # wall-clock s added to the monotonic time for stamps
DT = 0.005  # s per rig step
USER = "user"  # the commander of the rig's setpoints and requests


class TelloRig:
    """A :class:`TelloCore` (``config`` overrides; no video) and the Tello it talks to.

    ``script`` maps a command to its reply (``None``: never answered; default ``ok``);
    ``delays`` maps a command to its reply delay in s (default ``reply_delay``);
    ``watched()`` says whether a subscriber matches the camera at each tick (the node's
    CameraWatch); ``video_on`` is the Tello's stream as its accepted switches left it.
    """

    def __init__(self, *, reply_delay: float = 0.02, **config: Any) -> None:
        config.setdefault("video", False)
        self.now = T0
        self.core = TelloCore(Config(**config), self.now)
        self.script: dict[str, str | None] = {"battery?": "80", "speed?": "100.0"}
        self.delays: dict[str, float] = {}
        self.reply_delay = reply_delay
        self.sent: list[tuple[float, str]] = []  # (time, SDK command the core sent)
        self.samples: list[tuple[float, Any, Any]] = []  # (time, topic, message published)
        self.flying = False
        self.height_cm = 0
        self.streaming_state = True  # the Tello sends its state string (False: link lost)
        self.watched: Callable[[], bool] = lambda: False
        self.video_on = False
        self.video_restarts: list[float] = []  # times the core told the receiver to restart
        self._replies: list[tuple[float, str]] = []  # (due, text)
        self._next_state = self.now
        self._next_tick = self.now

    # ---- the Tello's side

    def state_text(self) -> bytes:
        motor = int(self.now - T0) if self.flying else 0
        h = self.height_cm
        return STATE.format(tof=h + 10, h=h, t=motor).encode()

    def _answer(self, text: str) -> None:
        if text.startswith("rc "):
            return  # the Tello never answers rc
        reply = self.script.get(text, "ok")
        if text == "takeoff" and reply == "ok":
            self.flying, self.height_cm = True, 100
        if text == "land" and reply == "ok":
            self.flying, self.height_cm = False, 0
        if text in ("streamon", "streamoff") and reply == "ok":
            self.video_on = text == "streamon"
        verb, _, cm = text.partition(" ")
        if verb in ("up", "down") and reply == "ok":
            self.height_cm += int(cm) if verb == "up" else -int(cm)
        if reply is not None:
            delay = self.delays.get(text, self.reply_delay)
            self._replies.append((self.now + delay, reply))
            self._replies.sort()

    def reply_now(self, text: str) -> None:
        """A datagram from the Tello on the command port now (a late or stray reply)."""
        self.core.on_reply(text, self.now, self.now + EPOCH)
        self.collect()

    # ---- the rig

    def collect(self) -> None:
        """Take the core's outbox: record and answer its sends, record its samples."""
        out = self.core.take()
        if out.video_restart:
            self.video_restarts.append(self.now)
        for text in out.sends:
            self.sent.append((self.now, text))
            self._answer(text)
        for topic, msg in out.samples:
            self.samples.append((self.now, topic, msg))

    def step(self) -> None:
        """One rig step: due replies, the 10 Hz state string, the rc_rate_hz tick."""
        self.now += DT
        stamp = self.now + EPOCH
        while self._replies and self._replies[0][0] <= self.now:
            _, text = self._replies.pop(0)
            self.core.on_reply(text, self.now, stamp)
            self.collect()
        if self.now >= self._next_state:
            self._next_state += 0.1
            if self.streaming_state:
                self.core.on_state(self.state_text(), self.now, stamp)
                self.collect()
        if self.now >= self._next_tick:
            self._next_tick += 1.0 / self.core.config.rc_rate_hz
            self.core.tick(self.now, stamp, camera_watched=self.watched())
            self.collect()

    def run(self, seconds: float, until: Callable[[], bool] | None = None) -> None:
        """Step for ``seconds`` (or until ``until()`` holds)."""
        end = self.now + seconds
        while self.now < end and not (until is not None and until()):
            self.step()

    def connect(self) -> None:
        """State strings until the core is connected and in SDK mode."""
        self.run(5.0, until=lambda: self.core.connected and self.core.sdk_mode)
        assert self.core.connected and self.core.sdk_mode

    def start(
        self, steps: Callable[..., Any], request: Any = None, commander: str = USER
    ) -> Operation:
        """Start a service operation now, as the node hands a request from ``commander`` to the
        core (a command service's request goes through the lease; no request: the bridge's
        own operation)."""
        if request is None:
            op = self.core.start(steps(self.core), self.now, self.now + EPOCH)
        else:
            what = steps.__name__ if steps.__name__ in COMMANDS.values() else ""
            steps = steps(self.core, request)
            op = self.core.request(steps, commander, what, self.now, self.now + EPOCH)
        self.collect()
        return op

    def call(self, steps: Callable[..., Any], request: Any = None, limit=60.0, commander=USER):
        """A service call: start the operation and run until it is done; its reply."""
        op = self.start(steps, request, commander)
        self.run(limit, until=lambda: op.done)
        assert op.done, f"{op.name} still running after {limit} s"
        return op.result()

    def setpoint(self, target: PositionTarget, commander: str = USER) -> None:
        self.core.on_setpoint(target, commander, self.now, self.now + EPOCH)
        self.collect()

    def stream(
        self, target: PositionTarget, seconds: float, hz: float = 20.0, commander: str = USER
    ) -> None:
        """Publish ``target`` at ``hz`` for ``seconds``."""
        end, next_at = self.now + seconds, self.now
        while self.now < end:
            if self.now >= next_at:
                next_at += 1.0 / hz
                self.setpoint(target, commander)
            self.step()

    # ---- what the Tello received

    def commands(self, since: float = -math.inf) -> list[str]:
        """Non-rc commands received since ``since``."""
        return [t for at, t in self.sent if at >= since and not t.startswith("rc ")]

    def rcs(self, since: float = -math.inf) -> list[tuple[float, tuple[int, ...]]]:
        """(time, sticks) of every rc command since ``since``."""
        return [
            (at, tuple(int(v) for v in t.split()[1:]))
            for at, t in self.sent
            if at >= since and t.startswith("rc ")
        ]

    def published(self, topic: Any) -> list[Any]:
        return [msg for _, t, msg in self.samples if t is topic]
