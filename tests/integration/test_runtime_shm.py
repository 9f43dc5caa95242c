"""Shared-memory leftovers are swept: unmapped Zenoh segments go, mapped ones stay."""

from __future__ import annotations

import os
import subprocess
import sys
import time

import pytest

from dronewrapper.runtime.shm import mapped_segments, remove_stale_segments
from support import REPO

pytestmark = pytest.mark.integration


def test_frames_travel_by_shared_memory_and_leftovers_are_swept(router):
    out = subprocess.run(
        [sys.executable, str(REPO / "tests" / "data" / "shm_exchange.py"), router],
        capture_output=True, text=True, timeout=60, check=True,
        env={**os.environ, "PYTHONPATH": str(REPO / "tests")},
    ).stdout  # fmt: skip
    assert "fallbacks 0" in out.splitlines(), f"a local frame fell back from shared memory: {out}"
    segments = [line for line in out.splitlines() if line.endswith(".zenoh")]
    assert segments, "two local peers exchanging 900 kB frames should use Zenoh SHM segments"
    leftovers = [p for p in segments if os.path.exists(p)]
    assert leftovers, "Zenoh leaves its segments behind after a clean exit (the pitfall)"
    remove_stale_segments(min_age_s=0.0)
    in_use = mapped_segments()
    assert [p for p in leftovers if os.path.exists(p) and p not in in_use] == []


def test_sweep_keeps_mapped_and_young_segments(tmp_path):
    old, new, other = tmp_path / "old.zenoh", tmp_path / "new.zenoh", tmp_path / "other.txt"
    for path in (old, new, other):
        path.write_bytes(b"x")
    past = time.time() - 60
    os.utime(old, (past, past))
    assert remove_stale_segments(min_age_s=5.0, shm_dir=tmp_path) == [str(old)]
    assert new.exists() and other.exists()
