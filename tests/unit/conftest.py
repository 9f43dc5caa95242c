"""The unit tier's rule: pure logic, in milliseconds; a test that opens a real Zenoh session or
talks on a network socket (connect, sendto) fails, naming the tier it belongs in (see
tests/tier_guard.py)."""

from __future__ import annotations

import pytest
from tier_guard import TRAFFIC, TierGuard, run_phase

GUARD = TierGuard("unit", sockets=TRAFFIC)


@pytest.hookimpl(wrapper=True)
def pytest_runtest_setup(item):
    return (yield from run_phase(GUARD, item))


@pytest.hookimpl(wrapper=True)
def pytest_runtest_call(item):
    return (yield from run_phase(GUARD, item))


@pytest.hookimpl(wrapper=True)
def pytest_runtest_teardown(item, nextitem):
    return (yield from run_phase(GUARD, item))
