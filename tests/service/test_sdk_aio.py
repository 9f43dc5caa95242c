"""The asyncio API mirrors the sync one, on the fake bus (tests/bus_autopilot.py SdkRig).

Its blocking calls run on a worker thread while the event loop keeps running; telemetry comes
as async iterators of the newest values. The constructor's diagnoses over a real router are
in tests/integration/test_sdk_zenoh.py.
"""

from __future__ import annotations

import asyncio

import numpy as np
import pytest
from bus_autopilot import REFUSED, TELEMETRY_PERIOD_S, SdkRig

from dronewrapper import CommandRefused, InvalidArgument, NotConnected
from dronewrapper.aio import Drone
from dronewrapper.msgs import registry
from dronewrapper.msgs.mavros import LANDED_STATE_ON_GROUND, MASK_VELOCITY
from dronewrapper.msgs.sensor import Image
from dronewrapper.msgs.std import Header
from dronewrapper.runtime.fake import FakeBus, FakeNode


def run(coroutine):
    return asyncio.run(asyncio.wait_for(coroutine, 60))


@pytest.fixture
def rig():
    return SdkRig(open_drone=False)


async def feed(rig: SdkRig, stop: asyncio.Event) -> None:
    """Tick the aircraft from the event loop (so each value arrives on the loop's thread)."""
    while not stop.is_set():
        rig.run(TELEMETRY_PERIOD_S)
        await asyncio.sleep(0)


def test_connect_getters_and_setpoints_pass_through(rig):
    async def main():
        async with Drone(**rig.options()) as drone:
            rig.run(TELEMETRY_PERIOD_S)
            assert drone.get_landed_state() == LANDED_STATE_ON_GROUND
            assert drone.get_battery() == pytest.approx(0.8)
            assert drone.sync.is_connected()
            drone.set_cmd_vel(vx=0.5)  # plain call, never awaited
            drone.stop_commanding()

    run(main())
    first = rig.pilot.setpoints()[0][1]
    assert first.type_mask == MASK_VELOCITY and first.velocity.x == 0.5


def test_takeoff_and_land_are_awaitable_and_the_loop_keeps_running(rig):
    """Each wait of the blocking take-off and landing (on the worker thread) asks the event
    loop to run a step and waits for it: a loop blocked by the call would never answer."""
    answered = 0

    async def main():
        loop = asyncio.get_running_loop()

        def step_while_the_loop_runs(until: float, done) -> None:
            nonlocal answered
            asyncio.run_coroutine_threadsafe(asyncio.sleep(0), loop).result(timeout=30)
            answered += 1
            rig.run_until(until, done)

        rig.bus.clock.stepper = step_while_the_loop_runs
        async with Drone(**rig.options()) as drone:
            rig.run(TELEMETRY_PERIOD_S)
            await drone.takeoff(h=1.0, timeout=20)
            climbed = drone.get_position()[2]
            await drone.land(timeout=20)
            return climbed

    assert run(main()) >= 0.9
    assert answered >= 10  # the loop ran at each of the climb's waits
    names = [name for _, name in rig.pilot.calls]
    assert names == ["set_mode", "arming", "land"]


def test_cancelling_an_awaited_takeoff_stops_it(rig):
    """The take-off runs on a worker thread; cancelling its await stops the climb's steps and
    the setpoint stream before CancelledError reaches the awaiting code. The cancel comes
    mid-climb: the worker's wait hands it to the event loop and goes on once the loop ran it."""
    heights: list[float] = []

    async def main():
        loop = asyncio.get_running_loop()
        takeoff: asyncio.Task | None = None

        async def cancel_takeoff() -> None:
            takeoff.cancel()
            await asyncio.sleep(0)  # the task's wake-up runs first (FIFO): it sets the cancel

        def step(until: float, done) -> None:
            if not heights and rig.pilot.z > 0.3:
                heights.append(rig.pilot.z)
                asyncio.run_coroutine_threadsafe(cancel_takeoff(), loop).result(timeout=30)
            rig.run_until(until, done)

        rig.bus.clock.stepper = step
        async with Drone(**rig.options()) as drone:
            rig.run(TELEMETRY_PERIOD_S)
            takeoff = asyncio.create_task(drone.takeoff(h=2.0, timeout=20))
            with pytest.raises(asyncio.CancelledError):
                await takeoff
            stopped_at, height = rig.bus.clock(), rig.pilot.z
            assert drone.commanding is None
            rig.run(1.0)
            return stopped_at, height

    stopped_at, height = run(main())
    assert height == heights[0] < 1.0  # no bus time passed after the cancel: stopped mid-climb
    assert rig.pilot.setpoints(since=stopped_at + 1e-9) == []  # nothing streamed after
    assert [name for _, name in rig.pilot.calls] == ["set_mode", "arming"]


def test_async_iterators_yield_newest_telemetry_and_stop_cleanly(rig):
    async def main():
        async with Drone(**rig.options()) as drone:
            stop = asyncio.Event()
            feeder = asyncio.create_task(feed(rig, stop))
            positions = [p async for p in _take(drone.position(), 5)]
            states = [s async for s in _take(drone.landed_state(), 3)]
            batteries = [b async for b in _take(drone.battery(), 2)]
            stop.set()
            await feeder
            return positions, states, batteries

    positions, states, batteries = run(main())
    assert all(isinstance(p, np.ndarray) and p.shape == (3,) for p in positions)
    assert states == [LANDED_STATE_ON_GROUND] * 3
    assert batteries == [pytest.approx(0.8)] * 2


def test_frames_iterator_gives_bgr_arrays(rig):
    camera = FakeNode("camera", rig.bus).publisher(registry.IMAGE_RAW, camera="cam_frontal")
    image = np.full((24, 32, 3), 7, np.uint8)

    async def main():
        async with Drone(**rig.options()) as drone:
            frames = drone.frames("frontal")
            first = asyncio.ensure_future(anext(frames))
            await asyncio.sleep(0)  # subscribed
            header = Header(stamp=rig.bus.clock())
            camera.put(Image(header=header, height=24, width=32, step=96, data=image.tobytes()))
            frame = await first
            await frames.aclose()
            return frame

    frame = run(main())
    assert frame.shape == (24, 32, 3) and int(frame[0, 0, 0]) == 7


def test_errors_are_the_sync_ones(rig):
    rig.pilot.refuse["arming"] = "Arming denied: preflight checks failed"

    async def main():
        async with Drone(**rig.options()) as drone:
            rig.run(TELEMETRY_PERIOD_S)
            with pytest.raises(InvalidArgument):
                drone.set_cmd_vel(vx=float("nan"))
            with pytest.raises(CommandRefused) as info:
                await drone.takeoff(h=1.0, timeout=10)
            return info.value

    refusal = run(main())
    assert refusal.result == REFUSED and "preflight" in str(refusal)


def test_no_bridge_is_the_same_clear_error():
    bus = FakeBus()  # nobody publishes: the constructor waits (briefly) in vain

    async def main():
        await Drone(node=FakeNode("app", bus), timeout=0.05).connect()

    with pytest.raises(NotConnected, match=r"no bridge for drone 'drone'.*nothing published"):
        run(main())


def test_blocking_members_are_never_passed_through_unawaited(rig):
    async def main():
        async with Drone(**rig.options()) as drone:
            assert asyncio.iscoroutinefunction(Drone.takeoff)
            with pytest.raises(AttributeError):
                drone.__getattr__("takeoff")  # the sync one is never handed out
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
