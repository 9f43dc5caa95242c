"""bridge_mavlink's pure core on a real MAVLink link, in real time: the same calls as
tests/sim_pair.py (connect, call an operation, stream a setpoint, run until), against real
firmware (PX4 or ArduCopter SITL). Positions are the autopilot's own estimate (LOCAL_POSITION)
relative to home, the only truth a real autopilot tells."""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from typing import Any

from dronewrapper.msgs import registry
from dronewrapper.msgs.mavros import PositionTarget
from dronewrapper_bridge_mavlink.config import Config
from dronewrapper_bridge_mavlink.core import BridgeCore
from dronewrapper_bridge_mavlink.link import MavLink

SETPOINT_HZ = 20.0


class RealPair:
    """The core, its link, and a loop stepping both in real time."""

    def __init__(self, connection: str, **config: Any) -> None:
        config.setdefault("heartbeat_type", 6)  # GCS: the autopilots send their reasons
        self.config = Config(connection=connection, **config)
        self.link = MavLink(connection, source_system=255, source_component=191)
        self.link.open()
        self.core = BridgeCore(self.config, time.monotonic())
        self.setpoint: PositionTarget | None = None
        self.texts: list[str] = []
        self.reached: list[int] = []  # mission items reached, in order
        self.track: list[tuple[float, tuple[float, float, float], str]] = []  # t, ENU, mode
        self._next_tick = 0.0
        self._next_setpoint = 0.0

    def close(self) -> None:
        self.link.close()

    def _execute(self) -> None:
        out = self.core.take()
        for peer in out.peers:
            self.link.peer = peer
        for message in out.sends:
            self.link.send(message)
        for topic, msg in out.samples:
            if topic == registry.STATUSTEXT:
                self.texts.append(msg.text)
            elif topic == registry.MISSION_REACHED:
                self.reached.append(msg.wp_seq)

    def step(self) -> None:
        msg = self.link.recv(0.01)
        now = time.monotonic()
        if msg is not None:
            self.core.on_mavlink(msg, self.link.last_source, now, time.time())
            self._execute()
        if self.setpoint is not None and now >= self._next_setpoint:
            self._next_setpoint = now + 1.0 / SETPOINT_HZ
            self.core.on_setpoint(self.setpoint, "", now, time.time())
            self._execute()
        if now >= self._next_tick:
            self._next_tick = now + 1.0 / self.config.stream_rate_hz
            self.core.tick(now, time.time())
            self._execute()
            pose = self.core.pose()
            if pose is not None:
                mode = self.core.heartbeat_state.mode if self.core.heartbeat_state else ""
                self.track.append((now, self.position, mode))

    def run(self, seconds: float, until: Callable[[], bool] | None = None) -> bool:
        end = time.monotonic() + seconds
        while time.monotonic() < end:
            self.step()
            if until is not None and until():
                return True
        return until is None

    def call(self, steps: Callable[..., Any], request: Any = None, limit: float = 60.0) -> Any:
        args = (self.core,) if request is None else (self.core, request)
        op = self.core.start(steps(*args), time.monotonic(), time.time())
        self._execute()
        assert self.run(limit, until=lambda: op.done), f"{op.name} still running after {limit} s"
        return op.result()

    @property
    def mode(self) -> str:
        return self.core.heartbeat_state.mode if self.core.heartbeat_state else ""

    @property
    def armed(self) -> bool:
        return bool(self.core.heartbeat_state and self.core.heartbeat_state.armed)

    @property
    def position(self) -> tuple[float, float, float]:
        """ENU m from home (the autopilot's estimate)."""
        pose = self.core.pose()
        if pose is None:
            return (math.nan, math.nan, math.nan)
        hx, hy, hz = self.core.missions.home_local
        x, y, z = pose[0]
        return (x - hx, y - hy, z - hz)

    def closest_approach(self, point: tuple[float, float, float], since: float) -> float:
        return min(math.dist(p, point) for t, p, _ in self.track if t >= since)
