"""One running process of a graph: started in its own session (the launcher, not the
terminal, decides the stop order), its output forwarded line by line with its name as prefix,
stopped with SIGINT then SIGKILL, and stopped by Linux if the launcher is killed
(:func:`dronewrapper.runtime.children.die_with_parent`)."""

from __future__ import annotations

import os
import signal
import subprocess
import threading
from typing import TextIO

from dronewrapper.runtime.children import die_with_parent
from dronewrapper_compose.graph import REPO, ProcessSpec


class Child:
    """A running process of the graph, with its output forwarded line by line."""

    def __init__(
        self,
        spec: ProcessSpec,
        argv: list[str],
        env: dict[str, str],
        out: TextIO,
        out_lock: threading.Lock,
        width: int,
        *,
        label: str = "",
        ns: str = "",
    ) -> None:
        self.spec = spec
        self.name = label or spec.name  # a fleet's process: ``drone2/sim``
        self.ns = ns  # the namespace it runs under (its liveliness token's)
        self.argv = argv
        self.stopping = False
        self.proc = subprocess.Popen(
            argv,
            stdin=subprocess.DEVNULL,
            stdout=subprocess.PIPE,
            stderr=subprocess.STDOUT,
            env={**os.environ, "PYTHONUNBUFFERED": "1", **env},
            cwd=REPO,
            start_new_session=True,  # the launcher, not the terminal, decides the stop order
            preexec_fn=die_with_parent,
        )
        prefix = f"{self.name:>{width}} | "
        self._reader = threading.Thread(
            target=self._forward, args=(prefix, out, out_lock), daemon=True
        )
        self._reader.start()

    def _forward(self, prefix: str, out: TextIO, lock: threading.Lock) -> None:
        assert self.proc.stdout is not None
        for raw in iter(self.proc.stdout.readline, b""):
            line = raw.decode("utf-8", "replace").rstrip("\n")
            with lock:
                out.write(prefix + line + "\n")
                out.flush()

    def poll(self) -> int | None:
        return self.proc.poll()

    def interrupt(self) -> None:
        self.stopping = True
        if self.proc.poll() is None:
            self.proc.send_signal(signal.SIGINT)

    def wait(self, timeout: float) -> int | None:
        try:
            return self.proc.wait(max(timeout, 0.0))
        except subprocess.TimeoutExpired:
            return None

    def kill(self) -> None:
        if self.proc.poll() is None:
            self.proc.kill()
            self.proc.wait(5)

    def join_output(self) -> None:
        self._reader.join(2)
