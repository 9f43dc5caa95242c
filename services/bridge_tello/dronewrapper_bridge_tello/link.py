"""The UDP sockets of the Tello SDK: commands (to the Tello's 8889), state (8890), video (11111).

The Tello answers a command to the address it came from, and sends the state string and the
video to the commanding client's IP on ports 8890 and 11111. So the bridge binds its three
sockets on ``local_address`` (``0.0.0.0`` on the Tello's Wi-Fi; a loopback address such as
``127.0.0.2`` next to a simulated Tello, so several bridges can run on one machine).
"""

from __future__ import annotations

import socket
from dataclasses import dataclass, fields
from typing import Any

MAX_DATAGRAM = 65535


@dataclass
class TelloAddress:
    """Where the Tello is and where we listen."""

    tello_address: str = "192.168.10.1"
    command_port: int = 8889
    local_address: str = "0.0.0.0"
    local_command_port: int = 0  # 0: any free port (the Tello replies to the sender's port)
    state_port: int = 8890
    video_port: int = 11111

    @classmethod
    def of(cls, config: Any) -> TelloAddress:
        """The addresses and ports ``config`` (the bridge's Config) names, by the same names."""
        return cls(**{f.name: getattr(config, f.name) for f in fields(cls)})


def _udp(address: str, port: int, *, buffer: int = 0) -> socket.socket:
    sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    # no SO_REUSEADDR: a second bridge (or Tello client) on the same address must fail loudly
    # instead of silently sharing the state and video datagrams with this one
    if buffer:
        sock.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, buffer)
    try:
        sock.bind((address, port))
    except OSError:
        sock.close()
        raise
    return sock


class TelloLink:
    """The three sockets, opened together (``OSError`` if a port is taken)."""

    def __init__(self, address: TelloAddress, *, video: bool = True) -> None:
        self.address = address
        self.command = _udp(address.local_address, address.local_command_port)
        try:
            self.state = _udp(address.local_address, address.state_port)
            self.video = (
                _udp(address.local_address, address.video_port, buffer=1 << 20) if video else None
            )
        except OSError:
            self.close()
            raise
        for sock in (self.command, self.state, self.video):
            if sock is not None:
                sock.settimeout(0.2)

    def send(self, text: str) -> None:
        """Send one SDK command (ASCII text) to the Tello."""
        target = (self.address.tello_address, self.address.command_port)
        self.command.sendto(text.encode("ascii"), target)

    def close(self) -> None:
        for name in ("command", "state", "video"):
            sock = getattr(self, name, None)
            if sock is not None:
                sock.close()
