"""A TCP port forwarder, as ``ssh -L`` or a reverse proxy ending on the drone would be: every
connection to LISTEN is relayed byte for byte to TARGET (for the security tests).

    tcp_forward.py LISTEN_HOST:PORT TARGET_HOST:PORT     prints "forwarding" once listening;
                                                         runs until SIGTERM
"""

from __future__ import annotations

import contextlib
import signal
import socket
import sys
import threading


def _address(text: str) -> tuple[str, int]:
    host, _, port = text.rpartition(":")
    return host, int(port)


def _pipe(src: socket.socket, dst: socket.socket) -> None:
    try:
        while data := src.recv(65536):
            dst.sendall(data)
    except OSError:
        pass
    finally:
        for sock in (src, dst):
            with contextlib.suppress(OSError):
                sock.shutdown(socket.SHUT_RDWR)


def _relay(client: socket.socket, target: tuple[str, int]) -> None:
    try:
        upstream = socket.create_connection(target, timeout=5)
    except OSError:
        client.close()
        return
    upstream.settimeout(None)
    threading.Thread(target=_pipe, args=(client, upstream), daemon=True).start()
    _pipe(upstream, client)
    client.close()
    upstream.close()


def main() -> int:
    listen, target = _address(sys.argv[1]), _address(sys.argv[2])
    signal.signal(signal.SIGTERM, lambda *_: sys.exit(0))
    server = socket.create_server(listen, reuse_port=False)
    print("forwarding", flush=True)
    while True:
        client, _ = server.accept()
        threading.Thread(target=_relay, args=(client, target), daemon=True).start()


if __name__ == "__main__":
    raise SystemExit(main())
