"""A TCP relay that delays every byte by a fixed time each way: the radio link's latency.

The kernel here has no ``netem``, so a link's delay is added in user space: the relay accepts
on ``LISTEN_HOST:PORT``, connects each accepted connection to ``TARGET_HOST:PORT``, and writes
what it reads on one side to the other ``delay_ms`` later, in order. Bandwidth is shaped by the
kernel (``tbf`` on the namespace's links), not here. Prints ``ready`` once listening; stops on
SIGINT/SIGTERM.

    python tests/network/delay_relay.py LISTEN_HOST:PORT TARGET_HOST:PORT DELAY_MS
"""

from __future__ import annotations

import asyncio
import contextlib
import signal
import sys


async def pump(reader: asyncio.StreamReader, writer: asyncio.StreamWriter, delay: float) -> None:
    """Copy ``reader`` to ``writer``, each chunk ``delay`` s after it arrived, in order."""
    loop = asyncio.get_running_loop()
    queue: asyncio.Queue[tuple[float, bytes]] = asyncio.Queue()

    async def send() -> None:
        while True:
            due, chunk = await queue.get()
            if not chunk:
                break
            await asyncio.sleep(max(0.0, due - loop.time()))
            writer.write(chunk)
            await writer.drain()

    sender = asyncio.create_task(send())
    try:
        while chunk := await reader.read(65536):
            queue.put_nowait((loop.time() + delay, chunk))
    except (ConnectionError, OSError):
        pass
    queue.put_nowait((0.0, b""))
    with contextlib.suppress(ConnectionError, OSError):
        await sender
    writer.close()


async def main(listen: str, target: str, delay_ms: float) -> None:
    delay = delay_ms / 1000.0
    host, port = target.rsplit(":", 1)

    async def relay(in_reader: asyncio.StreamReader, in_writer: asyncio.StreamWriter) -> None:
        try:
            out_reader, out_writer = await asyncio.open_connection(host, int(port))
        except OSError:
            in_writer.close()
            return
        await asyncio.gather(pump(in_reader, out_writer, delay), pump(out_reader, in_writer, delay))

    listen_host, listen_port = listen.rsplit(":", 1)
    server = await asyncio.start_server(relay, listen_host, int(listen_port))
    stop = asyncio.Event()
    for sig in (signal.SIGINT, signal.SIGTERM):
        asyncio.get_running_loop().add_signal_handler(sig, stop.set)
    print("ready", flush=True)
    async with server:
        await stop.wait()


if __name__ == "__main__":
    asyncio.run(main(sys.argv[1], sys.argv[2], float(sys.argv[3])))
