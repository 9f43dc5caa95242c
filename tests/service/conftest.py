"""The service tier's rule: one process's logic on the fake bus, in injected time; a test that
opens a real Zenoh session or a network socket fails, naming the tier it belongs in (see
tests/tier_guard.py)."""

from __future__ import annotations

import pytest
from tier_guard import NETWORK, TierGuard, run_phase

GUARD = TierGuard("service", sockets=NETWORK)


@pytest.hookimpl(wrapper=True)
def pytest_runtest_setup(item):
    return (yield from run_phase(GUARD, item))


@pytest.hookimpl(wrapper=True)
def pytest_runtest_call(item):
    return (yield from run_phase(GUARD, item))


@pytest.hookimpl(wrapper=True)
def pytest_runtest_teardown(item, nextitem):
    return (yield from run_phase(GUARD, item))
