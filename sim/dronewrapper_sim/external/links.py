"""The MAVLink links that bring an autopilot's truth to the world.

- PX4 SIH (``px4-sih``): PX4 sends ``HIL_STATE_QUATERNION`` to UDP 19410 (about 25 Hz); the
  world binds that port and, once it has heard PX4, asks it (``SET_MESSAGE_INTERVAL``) for the
  message at ``rate_hz``.
- ArduCopter SITL (``ardupilot``): the world connects to a spare serial port of the SITL
  (SERIAL1, TCP 5762: SERIAL0 is the bridge's, SERIAL2 the ground station's), identifies itself
  with a 1 Hz ground-station heartbeat, and asks for ``SIM_STATE`` at ``rate_hz``; it
  reconnects while the SITL is not (yet) there.

Each link is polled with ``select`` on ``fileno`` (None while a TCP link is not connected) and
``receive`` returns the truth messages that arrived. Both use pymavlink's ``ardupilotmega``
dialect (it includes ``common``); bytes that do not parse are counted and dropped.
"""

from __future__ import annotations

import logging
import socket
from typing import Any

from pymavlink.dialects.v20 import ardupilotmega as mavlink

from dronewrapper_sim.external.truth import TRUTH_MESSAGES
from dronewrapper_sim.udp import bind_udp

log = logging.getLogger("sim.external")

PX4_SIH_TRUTH_PORT = 19410
ARDUPILOT_TRUTH_PORT = 5762  # SERIAL1 of ArduCopter SITL instance 0
AUTOPILOTS = ("px4-sih", "ardupilot")
MSG_ID = {"HIL_STATE_QUATERNION": 115, "SIM_STATE": 108}
REQUEST_EVERY_S = 2.0  # the rate request is repeated until the rate is seen
SYSID, COMPID = 255, 191  # a ground station's system id; a component of its own


def default_link(autopilot: str) -> str:
    """The default ``udp:HOST:PORT`` / ``tcp:HOST:PORT`` of ``autopilot``'s truth."""
    if autopilot == "px4-sih":
        return f"udp:127.0.0.1:{PX4_SIH_TRUTH_PORT}"
    if autopilot == "ardupilot":
        return f"tcp:127.0.0.1:{ARDUPILOT_TRUTH_PORT}"
    raise ValueError(f"autopilot must be one of {', '.join(AUTOPILOTS)}, got {autopilot!r}")


def parse_link(spec: str) -> tuple[str, str, int]:
    """``udp:HOST:PORT`` or ``tcp:HOST:PORT`` -> (kind, host, port); ValueError otherwise."""
    parts = spec.split(":")
    if len(parts) != 3 or parts[0] not in ("udp", "tcp"):
        raise ValueError(f"link must be udp:HOST:PORT or tcp:HOST:PORT, got {spec!r}")
    try:
        port = int(parts[2])
    except ValueError:
        raise ValueError(f"link port must be a number, got {parts[2]!r}") from None
    if not 0 <= port <= 65535:
        raise ValueError(f"link port must be 0..65535, got {port}")
    return parts[0], parts[1], port


def interval_request(msg_name: str, rate_hz: float, target_system: int) -> Any:
    """COMMAND_LONG MAV_CMD_SET_MESSAGE_INTERVAL asking for ``msg_name`` at ``rate_hz``."""
    return mavlink.MAVLink_command_long_message(
        target_system, 0, mavlink.MAV_CMD_SET_MESSAGE_INTERVAL, 0,
        MSG_ID[msg_name], 1e6 / rate_hz, 0, 0, 0, 0, 0,
    )  # fmt: skip


class TruthLink:
    """One link to an autopilot's truth (see module doc).

    Args:
        autopilot: ``px4-sih`` or ``ardupilot``.
        spec: ``udp:HOST:PORT`` (bound) or ``tcp:HOST:PORT`` (connected to).
        rate_hz: the truth rate asked of the autopilot.
    """

    def __init__(self, autopilot: str, spec: str, rate_hz: float) -> None:
        self.autopilot = autopilot
        self.kind, self.host, self.port = parse_link(spec)
        self.spec = spec
        self.rate_hz = rate_hz
        self.wanted = "HIL_STATE_QUATERNION" if autopilot == "px4-sih" else "SIM_STATE"
        self.mav = mavlink.MAVLink(None, srcSystem=SYSID, srcComponent=COMPID)
        self.mav.robust_parsing = True
        self.sock: socket.socket | None = None
        self.remote: tuple[str, int] | None = None
        self.target_system = 0
        self.received = 0
        self.bad = 0
        self.connects = 0
        self._next_try = 0.0
        self._next_heartbeat = 0.0
        self._next_request = 0.0
        self._truth_times: list[float] = []
        if self.kind == "udp":
            self.sock = bind_udp(self.host, self.port, f"{autopilot} truth")

    def fileno(self) -> int:
        return self.sock.fileno() if self.sock is not None else -1

    @property
    def connected(self) -> bool:
        return self.sock is not None and (self.kind == "udp" or self.remote is not None)

    def tick(self, now: float) -> None:
        """Connect (TCP), send the heartbeat (TCP) and the rate request when due."""
        if self.kind == "tcp" and self.sock is None and now >= self._next_try:
            self._next_try = now + 1.0
            self._connect()
        if not self.connected or self.remote is None:
            return
        if self.kind == "tcp" and now >= self._next_heartbeat:
            self._next_heartbeat = now + 1.0
            self._send(
                mavlink.MAVLink_heartbeat_message(
                    mavlink.MAV_TYPE_GCS, mavlink.MAV_AUTOPILOT_INVALID, 0, 0, 0, 3
                )
            )
        if now >= self._next_request and self.measured_rate_hz(now) < 0.8 * self.rate_hz:
            self._next_request = now + REQUEST_EVERY_S
            self._send(interval_request(self.wanted, self.rate_hz, self.target_system))

    def measured_rate_hz(self, now: float) -> float:
        """Truth messages per second over the last second."""
        recent = [t for t in self._truth_times if t > now - 1.0]
        self._truth_times = recent
        return float(len(recent))

    def _connect(self) -> None:
        sock = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
        sock.settimeout(0.5)
        try:
            sock.connect((self.host, self.port))
        except OSError:
            sock.close()
            return
        sock.setblocking(False)
        self.sock = sock
        self.remote = (self.host, self.port)
        self.connects += 1
        self._next_request = 0.0
        log.info("%s truth: connected to tcp:%s:%d", self.autopilot, self.host, self.port)

    def _drop(self) -> None:
        if self.sock is not None:
            self.sock.close()
        self.sock = None
        self.remote = None
        self.mav = mavlink.MAVLink(None, srcSystem=SYSID, srcComponent=COMPID)
        self.mav.robust_parsing = True
        log.info("%s truth: tcp:%s:%d closed; reconnecting", self.autopilot, self.host, self.port)

    def _send(self, msg: Any) -> None:
        if self.sock is None or self.remote is None:
            return
        buf = msg.pack(self.mav)
        self.mav.seq = (self.mav.seq + 1) % 256
        try:
            if self.kind == "udp":
                self.sock.sendto(buf, self.remote)
            else:
                self.sock.sendall(buf)
        except OSError:
            if self.kind == "tcp":
                self._drop()

    def receive(self, now: float) -> list[Any]:
        """The truth messages waiting on the link (bounded per call)."""
        if self.sock is None:
            return []
        out: list[Any] = []
        for _ in range(256):
            try:
                data, addr = self.sock.recvfrom(65535)
            except (BlockingIOError, InterruptedError):
                break
            except OSError:
                if self.kind == "tcp":
                    self._drop()
                break
            if self.kind == "tcp" and not data:
                self._drop()
                break
            if self.kind == "udp":
                self.remote = (addr[0], addr[1])
            out.extend(self._parse(data, now))
        return out

    def _parse(self, data: bytes, now: float) -> list[Any]:
        try:
            msgs = self.mav.parse_buffer(data) or []
        except Exception:  # never let bad bytes end the link
            self.bad += 1
            return []
        out = []
        for msg in msgs:
            kind = msg.get_type()
            if kind in ("BAD_DATA", "UNKNOWN"):
                self.bad += 1
                continue
            if kind == "HEARTBEAT" and msg.autopilot != mavlink.MAV_AUTOPILOT_INVALID:
                self.target_system = msg.get_srcSystem()
            if kind in TRUTH_MESSAGES:
                self.received += 1
                self._truth_times.append(now)
                out.append(msg)
        return out

    def close(self) -> None:
        if self.sock is not None:
            self.sock.close()
            self.sock = None
