"""The bridge's pure core facing a scripted autopilot in given time, over real MAVLink bytes.

No sockets, threads or clock: the rig moves time itself, packs the autopilot's messages with
pymavlink and decodes them again before the core sees them (ids, sequence numbers and
checksums as on the wire), and encodes every message the core asks to send, so a test reads
exactly what would have reached the autopilot.
"""

from __future__ import annotations

import math
import os
import struct
from typing import Any

os.environ.setdefault("MAVLINK20", "1")

from pymavlink.dialects.v20 import common as mavlink

from dronewrapper.msgs import registry
from dronewrapper.msgs.geometry import Vector3
from dronewrapper.msgs.mavros import FRAME_BODY_NED, MASK_VELOCITY, PositionTarget
from dronewrapper_bridge_base.bridge_node import COMMANDS
from dronewrapper_bridge_base.operation import Operation
from dronewrapper_bridge_mavlink import operations as ops
from dronewrapper_bridge_mavlink.config import Config
from dronewrapper_bridge_mavlink.core import BridgeCore
from dronewrapper_bridge_mavlink.outgoing import encode

PX4, ARDUPILOT = mavlink.MAV_AUTOPILOT_PX4, mavlink.MAV_AUTOPILOT_ARDUPILOTMEGA
OFFBOARD = 6 << 16
POSCTL = 3 << 16
AUTO_LOITER = (4 << 16) | (3 << 24)
AUTO_LAND = (4 << 16) | (6 << 24)
ARDU_GUIDED, ARDU_LOITER = 4, 5
SET_MODE = mavlink.MAV_CMD_DO_SET_MODE
ARM = mavlink.MAV_CMD_COMPONENT_ARM_DISARM
NAV_TAKEOFF = mavlink.MAV_CMD_NAV_TAKEOFF
NAV_LAND = mavlink.MAV_CMD_NAV_LAND
ACCEPTED = mavlink.MAV_RESULT_ACCEPTED
REJECTED = mavlink.MAV_RESULT_TEMPORARILY_REJECTED
T0 = 1000.0  # monotonic s at the rig's start
EPOCH = 1.7e9  # wall-clock s added to the monotonic time for stamps
ADDRESS = ("127.0.0.1", 14580)
USER = "user"  # the commander of the rig's setpoints and requests


def int_bits(value: int) -> float:
    """PX4's int32 parameter encoding: the int's bytes as a float."""
    return struct.unpack("<f", struct.pack("<i", value))[0]


def velocity(vx: float = 1.0) -> PositionTarget:
    """A body-velocity setpoint (forward ``vx`` m/s)."""
    return PositionTarget(
        coordinate_frame=FRAME_BODY_NED, type_mask=MASK_VELOCITY, velocity=Vector3(x=vx)
    )


class CoreRig:
    """A :class:`BridgeCore` (``config`` overrides) and the autopilot it talks to."""

    def __init__(self, *, autopilot: int = PX4, **config: Any) -> None:
        self.now = T0
        self.core = BridgeCore(Config(**config), self.now)
        self.autopilot = autopilot
        self._to_bridge = mavlink.MAVLink(None, srcSystem=1, srcComponent=1)
        self._decoder = mavlink.MAVLink(None)
        self.custom_mode = AUTO_LOITER if autopilot == PX4 else ARDU_LOITER
        self.armed = False
        self.sent: list[tuple[float, Any]] = []  # (time, message the core sent)
        self.samples: list[tuple[float, Any, Any]] = []  # (time, topic, message published)
        self._next_heartbeat = self.now
        self._boot_ms = 0

    # ---- the autopilot's side

    def packed(self, msg: Any) -> bytes:
        """``msg`` as the autopilot's next datagram."""
        buf = msg.pack(self._to_bridge)
        self._to_bridge.seq = (self._to_bridge.seq + 1) % 256  # as MAVLink.send counts
        return buf

    def deliver(self, msg: Any, source: Any = ADDRESS) -> None:
        """Send ``msg`` from the autopilot (packed, then decoded as the bridge would)."""
        self.deliver_bytes(self.packed(msg), source)

    def deliver_bytes(self, buf: bytes, source: Any = ADDRESS) -> None:
        """A datagram from the autopilot, as it is."""
        (decoded,) = self._decoder.parse_buffer(buf)
        self.core.on_mavlink(decoded, source, self.now, EPOCH + self.now)
        self._collect()

    def heartbeat(self) -> None:
        base_mode = mavlink.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED | (128 if self.armed else 0)
        self.deliver(
            mavlink.MAVLink_heartbeat_message(
                mavlink.MAV_TYPE_QUADROTOR, self.autopilot, base_mode, self.custom_mode, 4, 3
            )
        )

    def landed(self, state: int) -> None:
        """EXTENDED_SYS_STATE with MAV_LANDED_STATE ``state``."""
        self.deliver(mavlink.MAVLink_extended_sys_state_message(0, state))

    def pose(self, north: float = 0.0, east: float = 0.0, down: float = -5.0) -> None:
        """LOCAL_POSITION_NED (m, NED) with a rising time_boot_ms."""
        self._boot_ms = max(self._boot_ms + 1, int((self.now - T0) * 1000))
        self.deliver(
            mavlink.MAVLink_local_position_ned_message(
                self._boot_ms, north, east, down, 0.0, 0.0, 0.0
            )
        )

    def ack(self, command: int, result: int) -> None:
        self.deliver(mavlink.MAVLink_command_ack_message(command, result, 0, 0, 255, 191))

    def text(self, text: str, severity: int = mavlink.MAV_SEVERITY_WARNING) -> None:
        self.deliver(mavlink.MAVLink_statustext_message(severity, text.encode()))

    def param(self, name: str, raw: float, param_type: int) -> None:
        self.deliver(mavlink.MAVLink_param_value_message(name.encode(), raw, param_type, 1, 0))

    def connect(self, *, mode: int | None = None, armed: bool = False, flying: bool = False):
        """Heartbeat, pose and landed state: a connected autopilot in ``mode``."""
        self.custom_mode = self.custom_mode if mode is None else mode
        self.armed = armed
        self.heartbeat()
        self.pose(down=-5.0 if flying else 0.0)
        air = mavlink.MAV_LANDED_STATE_IN_AIR if flying else mavlink.MAV_LANDED_STATE_ON_GROUND
        self.landed(air)
        return self

    # ---- the bridge's side

    def _collect(self) -> None:
        out = self.core.take()
        for message in out.sends:
            self.sent.append((self.now, encode(message)))
        for topic, msg in out.samples:
            self.samples.append((self.now, topic, msg))

    def setpoint(self, target: PositionTarget | None = None, commander: str = USER) -> None:
        self.core.on_setpoint(target or velocity(), commander, self.now, EPOCH + self.now)
        self._collect()

    def call(self, steps: Any, request: Any, commander: str = USER) -> Operation:
        """A service request (``operations.takeoff`` ...) from ``commander`` now, as the node
        hands it to the core (a command service's request goes through the lease)."""
        what = steps.__name__ if steps.__name__ in COMMANDS.values() else ""
        op = self.core.request(steps(self.core, request), commander, what, self.now, self.stamp)
        self._collect()
        return op

    @property
    def stamp(self) -> float:
        return EPOCH + self.now

    def run(self, seconds: float, *, stream: bool = False, heartbeat_hz: float = 5.0) -> None:
        """Let ``seconds`` pass in stream ticks (30 Hz), with autopilot heartbeats and, with
        ``stream``, a commander's setpoint before each tick (``heartbeat_hz`` 0: none)."""
        end = self.now + seconds
        period = 1.0 / self.core.config.stream_rate_hz
        while self.now < end - 1e-9:
            self.now = min(end, self.now + period)
            if heartbeat_hz > 0 and self.now >= self._next_heartbeat:
                self._next_heartbeat = self.now + 1.0 / heartbeat_hz
                self.heartbeat()
            if stream:
                self.setpoint()
            self.core.tick(self.now, EPOCH + self.now)
            self._collect()

    # ---- what happened

    def sent_since(self, since: float, kind: str | None = None) -> list:
        return [m for t, m in self.sent if t >= since and (kind is None or m.get_type() == kind)]

    def commands(self, command: int, since: float = -math.inf) -> list:
        return [m for m in self.sent_since(since, "COMMAND_LONG") if m.command == command]

    def setpoints(self, since: float = -math.inf, mask: int | None = None) -> list:
        return [
            m
            for m in self.sent_since(since, "SET_POSITION_TARGET_LOCAL_NED")
            if mask is None or m.type_mask == mask
        ]

    def published(self, topic: Any, since: float = -math.inf) -> list:
        return [m for t, tp, m in self.samples if tp == topic and t >= since]

    def state(self) -> Any:
        return self.published(registry.STATE)[-1]


__all__ = ["CoreRig", "int_bits", "ops", "velocity"]
