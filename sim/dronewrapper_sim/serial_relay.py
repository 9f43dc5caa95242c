"""A serial line at a real baud rate between a pseudo-terminal and an autopilot's UDP/TCP port.

The bridge opens the pseudo-terminal's device as it would a flight controller's
``/dev/ttyACM0``; the relay carries the bytes to the autopilot's network port (our simulator,
PX4 SITL, ArduCopter SITL) and back, each direction paced at ``baud / 10`` bytes a second
behind a bounded transmit buffer (:class:`~dronewrapper_sim.serial_line.SerialLine`): what
does not fit in a 57600-baud line is late, then dropped, as on the wire.

    python -m dronewrapper_sim.serial_relay --baud 57600 --udp-listen 127.0.0.1:14540
    python -m dronewrapper_sim.serial_relay --baud 921600 --tcp 127.0.0.1:5760 --link /tmp/ttyAP
    python -m dronewrapper_sim.serial_relay --baud 57600 --pty --link /tmp/ttyAP

``--udp-listen`` binds the port the autopilot sends to (the bridge's ``udpin`` port: PX4 SITL's
14540, the simulator's ``--udp-onboard`` port) and answers whoever sent last, one datagram per
MAVLink frame; ``--tcp`` connects to an ArduPilot SITL serial port; ``--pty`` makes a second
pseudo-terminal for the autopilot to open as its own serial port (PX4 SITL's ``mavlink start -d
DEVICE -b BAUD``, ArduCopter SITL's ``--serial0 uart:DEVICE:BAUD``), so that the firmware sizes
its streams to the baud as on a flight controller. The bridge's device path is printed (and
linked at ``--link``), then, with ``--pty``, the autopilot's.
"""

from __future__ import annotations

import contextlib
import os
import select
import socket
import sys
import threading
import time
import tty
from pathlib import Path

from dronewrapper.runtime.arguments import CommandParser
from dronewrapper_sim.serial_line import FrameCutter, SerialLine

UPLINK_BUFFER_BYTES = 4096  # the pty's own buffer is about this deep
TICK_S = 0.05  # the longest wait between two looks at the line
MIN_WAIT_S = 0.002  # the shortest: bytes leave in bursts of 2 ms (12 B at 57600 baud)


def parse_address(text: str) -> tuple[str, int]:
    """``HOST:PORT`` (or ``PORT`` on 127.0.0.1) as an address; ValueError naming the form."""
    host, _, port = text.rpartition(":")
    if not port.isdigit() or not 0 < int(port) < 65536:
        raise ValueError(f"{text!r} is not HOST:PORT")
    return host or "127.0.0.1", int(port)


class SerialRelay:
    """A pseudo-terminal joined to an autopilot's port by a serial line at ``baud``.

    Args:
        baud: the line's rate, bits/s.
        udp_listen: (host, port) to bind; replies go to whoever sent last.
        tcp: (host, port) to connect to.
        pty: make a pseudo-terminal for the autopilot (its path: :attr:`autopilot_path`).
            Exactly one of ``udp_listen``, ``tcp`` and ``pty``.
        buffer_bytes: the autopilot's transmit buffer toward the bridge.
    """

    def __init__(
        self,
        baud: int,
        *,
        udp_listen: tuple[str, int] | None = None,
        tcp: tuple[str, int] | None = None,
        pty: bool = False,
        buffer_bytes: int = 1024,
    ) -> None:
        if [udp_listen is not None, tcp is not None, pty].count(True) != 1:
            raise ValueError("give exactly one of udp_listen, tcp and pty")
        now = time.monotonic()
        self.baud = baud
        self.down = SerialLine(baud, buffer_bytes=buffer_bytes, now=now)  # autopilot -> bridge
        self.up = SerialLine(baud, buffer_bytes=UPLINK_BUFFER_BYTES, now=now)  # bridge -> AP
        self._up_frames, self._up_out = FrameCutter(), FrameCutter()
        self._down_frames = FrameCutter()  # the TCP stream's (a datagram holds whole frames)
        self._master, self._slave = os.openpty()
        tty.setraw(self._master)
        tty.setraw(self._slave)  # no echo before the bridge opens it
        os.set_blocking(self._master, False)
        self.path = os.ttyname(self._slave)
        self._remote: tuple[str, int] | None = None
        self.autopilot_path = ""
        self._far_fd = -1  # the autopilot's pseudo-terminal (master side), with pty
        self._far_slave = -1  # kept open: the master reads no hang-up before the autopilot opens
        self._sock: socket.socket | None = None
        self._udp = False
        self._down_frames = FrameCutter()
        if pty:
            self._far_fd, self._far_slave = os.openpty()
            tty.setraw(self._far_fd)
            tty.setraw(self._far_slave)
            os.set_blocking(self._far_fd, False)
            self.autopilot_path = os.ttyname(self._far_slave)
        elif udp_listen is not None:
            self._sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
            self._sock.bind(udp_listen)
            self._udp = True
        else:
            assert tcp is not None  # exactly one of the two, checked above
            self._sock = socket.create_connection(tcp, timeout=5.0)
            self._sock.settimeout(None)
        if self._sock is not None:
            self._sock.setblocking(False)
        self.unwritten = 0  # bytes the pseudo-terminal would not take (nobody reading)
        self.unplugged = False  # set: the cable is out, every byte either way is lost
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None

    def start(self) -> SerialRelay:
        """Run the relay in a thread (stopped by :meth:`close`)."""
        self._thread = threading.Thread(target=self.run, args=(self._stop,), daemon=True)
        self._thread.start()
        return self

    def close(self) -> None:
        """Stop the thread and close the pseudo-terminal and the socket (idempotent)."""
        self._stop.set()
        if self._thread is not None:
            self._thread.join(timeout=2.0)
            self._thread = None
        for fd in (self._master, self._slave, self._far_fd, self._far_slave):
            if fd >= 0:
                with contextlib.suppress(OSError):
                    os.close(fd)
        self._master = self._slave = self._far_fd = self._far_slave = -1
        if self._sock is not None:
            self._sock.close()

    def __enter__(self) -> SerialRelay:
        return self.start()

    def __exit__(self, *exc: object) -> None:
        self.close()

    def run(self, stop: threading.Event) -> None:
        """Carry bytes both ways until ``stop`` is set."""
        while not stop.is_set():
            now = time.monotonic()
            waits = [self.down.next_byte_in(now), self.up.next_byte_in(now)]
            timeout = max(MIN_WAIT_S, min([TICK_S, *(w for w in waits if w is not None)]))
            try:
                ends: list[int | socket.socket] = [self._master, self._far]
                readable, _, _ = select.select(ends, [], [], timeout)
            except (OSError, ValueError):
                return  # closed under us
            now = time.monotonic()
            if self._far in readable:
                self._from_autopilot(now)
            if self._master in readable:
                self._from_bridge(now)
            self._deliver(now)

    @property
    def _far(self) -> socket.socket | int:
        """What the autopilot's side reads from: its socket or its pseudo-terminal."""
        return self._sock if self._sock is not None else self._far_fd

    def _from_autopilot(self, now: float) -> None:
        try:
            if self._sock is None:
                data = os.read(self._far_fd, 65535)
                frames = self._down_frames.feed(data)
            elif self._udp:
                data, self._remote = self._sock.recvfrom(65535)
                frames = FrameCutter().feed(data)  # a datagram holds whole frames
            else:
                data = self._sock.recv(65535)
                frames = self._down_frames.feed(data) if data else []
        except (BlockingIOError, InterruptedError, ConnectionRefusedError):
            return
        except OSError:  # a hang-up cannot last: the relay holds the autopilot's side open
            return
        if self.unplugged:
            return
        for frame in frames:
            self.down.offer(frame, now)

    def _from_bridge(self, now: float) -> None:
        try:
            data = os.read(self._master, 4096)
        except (BlockingIOError, InterruptedError):
            return
        if self.unplugged:
            return
        for frame in self._up_frames.feed(data):
            self.up.offer(frame, now)

    def _deliver(self, now: float) -> None:
        down = self.down.take(now)
        if down:
            try:
                written = os.write(self._master, down)
            except BlockingIOError:
                written = 0
            self.unwritten += len(down) - written
        up = self.up.take(now)
        if not up:
            return
        if self._sock is None:
            with contextlib.suppress(BlockingIOError, OSError):
                os.write(self._far_fd, up)
            return
        if not self._udp:
            with contextlib.suppress(BlockingIOError):
                self._sock.sendall(up)
            return
        for frame in self._up_out.feed(up):
            if self._remote is not None:
                with contextlib.suppress(OSError):
                    self._sock.sendto(frame, self._remote)


def main(argv: list[str] | None = None) -> int:
    parser = CommandParser(
        prog="python -m dronewrapper_sim.serial_relay",
        description="a pseudo-terminal joined to an autopilot's port at a real baud rate",
    )
    parser.add_argument("--baud", type=int, default=57600, help="bits/s (57600)")
    where = parser.add_mutually_exclusive_group(required=True)
    where.add_argument("--udp-listen", metavar="[HOST:]PORT", help="bind this UDP port")
    where.add_argument("--tcp", metavar="HOST:PORT", help="connect to this TCP port")
    where.add_argument("--pty", action="store_true", help="a pseudo-terminal for the autopilot")
    parser.add_argument("--link", metavar="PATH", help="also make PATH a link to the device")
    args = parser.parse_args(argv)
    try:
        relay = SerialRelay(
            args.baud,
            udp_listen=parse_address(args.udp_listen) if args.udp_listen else None,
            tcp=parse_address(args.tcp) if args.tcp else None,
            pty=args.pty,
        )
    except (ValueError, OSError) as exc:
        parser.error(str(exc))
    link = Path(args.link) if args.link else None
    if link is not None:
        link.unlink(missing_ok=True)
        link.symlink_to(relay.path)
    print(relay.path, flush=True)
    if relay.autopilot_path:
        print(relay.autopilot_path, flush=True)
    stop = threading.Event()
    try:
        relay.run(stop)
    except KeyboardInterrupt:
        pass
    finally:
        relay.close()
        if link is not None:
            link.unlink(missing_ok=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
