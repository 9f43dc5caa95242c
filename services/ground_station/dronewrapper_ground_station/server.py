"""The web server: uvicorn serving the station's app on its own thread and event loop.

Its thread never installs signal handlers (only the main thread may): the process's Node keeps
SIGINT/SIGTERM and stops the server through :meth:`WebServer.stop`.
"""

from __future__ import annotations

import threading
import time

import uvicorn
from starlette.applications import Starlette

START_TIMEOUT_S = 15.0


class WebServer:
    """``app`` on ``host``:``port`` (0: a free port, see :attr:`port` once started)."""

    def __init__(self, app: Starlette, host: str, port: int) -> None:
        self.host = host
        self._server = uvicorn.Server(
            uvicorn.Config(app, host=host, port=port, log_level="warning", lifespan="off")
        )
        self._thread = threading.Thread(target=self._server.run, name="station-http", daemon=True)
        self.port = port

    def start(self, timeout: float = START_TIMEOUT_S) -> int:
        """Start serving; returns the port. Raises RuntimeError if it did not start in time."""
        self._thread.start()
        deadline = time.monotonic() + timeout
        while not self._server.started:
            if not self._thread.is_alive() or time.monotonic() > deadline:
                self.stop()
                raise RuntimeError(f"the web server did not start on {self.host}:{self.port}")
            time.sleep(0.02)
        self.port = self._server.servers[0].sockets[0].getsockname()[1]
        return self.port

    def stop(self, timeout: float = 5.0) -> None:
        """Close the connections and stop (bounded by ``timeout`` seconds)."""
        self._server.should_exit = True
        if self._thread.is_alive():
            self._thread.join(timeout)
