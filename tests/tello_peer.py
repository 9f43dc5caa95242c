"""A scripted Tello on real UDP for bridge_tello's service and fuzz tests.

It answers each command from a script (so refusals, silence and odd replies can be produced at
will), streams a state string at 10 Hz to its commander's 8890 and records every datagram it
receives, so what the bridge puts on the wire is checked exactly.
"""

from __future__ import annotations

import socket
import threading
import time

# what a Tello may receive without moving: SDK mode, video switches, reads, a centred stick
HARMLESS = ("command", "streamon", "streamoff", "rc 0 0 0 0")


STATE = (
    "mid:-1;x:-100;y:-100;z:-100;mpry:-1,-1,-1;pitch:0;roll:0;yaw:0;vgx:0;vgy:0;vgz:0;"
    "templ:60;temph:62;tof:{tof};h:{h};bat:80;baro:100.00;time:{t};agx:0.00;agy:0.00;"
    "agz:-1000.00;\r\n"
)


class ScriptedTello(threading.Thread):
    """Replies from ``script`` (command -> reply, None = silence; default ``ok``)."""

    def __init__(self, address: str) -> None:
        super().__init__(daemon=True)
        self.address = address
        self.sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self.sock.bind((address, 8889))
        self.sock.settimeout(0.05)
        self.script: dict[str, str | None] = {"battery?": "80", "speed?": "100.0"}
        self.received: list[tuple[float, str]] = []
        self.client: tuple[str, int] | None = None
        self.flying = False
        self.stop = threading.Event()

    def run(self) -> None:
        next_state, motor_time = 0.0, 0
        while not self.stop.is_set():
            now = time.monotonic()
            if self.client is not None and now >= next_state:
                next_state = now + 0.1
                if self.flying:
                    motor_time = int(now)  # ticks once a second while flying
                h = 100 if self.flying else 0
                text = STATE.format(tof=h + 10, h=h, t=motor_time)
                self.sock.sendto(text.encode(), (self.client[0], 8890))
            try:
                data, source = self.sock.recvfrom(2048)
            except TimeoutError:
                continue
            except OSError:
                return
            text = data.decode()
            self.received.append((time.monotonic(), text))
            self.client = source
            if text.startswith("rc "):
                continue
            reply = self.script.get(text, "ok")
            if text == "takeoff" and reply == "ok":
                self.flying = True
            if text == "land" and reply == "ok":
                self.flying = False
            if reply is not None:
                self.sock.sendto(reply.encode(), source)

    def rcs(self, since: float = 0.0) -> list[tuple[float, tuple[int, ...]]]:
        return [
            (t, tuple(int(v) for v in text.split()[1:]))
            for t, text in list(self.received)
            if t >= since and text.startswith("rc ")
        ]

    def actuating(self, since: float) -> list[str]:
        """Commands received since ``since`` that could move the Tello (not HARMLESS, no read)."""
        return [
            text
            for t, text in list(self.received)
            if t >= since and text not in HARMLESS and not text.endswith("?")
        ]
