"""Zenoh shared-memory leftovers: segments in /dev/shm that no process maps any more.

Zenoh (1.10) leaves its ``/dev/shm/*.zenoh`` segments behind even after a clean
``session.close()`` (up to 16 MiB each), and always after a kill. On a Jetson that runs the
graph many times a day this fills RAM-backed /dev/shm, so every Node and the launcher sweep on
exit. A segment is removed only when no live process maps it and it is older than
``min_age_s`` (so one being created right now is never touched); only our own user's files
can be removed anyway (/dev/shm is sticky).
"""

from __future__ import annotations

import contextlib
import os
import time
from pathlib import Path

SHM_DIR = Path("/dev/shm")
SUFFIX = ".zenoh"


def mapped_segments(pid: int | None = None) -> set[str]:
    """Paths of Zenoh segments mapped by process ``pid``, or by any process we can see."""
    mapped: set[str] = set()
    pattern = f"{pid}/maps" if pid is not None else "[0-9]*/maps"
    for maps in Path("/proc").glob(pattern):
        try:
            text = maps.read_text()
        except OSError:  # the process ended, or is not ours to read
            continue
        for line in text.splitlines():
            if line.endswith(SUFFIX):
                mapped.add(line.split(maxsplit=5)[-1].removesuffix(" (deleted)"))
    return mapped


def remove_stale_segments(min_age_s: float = 5.0, shm_dir: Path = SHM_DIR) -> list[str]:
    """Remove unmapped Zenoh segments older than ``min_age_s``; returns the removed paths."""
    if not shm_dir.is_dir():
        return []
    candidates = list(shm_dir.glob(f"*{SUFFIX}"))
    if not candidates:
        return []
    in_use = mapped_segments()
    now = time.time()
    removed = []
    for path in candidates:
        if str(path) in in_use:
            continue
        with contextlib.suppress(OSError):
            info = path.stat()
            if now - info.st_mtime >= min_age_s and info.st_uid == os.getuid():
                path.unlink()
                removed.append(str(path))
    return removed
