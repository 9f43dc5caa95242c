"""A TCP relay that delays every byte by a fixed time each way: the radio link's latency.

The kernel here has no ``netem`` (``tc qdisc ... netem`` answers "Specified qdisc kind is
unknown"), so the link's delay is added in user space: for each ``LISTEN=TARGET`` pair the relay
accepts on ``LISTEN`` (``HOST:PORT``), connects each accepted connection to ``TARGET``, and
writes what it reads on one side to the other ``delay_ms`` later, in order. Bandwidth is shaped
by the kernel (``tbf`` on the namespace's links), not here. Prints ``ready`` once listening;
stops on SIGINT/SIGTERM.

    python tests/network/delay_relay.py DELAY_MS LISTEN_HOST:PORT=TARGET_HOST:PORT [...]
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


def split(address: str) -> tuple[str, int]:
    host, port = address.rsplit(":", 1)
    return host, int(port)


async def serve(listen: str, target: str, delay: float) -> asyncio.Server:
    """Relay connections accepted on ``listen`` to ``target``, ``delay`` s each way."""
    host, port = split(target)

    async def relay(in_reader: asyncio.StreamReader, in_writer: asyncio.StreamWriter) -> None:
        try:
            out_reader, out_writer = await asyncio.open_connection(host, port)
        except OSError:
            in_writer.close()
            return
        await asyncio.gather(pump(in_reader, out_writer, delay), pump(out_reader, in_writer, delay))

    return await asyncio.start_server(relay, *split(listen))


async def main(delay_ms: float, pairs: list[str]) -> None:
    servers = [await serve(*pair.split("=", 1), delay_ms / 1000.0) for pair in pairs]
    stop = asyncio.Event()
    for sig in (signal.SIGINT, signal.SIGTERM):
        asyncio.get_running_loop().add_signal_handler(sig, stop.set)
    print("ready", flush=True)
    await stop.wait()
    for server in servers:
        server.close()


if __name__ == "__main__":
    asyncio.run(main(float(sys.argv[1]), sys.argv[2:]))
