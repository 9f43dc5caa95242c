"""Measure a link's delay each way and its rate each way, over TCP through the link.

    python link_measure.py serve HOST:PORT      # at one end (prints ``ready``; SIGINT stops)
    python link_measure.py measure HOST:PORT    # at the other end: one JSON line, then exits

Both ends share one clock (network namespaces of one machine), so a message's delay is its
arrival time minus the send time it carries. ``measure`` sends ``PINGS`` stamped messages one
after another (each answered with the server's arrival time): ``forward_ms`` is client ->
server, ``back_ms`` server -> client. Then it sends ``BULK_BYTES`` to the server and takes as
many from it at the same time: each receiver's rate (``up_mbit_s``: client -> server,
``down_mbit_s``: server -> client) counts the payload after its first quarter arrived, past
TCP's slow start, up to the last byte.
"""

from __future__ import annotations

import json
import signal
import socket
import socketserver
import struct
import sys
import threading
import time

PINGS = 10
BULK_BYTES = 3_000_000
CHUNK = 65536
STAMP = struct.Struct("!d")
ECHO = struct.Struct("!dd")
SIZE = struct.Struct("!Q")


def read_exactly(sock: socket.socket, n: int) -> bytes:
    data = bytearray()
    while len(data) < n:
        chunk = sock.recv(n - len(data))
        if not chunk:
            raise ConnectionError("closed early")
        data += chunk
    return bytes(data)


def receive_rate(sock: socket.socket, total: int) -> float:
    """Read ``total`` bytes; the rate (Mbit/s) of what came after the first read, from its
    return to the last read's.

    Behind the shaper each hop is a TCP stream with a round trip under a millisecond (the
    link's delay is the relay's), so the shaped rate holds from the first byte: the whole
    transfer is the window, and only the bucket's first burst (32 KB, 1 % of it) can raise
    the figure. A window that opens later reads several % high when it opens just before a
    loss's retransmission releases what TCP held past the hole.
    """
    buffer = memoryview(bytearray(total))
    got = first = sock.recv_into(buffer, total)
    start = time.time()
    while got < total:
        n = sock.recv_into(buffer[got:], total - got)
        if not n:
            raise ConnectionError("closed early")
        got += n
    return (total - first) * 8 / (time.time() - start) / 1e6


def send_bulk(sock: socket.socket, total: int) -> None:
    block = bytes(CHUNK)
    sent = 0
    while sent < total:
        sent += sock.send(block[: min(CHUNK, total - sent)])


class Handler(socketserver.BaseRequestHandler):
    """One measurement: ``e`` echo stamps, ``u`` take bulk and say its rate, ``d`` send bulk."""

    def handle(self) -> None:
        sock: socket.socket = self.request
        mode = read_exactly(sock, 1)
        if mode == b"e":
            while data := sock.recv(STAMP.size):
                if len(data) < STAMP.size:
                    data += read_exactly(sock, STAMP.size - len(data))
                sock.sendall(ECHO.pack(STAMP.unpack(data)[0], time.time()))
        elif mode == b"u":
            total = SIZE.unpack(read_exactly(sock, SIZE.size))[0]
            sock.sendall(STAMP.pack(receive_rate(sock, total)))
        elif mode == b"d":
            send_bulk(sock, SIZE.unpack(read_exactly(sock, SIZE.size))[0])


def serve(address: str) -> int:
    host, port = address.rsplit(":", 1)
    socketserver.ThreadingTCPServer.allow_reuse_address = True
    server = socketserver.ThreadingTCPServer((host, int(port)), Handler)
    server.daemon_threads = True
    stop = threading.Event()
    for sig in (signal.SIGINT, signal.SIGTERM):
        signal.signal(sig, lambda *_: stop.set())
    threading.Thread(target=server.serve_forever, daemon=True).start()
    print("ready", flush=True)
    stop.wait()
    server.shutdown()
    server.server_close()
    return 0


def connect(address: str, mode: bytes) -> socket.socket:
    host, port = address.rsplit(":", 1)
    sock = socket.create_connection((host, int(port)), timeout=30)
    sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
    sock.sendall(mode)
    return sock


def measure(address: str) -> int:
    forward, back = [], []
    with connect(address, b"e") as sock:
        for _ in range(PINGS):
            sock.sendall(STAMP.pack(time.time()))
            sent, arrived = ECHO.unpack(read_exactly(sock, ECHO.size))
            forward.append((arrived - sent) * 1000)
            back.append((time.time() - arrived) * 1000)
    rates: dict[str, float] = {}

    def upload() -> None:
        with connect(address, b"u") as sock:
            sock.sendall(SIZE.pack(BULK_BYTES))
            send_bulk(sock, BULK_BYTES)
            rates["up_mbit_s"] = STAMP.unpack(read_exactly(sock, STAMP.size))[0]

    def download() -> None:
        with connect(address, b"d") as sock:
            sock.sendall(SIZE.pack(BULK_BYTES))
            rates["down_mbit_s"] = receive_rate(sock, BULK_BYTES)

    workers = [threading.Thread(target=upload), threading.Thread(target=download)]
    for worker in workers:
        worker.start()
    for worker in workers:
        worker.join(60)
    print(json.dumps({"forward_ms": forward, "back_ms": back, **rates}), flush=True)
    return 0 if len(rates) == 2 else 1


if __name__ == "__main__":
    mode, address = sys.argv[1], sys.argv[2]
    raise SystemExit(serve(address) if mode == "serve" else measure(address))
