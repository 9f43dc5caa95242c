"""bridge_mavlink's pure core facing the simulator's pure PX4-like autopilot, in virtual time.

No sockets, threads or clock: :class:`SimPair` steps the autopilot's physics at 250 Hz,
hands every message each side sends to the other as real MAVLink bytes (packed, then parsed
again), ticks the bridge at its stream rate and lets a test call the bridge's operations and
stream a commander's setpoints. Ground truth is the autopilot's own state (local ENU m), so a
flight is judged by where the vehicle really was, not by what the bridge was told.
"""

from __future__ import annotations

import math
import os
from collections.abc import Callable
from typing import Any

os.environ.setdefault("MAVLINK20", "1")

from clocked_autopilot import RATES
from pymavlink.dialects.v20 import common as mavlink

from dronewrapper.msgs.mavros import (
    CommandBool,
    CommandTOL,
    PositionTarget,
)
from dronewrapper_bridge_mavlink import operations as ops
from dronewrapper_bridge_mavlink.config import Config
from dronewrapper_bridge_mavlink.core import BridgeCore
from dronewrapper_bridge_mavlink.outgoing import encode
from dronewrapper_sim.px4.autopilot import Autopilot, AutopilotConfig

PHYSICS_HZ = 250.0
POLL_EVERY = 4  # physics steps between the autopilot's sends (62.5 Hz)
SETPOINT_HZ = 20.0
EPOCH = 1.7e9
ALIVE_PERIOD_S = 1.0


class SimPair:
    """The bridge core and the simulated autopilot, wired together (see module docstring)."""

    def __init__(
        self,
        *,
        wind: tuple[float, float] = (0.0, 0.0),
        params: dict[str, float] | None = None,
        start: tuple[float, float] = (0.0, 0.0),
        **bridge_config: Any,
    ) -> None:
        self.t = 0.0
        self.autopilot = Autopilot(
            AutopilotConfig(
                wind_east=wind[0],
                wind_north=wind[1],
                params=params or {},
                start_x=start[0],
                start_y=start[1],
            ),
            link_rates={"onboard": dict(RATES)},
        )
        bridge_config.setdefault("heartbeat_type", mavlink.MAV_TYPE_GCS)
        bridge_config.setdefault("message_rates", {})  # the rates below, kept low
        self.core = BridgeCore(Config(**bridge_config), self.t)
        self._ap_out = mavlink.MAVLink(None, srcSystem=1, srcComponent=1)
        self._bridge_out = mavlink.MAVLink(None, srcSystem=255, srcComponent=191)
        self._decode_at_bridge = mavlink.MAVLink(None)
        self._decode_at_ap = mavlink.MAVLink(None)
        self.samples: list[tuple[float, Any, Any]] = []  # (t, topic, message) published
        self.setpoint: PositionTarget | None = None
        self.truth: list[tuple[float, tuple[float, float, float], str]] = []  # t, pose, mode
        self.drop_to_autopilot: Callable[[Any], bool] = lambda msg: False
        self.drop_to_bridge: Callable[[Any], bool] = lambda msg: False
        self.alive: Callable[[], set[str]] = set  # the commanders beating (each ALIVE_PERIOD_S)
        self._next_alive = 0.0
        self.streaming: Callable[[], bool] = lambda: True  # whether a commander streams
        self._steps = 0
        self._next_tick = 0.0
        self._next_setpoint = 0.0

    # ---- wiring

    def _to_bridge(self, msgs: list[Any]) -> None:
        for msg in msgs:
            if self.drop_to_bridge(msg):
                continue
            buf = msg.pack(self._ap_out)
            self._ap_out.seq = (self._ap_out.seq + 1) % 256
            for decoded in self._decode_at_bridge.parse_buffer(buf) or []:
                self.core.on_mavlink(decoded, None, self.t, EPOCH + self.t)
        self._collect()

    def _collect(self) -> None:
        out = self.core.take()
        for topic, msg in out.samples:
            self.samples.append((self.t, topic, msg))
        for message in out.sends:
            buf = encode(message).pack(self._bridge_out)
            self._bridge_out.seq = (self._bridge_out.seq + 1) % 256
            for decoded in self._decode_at_ap.parse_buffer(buf) or []:
                if self.drop_to_autopilot(decoded):
                    continue
                self._to_bridge(self.autopilot.handle("onboard", decoded))

    def step(self) -> None:
        """One physics step, and what is due on the links."""
        dt = 1.0 / PHYSICS_HZ
        self.autopilot.step(dt)
        self.t += dt
        self._steps += 1
        if self._steps % POLL_EVERY == 0:
            self._to_bridge(self.autopilot.poll()["onboard"])
            s = self.autopilot.state
            self.truth.append((self.t, (s.x, s.y, s.z), self.autopilot.mode.name))
        if self.setpoint is not None and self.streaming() and self.t >= self._next_setpoint:
            self._next_setpoint = self.t + 1.0 / SETPOINT_HZ
            self.core.on_setpoint(self.setpoint, "", self.t, EPOCH + self.t)
            self._collect()
        if self.t >= self._next_alive and self.core.unattended.watching:
            self._next_alive = self.t + ALIVE_PERIOD_S  # as the bridge node's watch loop
            self.core.on_alive(self.alive(), self.t, EPOCH + self.t)
            self._collect()
        if self.t >= self._next_tick:
            self._next_tick = self.t + 1.0 / self.core.config.stream_rate_hz
            self.core.tick(self.t, EPOCH + self.t)
            self._collect()

    def run(self, seconds: float, until: Callable[[], bool] | None = None) -> bool:
        """Step for ``seconds`` of virtual time, or until ``until()``; whether it held."""
        end = self.t + seconds
        while self.t < end:
            self.step()
            if until is not None and until():
                return True
        return until is None

    def call(self, steps: Callable[..., Any], request: Any = None, limit: float = 30.0) -> Any:
        """A bridge operation (a service call), run to its end; its reply (or its error)."""
        args = (self.core,) if request is None else (self.core, request)
        op = self.core.start(steps(*args), self.t, EPOCH + self.t)
        self._collect()
        assert self.run(limit, until=lambda: op.done), f"{op.name} still running after {limit} s"
        return op.result()

    # ---- flights

    def connect(self) -> None:
        assert self.run(5.0, until=lambda: self.core.connected and self.core.pose() is not None)
        assert self.run(5.0, until=lambda: self.core.missions.home_geo is not None)

    def take_off(self, height: float) -> None:
        """Arm, NAV_TAKEOFF to ``height`` m above home, wait until there (AUTO.LOITER)."""
        self.connect()
        assert self.call(ops.arming, CommandBool(value=True)).success
        assert self.call(ops.takeoff, CommandTOL.takeoff(altitude=height)).success
        assert self.run(30.0, until=lambda: self.autopilot.state.z > height - 0.15)
        self.run(2.0)

    @property
    def position(self) -> tuple[float, float, float]:
        s = self.autopilot.state
        return (s.x, s.y, s.z)

    def published(self, topic: Any, since: float = -math.inf) -> list[Any]:
        return [m for t, tp, m in self.samples if tp == topic and t >= since]

    def closest_approach(self, point: tuple[float, float, float], since: float = 0.0) -> float:
        """The ground truth's closest distance (m) to ``point`` since ``since``."""
        return min(math.dist(p, point) for t, p, _ in self.truth if t >= since)
