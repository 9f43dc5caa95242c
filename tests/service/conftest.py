"""The service tier's rule: one process's logic on the fake bus, in injected time; a test that
opens a real Zenoh session or a network socket, or starts a process, fails, naming the tier it
belongs in (see tests/tier_guard.py)."""

from __future__ import annotations

import pytest
from tier_guard import NETWORK, TierGuard, collect, refusing, run_phase

GUARD = TierGuard("service", sockets=NETWORK)

router = refusing(GUARD, "router", "asks for a real Zenoh router (the router fixture)")
spawn = refusing(GUARD, "spawn", "asks to start processes (the spawn fixture)")


@pytest.hookimpl(wrapper=True)
def pytest_runtest_setup(item):
    return (yield from run_phase(GUARD, item))


@pytest.hookimpl(wrapper=True)
def pytest_runtest_call(item):
    return (yield from run_phase(GUARD, item))


@pytest.hookimpl(wrapper=True)
def pytest_runtest_teardown(item, nextitem):
    return (yield from run_phase(GUARD, item))


@pytest.hookimpl(wrapper=True)
def pytest_make_collect_report(collector):
    return (yield from collect(GUARD, collector))
