"""The service tier's rule: one process's logic on the fake bus, in injected time; a test that
opens a real Zenoh session or a network socket, or starts a process, fails, naming the tier it
belongs in (see tests/tier_guard.py)."""

from __future__ import annotations

from tier_guard import NETWORK, TierGuard, conftest_hooks

GUARD = TierGuard("service", sockets=NETWORK)
globals().update(conftest_hooks(GUARD))  # the guarded hooks and the refused fixtures
