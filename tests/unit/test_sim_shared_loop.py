"""A simulated Iris's loop as deadlines (runner.wake) and on a host's shared loop
(dronewrapper_sim.shared_loop), in virtual time, without links."""

from __future__ import annotations

import math
import threading
from collections.abc import Sequence

import pytest

from dronewrapper.runtime.clock import VirtualClock
from dronewrapper.runtime.poller import Poller
from dronewrapper_sim.config import SimConfig
from dronewrapper_sim.runner import SimRunner
from dronewrapper_sim.shared_loop import run_on_poller
from dronewrapper_sim.world.scenario import load_scenario


def runner(clock: VirtualClock) -> SimRunner:
    config = SimConfig(cameras=False, udp_onboard="off", udp_gcs="off", loop_rate_hz=50.0)
    sim = SimRunner(config, load_scenario("empty"), node=None)
    sim.time = clock
    return sim


class NoSockets:
    """Readiness for a loop with no socket: never asked (the poller waits on its clock)."""

    def wait(self, fds: Sequence[int], timeout: float) -> list[int]:
        raise AssertionError("no socket to wait on")


def test_sims_started_apart_wake_on_one_grid_and_keep_the_physics_rate():
    clock = VirtualClock(monotonic=1000.0)
    sims = []
    for start in (1000.003, 1000.011):
        clock.advance_to(start)
        sim = runner(clock)
        sim.begin()
        sims.append(sim)
    wakes: list[list[float]] = [[], []]
    t = clock.monotonic()
    while t < 1000.5:
        clock.advance_to(t)
        for i, sim in enumerate(sims):
            if sim.next_wake() <= t:
                sim.wake(t)
                wakes[i].append(t)
        t = min(sim.next_wake() for sim in sims)
    later = [[t for t in w if t > 1000.05] for w in wakes]  # after their first wake-ups
    assert later[0] == later[1]  # the same instants
    gaps = {round(b - a, 6) for a, b in zip(later[0], later[0][1:], strict=False)}
    assert gaps == {0.02}
    for sim in sims:  # 250 Hz physics, five steps a wake-up
        assert sim.autopilot.steps == pytest.approx(250 * (clock.monotonic() - sim._t0), abs=5)


def test_a_sim_failing_on_the_shared_loop_raises_on_its_own_thread_and_stops():
    clock = VirtualClock(monotonic=1000.0)
    poller = Poller(clock=clock, readiness=NoSockets())
    sim = runner(clock)
    steps = sim.autopilot.step

    def step(dt: float) -> None:
        if sim.autopilot.steps >= 100:
            raise RuntimeError("a step failed")
        steps(dt)

    sim.autopilot.step = step  # type: ignore[method-assign]
    stop = threading.Event()
    with pytest.raises(RuntimeError, match="a step failed"):
        run_on_poller(sim, poller, stop)
    assert stop.is_set()
    assert sim.autopilot.steps == 100
    assert clock.monotonic() == pytest.approx(1000.4, abs=0.05)
    assert poller.errors == 1
    clock.run_for(0.2)
    assert poller.entries == 0
    assert math.isfinite(sim.autopilot.time_s)
