"""The asyncio API mirrors the sync one over the same fake PX4-like bridge (real Zenoh)."""

from __future__ import annotations

import asyncio
import time

import numpy as np
import pytest

from dronewrapper import CommandRefused, InvalidArgument, NotConnected
from dronewrapper.aio import Drone
from dronewrapper.msgs.mavros import LANDED_STATE_ON_GROUND, MAV_RESULT_DENIED
from fake_bridge import FakeBridge
from support import wait_for


@pytest.fixture
def bridge(router):
    fake = FakeBridge(router)
    yield fake
    fake.close()


def run(coroutine):
    return asyncio.run(asyncio.wait_for(coroutine, 60))


def test_connect_getters_and_setpoints_pass_through(router, bridge):
    async def main():
        async with Drone("drone", router, timeout=10) as drone:
            assert drone.get_landed_state() == LANDED_STATE_ON_GROUND
            assert drone.get_battery() == pytest.approx(0.8)
            assert drone.sync.is_connected()
            t0 = time.monotonic()
            drone.set_cmd_vel(vx=0.5)  # plain call, never awaited
            await asyncio.sleep(0.5)
            drone.stop_commanding()
            return t0

    t0 = run(main())
    assert len(bridge.setpoints_since(t0)) >= 5


def test_takeoff_and_land_are_awaitable_and_the_loop_keeps_running(router, bridge):
    ticks = 0

    async def ticker():
        nonlocal ticks
        while True:
            await asyncio.sleep(0.05)
            ticks += 1

    async def main():
        async with Drone("drone", router, timeout=10) as drone:
            task = asyncio.create_task(ticker())
            await drone.takeoff(h=1.0, timeout=20)
            climbed = drone.get_position()[2]
            await drone.land(timeout=20)
            task.cancel()
            return climbed

    assert run(main()) >= 0.9
    assert ticks >= 10  # the event loop ran while the drone climbed and landed
    assert bridge.calls[:2] == ["set_mode OFFBOARD", "arming True"] and bridge.calls[-1] == "land"


def test_async_iterators_yield_newest_telemetry_and_stop_cleanly(router, bridge):
    async def main():
        async with Drone("drone", router, timeout=10) as drone:
            positions = []
            async for position in drone.position():
                positions.append(position)
                if len(positions) == 5:
                    break
            states = [s async for s in _take(drone.landed_state(), 3)]
            batteries = [b async for b in _take(drone.battery(), 2)]
            return positions, states, batteries

    positions, states, batteries = run(main())
    assert all(isinstance(p, np.ndarray) and p.shape == (3,) for p in positions)
    assert states == [LANDED_STATE_ON_GROUND] * 3
    assert batteries == [pytest.approx(0.8)] * 2


def test_frames_iterator_gives_bgr_arrays(router, bridge):
    async def main():
        async with Drone("drone", router, timeout=10) as drone:
            frames = drone.frames("frontal")
            stop = asyncio.Event()

            async def feed():
                image = np.full((24, 32, 3), 7, np.uint8)
                while not stop.is_set():
                    bridge.publish_image(image, time.time())
                    await asyncio.sleep(0.05)

            feeder = asyncio.create_task(feed())
            frame = await anext(frames)
            stop.set()
            await feeder
            await frames.aclose()
            return frame

    frame = run(main())
    assert frame.shape == (24, 32, 3) and int(frame[0, 0, 0]) == 7


def test_errors_are_the_sync_ones(router, bridge):
    bridge.refuse_arming = "Arming denied: preflight checks failed"

    async def main():
        async with Drone("drone", router, timeout=10) as drone:
            with pytest.raises(InvalidArgument):
                drone.set_cmd_vel(vx=float("nan"))
            with pytest.raises(CommandRefused) as info:
                await drone.takeoff(h=1.0, timeout=10)
            return info.value

    refusal = run(main())
    assert refusal.result == MAV_RESULT_DENIED and "preflight" in str(refusal)


def test_no_bridge_is_the_same_clear_error(router):
    async def main():
        await Drone("drone", router, timeout=1.0).connect()

    with pytest.raises(NotConnected, match="no bridge"):
        run(main())


def test_blocking_members_are_never_passed_through_unawaited(router, bridge):
    async def main():
        async with Drone("drone", router, timeout=10) as drone:
            assert asyncio.iscoroutinefunction(Drone.takeoff)
            wait_for(lambda: drone.get_state() is not None, 5, what="state")
            with pytest.raises(RuntimeError, match="not connected"):
                Drone().sync  # noqa: B018
            return drone.ns

    assert run(main()) == "drone"


async def _take(iterator, n):
    taken = 0
    async for value in iterator:
        yield value
        taken += 1
        if taken == n:
            await iterator.aclose()
            return
