"""The unit tier's rule: pure logic, in milliseconds; a test that opens a real Zenoh session,
talks on a network socket (connect, sendto) or starts a process fails, naming the tier it
belongs in (see tests/tier_guard.py)."""

from __future__ import annotations

from tier_guard import TRAFFIC, TierGuard, conftest_hooks

GUARD = TierGuard("unit", sockets=TRAFFIC)
globals().update(conftest_hooks(GUARD))  # the guarded hooks and the refused fixtures
