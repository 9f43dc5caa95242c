"""An unrelated process keeping one CPU core busy, as on a drone's shared companion computer."""

from __future__ import annotations

import contextlib
import subprocess
import sys
from collections.abc import Iterator

BUSY_LOOP = "while True: pass"


@contextlib.contextmanager
def one_core_busy() -> Iterator[subprocess.Popen]:
    """Run a pure busy loop (one core's worth of CPU) for the duration of the block."""
    process = subprocess.Popen([sys.executable, "-c", BUSY_LOOP])
    try:
        yield process
    finally:
        process.kill()
        process.wait(timeout=10)
