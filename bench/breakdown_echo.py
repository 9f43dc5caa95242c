"""The echo process of ``bench.transport_breakdown``: it puts every ping back as a pong, in a
variant's way (plain zenoh-python or our runtime's Node), or as a plain TCP echo with one
reader thread per connection (rospy's TCPROS design), until its stdin closes."""

from __future__ import annotations

import socket
import struct
import sys
import threading

import zenoh

from bench.breakdown_variants import (
    PING_KEY,
    PONG_KEY,
    Variant,
    node_for,
    publisher,
    qos,
    session_config,
    subscribe,
)
from dronewrapper.msgs import registry


def serve_echo(variant: Variant, mode: str, connect: list[str], listen: list[str]) -> None:
    """In the child: put every ping back as a pong until stdin closes."""
    if variant.layer in ("ours", "ours_echo"):
        with node_for(variant, "echo", mode, connect, listen) as node:
            pub = node.publisher(registry.IMAGE_COMPRESSED, key=PONG_KEY, qos=qos(variant))
            node.subscribe(registry.IMAGE_COMPRESSED, pub.put, key=PING_KEY)
            print("ready", flush=True)
            sys.stdin.read()
        return
    session = zenoh.open(session_config(variant, mode, connect, listen))
    put = publisher(session, PONG_KEY, variant)
    sub = subscribe(session, PING_KEY, variant.echo, put)
    reader = None
    if variant.echo == "recv":

        def loop() -> None:
            try:
                while True:
                    put(sub.recv().payload.to_bytes())
            except zenoh.ZError:  # the session closed: the channel is empty and closed
                return

        reader = threading.Thread(target=loop, daemon=True)
        reader.start()
    print("ready", flush=True)
    sys.stdin.read()
    session.close()
    if reader is not None:
        reader.join(2.0)


def serve_socket() -> None:
    """In the child: a TCP echo with one reader thread, as a TCPROS connection has."""
    server = socket.create_server(("127.0.0.1", 0))
    print(server.getsockname()[1], flush=True)
    conn, _ = server.accept()
    conn.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)

    def loop() -> None:
        while True:
            head = conn.recv(4, socket.MSG_WAITALL)
            if len(head) < 4:
                return
            (size,) = struct.unpack("<I", head)
            data = conn.recv(size, socket.MSG_WAITALL)
            conn.sendall(struct.pack("<I", len(data)) + data)

    reader = threading.Thread(target=loop, daemon=True)
    reader.start()
    sys.stdin.read()
    conn.close()
    server.close()
