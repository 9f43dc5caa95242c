"""An ASGI app driven in process: HTTP requests and WebSockets with no server and no socket.

The app runs on its own event loop thread (as under uvicorn); the test talks to it through
ASGI messages. Each request or WebSocket names its client address and ``Host`` (the station's
access rules read both), as a real connection would carry them.

    client = AsgiClient(app)
    status, body, headers = client.http("POST", "/api/x", {"a": 1})
    with client.websocket("/ws/y") as ws:
        ws.send('{"type": "ping"}')
        reply = ws.recv(timeout=5)
"""

from __future__ import annotations

import asyncio
import json
import queue
import threading
from collections.abc import Callable
from concurrent.futures import Future
from typing import Any

ASGI = {"version": "3.0", "spec_version": "2.3"}
SERVER = ("127.0.0.1", 8080)
HOST = "127.0.0.1:8080"
CLIENT = ("127.0.0.1", 40000)


def _lower(headers: dict[str, str] | None) -> dict[str, str]:
    return {k.lower(): v for k, v in (headers or {}).items()}


def _scope(kind: str, target: str, headers: dict[str, str], client: tuple[str, int]) -> dict:
    path, _, query = target.partition("?")
    return {
        "type": kind,
        "asgi": ASGI,
        "http_version": "1.1",
        "scheme": "http" if kind == "http" else "ws",
        "path": path,
        "raw_path": path.encode(),
        "query_string": query.encode(),
        "root_path": "",
        "headers": [(k.encode(), v.encode()) for k, v in headers.items()],
        "client": client,
        "server": SERVER,
    }


class WebSocketRefused(Exception):
    """The app closed the WebSocket before accepting it (``code``, ``reason``)."""

    def __init__(self, message: dict) -> None:
        self.code = message.get("code", 1000)
        self.reason = message.get("reason", "")
        super().__init__(f"WebSocket refused ({self.code}): {self.reason}")


class WebSocketClosed(Exception):
    """The app closed an accepted WebSocket."""


class WebSocketSession:
    """One WebSocket to the app: :meth:`send` text or bytes, :meth:`recv` what the app sent."""

    def __init__(self, loop: asyncio.AbstractEventLoop) -> None:
        self._loop = loop
        self._incoming: asyncio.Queue[dict] = asyncio.Queue()
        self._outgoing: queue.Queue[dict] = queue.Queue()
        self._incoming.put_nowait({"type": "websocket.connect"})
        self.task: Future[Any] | None = None

    async def receive(self) -> dict:
        return await self._incoming.get()

    async def deliver(self, message: dict) -> None:
        self._outgoing.put(message)

    def _push(self, message: dict) -> None:
        self._loop.call_soon_threadsafe(self._incoming.put_nowait, message)

    def handshake(self, timeout: float) -> None:
        """Wait for the app to accept (or raise WebSocketRefused)."""
        message = self._outgoing.get(timeout=timeout)
        if message["type"] != "websocket.accept":
            raise WebSocketRefused(message)

    def send(self, data: str | bytes) -> None:
        key = "bytes" if isinstance(data, bytes) else "text"
        self._push({"type": "websocket.receive", key: data})

    def recv(self, timeout: float) -> str | bytes:
        """The next message the app sent. Raises TimeoutError if none within ``timeout`` s."""
        try:
            message = self._outgoing.get(timeout=timeout)
        except queue.Empty:
            raise TimeoutError(f"no WebSocket message within {timeout:g} s") from None
        if message["type"] == "websocket.close":
            raise WebSocketClosed(message.get("reason", ""))
        return message.get("bytes") if message.get("bytes") is not None else message["text"]

    def close(self, timeout: float = 5.0) -> None:
        """Disconnect, as a page closing, and wait for the app's handler to end."""
        self._push({"type": "websocket.disconnect", "code": 1000})
        if self.task is not None:
            self.task.result(timeout)

    def __enter__(self) -> WebSocketSession:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


class AsgiClient:
    """Requests to ``app`` on an event loop thread of its own (close it)."""

    def __init__(self, app: Callable[..., Any], *, client: tuple[str, int] = CLIENT) -> None:
        self.app = app
        self.client = client
        self.loop = asyncio.new_event_loop()
        self._thread = threading.Thread(target=self.loop.run_forever, name="asgi", daemon=True)
        self._thread.start()

    def _run(self, coroutine: Any) -> Future[Any]:
        return asyncio.run_coroutine_threadsafe(coroutine, self.loop)

    def http(
        self,
        method: str,
        target: str,
        body: Any = None,
        headers: dict[str, str] | None = None,
        *,
        timeout: float = 30.0,
    ) -> tuple[int, Any, dict[str, str]]:
        """(status, decoded JSON or text, lower-case headers) of one request."""
        raw = body if isinstance(body, bytes) else json.dumps(body).encode() if body else b""
        sent = {"host": HOST, "content-type": "application/json", **_lower(headers)}
        scope = _scope("http", target, sent, self.client)
        scope["method"] = method
        return self._run(self._http(scope, raw)).result(timeout)

    async def _http(self, scope: dict, raw: bytes) -> tuple[int, Any, dict[str, str]]:
        request = [{"type": "http.request", "body": raw, "more_body": False}]
        start: dict = {}
        chunks: list[bytes] = []

        async def receive() -> dict:
            if request:
                return request.pop()
            await asyncio.Event().wait()  # no disconnect: the client waits for the reply
            return {"type": "http.disconnect"}

        async def send(message: dict) -> None:
            if message["type"] == "http.response.start":
                start.update(message)
            elif message["type"] == "http.response.body":
                chunks.append(message.get("body", b""))

        await self.app(scope, receive, send)
        headers = {k.decode().lower(): v.decode() for k, v in start.get("headers", [])}
        text = b"".join(chunks)
        try:
            return start["status"], json.loads(text), headers
        except ValueError:
            return start["status"], text.decode(errors="replace"), headers

    def websocket(
        self, target: str, headers: dict[str, str] | None = None, *, timeout: float = 5.0
    ) -> WebSocketSession:
        """An accepted WebSocket (raises WebSocketRefused if the app refuses it)."""
        scope = _scope("websocket", target, {"host": HOST, **_lower(headers)}, self.client)
        scope["subprotocols"] = []
        session = WebSocketSession(self.loop)
        session.task = self._run(self.app(scope, session.receive, session.deliver))
        session.handshake(timeout)
        return session

    def close(self) -> None:
        """Cancel what still runs on the loop, then stop it."""

        async def cancel_all() -> None:
            tasks = [t for t in asyncio.all_tasks() if t is not asyncio.current_task()]
            for task in tasks:
                task.cancel()
            await asyncio.gather(*tasks, return_exceptions=True)

        self._run(cancel_all()).result(10)
        self.loop.call_soon_threadsafe(self.loop.stop)
        self._thread.join(10)
        self.loop.close()
