"""A Tello stand-in for the benchmarks: the SDK's three UDP ports on a loopback address of its
own, with no flight, so the bridges it serves are measured and not the simulator.

It answers every command at once (``ok``, or ``87`` to a read such as ``battery?``), sends a
state string at 10 Hz to the last address that spoke to it (port 8890), and while ``streamon``
is in force sends ``frame(index)``'s datagrams to port 11111 at ``fps`` frames a second,
``index`` counting the frames sent since the stand-in started (0, 1, 2, ...). Three daemon
threads; :meth:`close` stops them.
"""

from __future__ import annotations

import socket
import threading
import time
from collections.abc import Callable

STATE = (
    "mid:-1;x:-100;y:-100;z:-100;mpry:-1,-1,-1;pitch:0;roll:0;yaw:0;vgx:0;vgy:0;vgz:0;"
    "templ:60;temph:62;tof:10;h:0;bat:87;baro:100.00;time:0;agx:0.00;agy:0.00;agz:-1000.00;\r\n"
)
"""A Tello on the ground, its battery at 87 %."""


class TelloStandIn:
    """One Tello at ``address``: replies at once, state at 10 Hz, the video while streaming."""

    def __init__(
        self, address: str, frame: Callable[[int], list[bytes]], fps: float = 30.0
    ) -> None:
        self.address = address
        self.fps = fps
        self._frame = frame
        self.sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self.sock.bind((address, 8889))
        self.sock.settimeout(0.1)
        self.out = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self.client: str | None = None  # the address that spoke last
        self.streaming = threading.Event()  # streamon in force
        self.switches: list[tuple[float, str]] = []  # (monotonic s, streamon / streamoff)
        self.commands = 0  # ``command`` received (SDK mode: the first, then reconnections)
        self.frames = 0  # video frames sent
        self.datagrams = 0  # video datagrams sent
        self.stop = threading.Event()
        self.threads = [
            threading.Thread(target=loop, daemon=True)
            for loop in (self._commands, self._state, self._stream)
        ]
        for thread in self.threads:
            thread.start()

    def reset(self) -> None:
        """Forget the client, the stream and the counts (before a new set of bridges)."""
        self.client = None
        self.streaming.clear()
        self.switches, self.commands, self.frames, self.datagrams = [], 0, 0, 0

    def _commands(self) -> None:
        while not self.stop.is_set():
            try:
                data, source = self.sock.recvfrom(2048)
            except TimeoutError:
                continue
            text = data.decode("ascii", "replace").strip()
            if text.startswith("rc "):
                continue
            self.client = source[0]
            self.commands += text == "command"
            if text in ("streamon", "streamoff"):
                (self.streaming.set if text == "streamon" else self.streaming.clear)()
                self.switches.append((time.monotonic(), text))
            self.sock.sendto(b"87" if text.endswith("?") else b"ok", source)

    def _state(self) -> None:
        while not self.stop.wait(0.1):
            if self.client is not None:
                self.out.sendto(STATE.encode(), (self.client, 8890))

    def _stream(self) -> None:
        start, tick, index = time.monotonic(), 0, 0
        while not self.stop.is_set():
            delay = start + tick / self.fps - time.monotonic()
            if delay > 0:
                time.sleep(delay)
            tick += 1
            client = self.client
            if not self.streaming.is_set() or client is None:
                continue
            datagrams = self._frame(index)
            index += 1
            for datagram in datagrams:
                self.out.sendto(datagram, (client, 11111))
            self.datagrams += len(datagrams)
            self.frames += bool(datagrams)

    def close(self) -> None:
        self.stop.set()
        for thread in self.threads:
            thread.join(2)
        self.sock.close()
        self.out.close()
