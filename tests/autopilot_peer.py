"""A minimal PX4-like MAVLink peer on a real UDP socket, for the safety and fuzz tests.

It streams telemetry (LOCAL_POSITION_NED and ATTITUDE at 50 Hz with a rising time_boot_ms,
HEARTBEAT and EXTENDED_SYS_STATE at 5 Hz), answers parameter reads, and records every message
the bridge sends, so a test can assert that nothing reached the autopilot. It never accepts an
actuating command by itself: COMMAND_LONGs are acknowledged UNSUPPORTED (except the bridge's
own SET_MESSAGE_INTERVAL), so a request that slipped through would still be visible on the wire.
Raw datagrams can be sent too (``send_raw``) to duplicate or reorder them.
"""

from __future__ import annotations

import contextlib
import os
import struct
import threading
import time
from collections.abc import Iterator

os.environ.setdefault("MAVLINK20", "1")

from pymavlink.dialects.v20 import common as mavlink

from support import loopback_udp, start_daemons, stop_daemons

# PX4 custom modes (main mode << 16 | sub mode << 24; see sim/dronewrapper_sim/px4/modes.py)
OFFBOARD = 6 << 16
AUTO_LOITER = (4 << 16) | (3 << 24)
AUTO_RTL = (4 << 16) | (5 << 24)
ARMED = mavlink.MAV_MODE_FLAG_SAFETY_ARMED
# What the bridge may send that does not make the aircraft do anything.
PASSIVE = frozenset({"HEARTBEAT", "PARAM_REQUEST_READ"})


def int_bits(value: int) -> float:
    """PX4's int32 parameter encoding: the int's bytes as a float."""
    return struct.unpack("<f", struct.pack("<i", value))[0]


class AutopilotPeer:
    """A scripted autopilot sending to the bridge's ``udpin`` port from its own UDP socket."""

    def __init__(self, bridge_port: int, *, system: int = 1, telemetry: bool = True) -> None:
        self.bridge = ("127.0.0.1", bridge_port)
        self.sock = loopback_udp(0.1)
        self.address = self.sock.getsockname()
        self.mav = mavlink.MAVLink(None, srcSystem=system, srcComponent=1)
        self.mav.robust_parsing = True
        self.custom_mode = AUTO_LOITER
        self.armed = False
        self.system_status = 4
        self.heartbeats = True
        self.telemetry = telemetry
        self.north = 0.0
        self.params = {"MPC_XY_VEL_MAX": (12.0, 9), "COM_RC_IN_MODE": (int_bits(1), 6)}
        self.received: list[tuple[float, object]] = []
        self.sent_poses = 0
        self._boot = time.monotonic()
        self._lock = threading.RLock()
        self._stop = threading.Event()
        self._threads = start_daemons(self._send_loop, self._recv_loop)

    def close(self) -> None:
        stop_daemons(self._stop, self._threads)
        self.sock.close()

    # ---- sending ----

    def boot_ms(self) -> int:
        return int((time.monotonic() - self._boot) * 1000)

    def pack(self, msg) -> bytes:
        """Pack ``msg`` with the next seq (thread-safe)."""
        with self._lock:
            data = msg.pack(self.mav)
            self.mav.seq = (self.mav.seq + 1) % 256  # pack() alone does not advance it
            return data

    def send_raw(self, data: bytes) -> None:
        self.sock.sendto(data, self.bridge)

    def send(self, msg) -> bytes:
        """Pack and send ``msg``, no other message of this peer packed in between."""
        with self._lock:
            data = self.pack(msg)
            self.send_raw(data)
        return data

    @contextlib.contextmanager
    def exclusive(self) -> Iterator[None]:
        """While inside, this peer's telemetry thread packs and sends nothing: a test's own
        packs and sends reach the bridge in the order written (a message the thread packed
        in between would carry a newer seq, and make the test's next one look reordered)."""
        with self._lock:
            yield

    def pose(self) -> mavlink.MAVLink_local_position_ned_message:
        self.sent_poses += 1
        return mavlink.MAVLink_local_position_ned_message(
            self.boot_ms(), self.north, 0.0, -1.0, 0.0, 0.0, 0.0
        )

    def heartbeat(self) -> mavlink.MAVLink_heartbeat_message:
        base = 29 | (ARMED if self.armed else 0)
        return mavlink.MAVLink_heartbeat_message(
            2, 12, base, self.custom_mode, self.system_status, 3
        )

    def _send_loop(self) -> None:
        tick = 0
        while not self._stop.wait(0.02):
            tick += 1
            try:
                if self.telemetry:
                    self.send(self.pose())
                    self.send(mavlink.MAVLink_attitude_message(self.boot_ms(), 0, 0, 1.5, 0, 0, 0))
                if tick % 10 == 0 and self.heartbeats:
                    self.send(self.heartbeat())
                    self.send(mavlink.MAVLink_extended_sys_state_message(0, 1))
                    # battery, as every autopilot reports it (12.6 V, 80 %)
                    self.send(
                        mavlink.MAVLink_sys_status_message(
                            0, 0, 0, 0, 12600, -1, 80, 0, 0, 0, 0, 0, 0
                        )
                    )
            except OSError:
                return

    # ---- receiving ----

    def _recv_loop(self) -> None:
        while not self._stop.is_set():
            try:
                data, _ = self.sock.recvfrom(65535)
            except TimeoutError:
                continue
            except OSError:
                return
            try:
                msgs = self.mav.parse_buffer(data) or []
            except mavlink.MAVError:
                continue
            for msg in msgs:
                self.received.append((time.monotonic(), msg))
                self._answer(msg)

    def _answer(self, msg) -> None:
        kind = msg.get_type()
        if kind == "PARAM_REQUEST_READ":
            name = msg.param_id
            if name in self.params:
                value, ptype = self.params[name]
                self.send(
                    mavlink.MAVLink_param_value_message(
                        name.encode(), value, ptype, len(self.params), 0
                    )
                )
        elif kind == "COMMAND_LONG":
            result = (
                mavlink.MAV_RESULT_ACCEPTED
                if msg.command == mavlink.MAV_CMD_SET_MESSAGE_INTERVAL
                else mavlink.MAV_RESULT_UNSUPPORTED
            )
            self.send(mavlink.MAVLink_command_ack_message(msg.command, result, 0, 0, 0, 0))

    def actuating(self, since: float = 0.0) -> list[object]:
        """Messages from the bridge that could make the aircraft do something (commands other
        than SET_MESSAGE_INTERVAL, setpoints, parameter writes, mode changes) since ``since``."""
        out = []
        for at, msg in list(self.received):
            if at < since or msg.get_type() in PASSIVE:
                continue
            if (
                msg.get_type() == "COMMAND_LONG"
                and msg.command == mavlink.MAV_CMD_SET_MESSAGE_INTERVAL
            ):
                continue
            out.append(msg)
        return out
