"""An unrelated program keeping one core busy while a benchmark runs, as on a laptop doing
other things (``bench.fleet --busy``, ``bench.drone_cost --busy``)."""

from __future__ import annotations

import contextlib
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path


def autogroup_nice(pid: int | str = "self") -> str | None:
    """The nice value of process ``pid``'s autogroup (Linux with ``sched_autogroup``; None
    elsewhere): the kernel shares the CPU between sessions by their autogroups' weights, then
    between the threads of each."""
    try:
        return Path(f"/proc/{pid}/autogroup").read_text().split()[-1]
    except (OSError, IndexError):
        return None


@contextlib.contextmanager
def busy_core(busy: bool) -> Iterator[None]:
    """An unrelated program keeping one core busy (a Python busy loop) while the block runs.

    It runs in a session of its own, as a program started from another terminal does; where
    the kernel groups sessions (autogroups), its group gets this bench's group's weight, so
    that it and the fleet share the cores as two programs of one user do."""
    if not busy:
        yield
        return
    process = subprocess.Popen([sys.executable, "-c", "while True: pass"], start_new_session=True)
    nice = autogroup_nice()
    if nice is not None and autogroup_nice(process.pid) != nice:
        with contextlib.suppress(OSError):
            Path(f"/proc/{process.pid}/autogroup").write_text(nice)
    try:
        yield
    finally:
        process.kill()
        process.wait(10)
