"""The DroneWrapper API for asyncio programs (for users coming from MAVSDK).

    import asyncio
    from dronewrapper.aio import Drone

    async def main():
        async with Drone() as drone:                 # connects, waits for telemetry
            await drone.takeoff(h=2.0)
            drone.set_cmd_vel(az=0.5)                # setpoints never block: plain calls
            async for position in drone.position():  # newest values as they arrive
                if position[2] > 1.9:
                    break
            await drone.land()

    asyncio.run(main())

One core, two fronts: :class:`Drone` drives a :class:`~dronewrapper.drone.DroneWrapper` (and its
:class:`~dronewrapper.client.DroneClient`, whose input holders the iterators read) and adds no
flight logic of its own. Blocking calls (take-off, landing, mode changes, parameters, waits)
run on a worker thread and are awaited, so the event loop keeps running; getters and setpoints
return at once, as in the sync API. Cancelling an awaited take-off or landing stops it: no
further step is taken and the setpoint stream stops (the bridge holds position); the awaiting
task sees CancelledError once the worker has stopped. Telemetry and frames are async iterators
of the newest values: a slow consumer skips values instead of queueing them (never a backlog).
The bridge's refusals of our setpoints are an async iterator too (:meth:`Drone.refusal_stream`),
each one kept: a refusal is an event, not a value to skip.

Many drones at once: :class:`Fleet` (:mod:`dronewrapper.fleet_aio`).
"""

from __future__ import annotations

import asyncio
import contextlib
import threading
from collections.abc import AsyncIterator, Callable
from typing import Any, TypeVar

import numpy as np

from dronewrapper import telemetry
from dronewrapper.client.inputs import camera_key_name
from dronewrapper.drone import DroneWrapper
from dronewrapper.fleet_aio import Fleet
from dronewrapper.msgs import registry
from dronewrapper.msgs.mavros import ExtendedState, State
from dronewrapper.msgs.refusal import Refusal
from dronewrapper.msgs.registry import Topic
from dronewrapper.msgs.sensor import BatteryState

__all__ = ["Drone", "Fleet"]

T = TypeVar("T")
V = TypeVar("V")

REFUSAL_BACKLOG = 100
"""Most refusals :meth:`Drone.refusal_stream` keeps for a consumer that has not taken them."""


class Drone:
    """One drone for asyncio code: the constructor's arguments are :class:`DroneWrapper`'s.

    Use ``async with Drone(...) as drone`` (or ``await drone.connect()`` and
    ``await drone.close()``). The sync object is :attr:`sync`, for anything not wrapped here.
    """

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        self._args, self._kwargs = args, kwargs
        self._sync: DroneWrapper | None = None

    # ------------------------------------------------------------------ lifecycle

    async def connect(self) -> Drone:
        """Open the session and wait for the bridge and its telemetry (see DroneWrapper)."""
        if self._sync is None:
            self._sync = await asyncio.to_thread(DroneWrapper, *self._args, **self._kwargs)
        return self

    async def close(self) -> None:
        """Stop commanding and close (the bridge hovers, then lands if nobody commands)."""
        if self._sync is not None:
            await asyncio.to_thread(self._sync.close)

    async def __aenter__(self) -> Drone:
        return await self.connect()

    async def __aexit__(self, exc_type: object, exc: object, tb: object) -> None:
        if self._sync is not None:
            await asyncio.to_thread(self._sync.__exit__, exc_type, exc, tb)

    @property
    def sync(self) -> DroneWrapper:
        """The underlying synchronous DroneWrapper (connected)."""
        if self._sync is None:
            raise RuntimeError("not connected: use `async with Drone(...)` or await connect()")
        return self._sync

    def __getattr__(self, name: str) -> Any:
        """Non-blocking members of DroneWrapper (getters, setpoints, ``ns`` ...) as they are."""
        if name.startswith("_") or name in _AWAITABLE:
            raise AttributeError(name)
        return getattr(self.sync, name)

    # ------------------------------------------------------------------ awaitable commands

    async def _run(self, method: Callable[..., T], *args: Any, **kwargs: Any) -> T:
        return await asyncio.to_thread(method, *args, **kwargs)

    async def _run_cancellable(self, method: Callable[..., T], *args: Any, **kwargs: Any) -> T:
        """``method(..., cancel=event)`` on a worker thread; a cancelled await sets the event
        and waits for the worker to stop before CancelledError goes on."""
        cancel = threading.Event()
        worker = asyncio.ensure_future(asyncio.to_thread(method, *args, cancel=cancel, **kwargs))
        try:
            return await asyncio.shield(worker)
        except asyncio.CancelledError:
            cancel.set()
            with contextlib.suppress(Exception):  # Cancelled, or what it raised on the way
                await worker
            raise

    async def takeoff(self, h: float = 3.0, **kwargs: Any) -> None:
        """Take off to ``h`` m and return there (see :meth:`DroneWrapper.takeoff`); cancel
        the await to stop it."""
        await self._run_cancellable(self.sync.takeoff, h, **kwargs)

    async def land(self, **kwargs: Any) -> None:
        """Land and return on the ground, disarmed (see :meth:`DroneWrapper.land`); cancel
        the await to stop it."""
        await self._run_cancellable(self.sync.land, **kwargs)

    async def arm(self, **kwargs: Any) -> None:
        await self._run(self.sync.arm, **kwargs)

    async def disarm(self, **kwargs: Any) -> None:
        await self._run(self.sync.disarm, **kwargs)

    async def set_mode(self, mode: str, **kwargs: Any) -> None:
        await self._run(self.sync.set_mode, mode, **kwargs)

    async def param_get(self, param: str, **kwargs: Any) -> int | float:
        return await self._run(self.sync.param_get, param, **kwargs)

    async def param_set(self, param: str, value: int | float, **kwargs: Any) -> int | float:
        return await self._run(self.sync.param_set, param, value, **kwargs)

    async def goto(self, lat: float, lon: float, alt: float, **kwargs: Any) -> None:
        await self._run(self.sync.goto, lat, lon, alt, **kwargs)

    async def goto_local(self, x: float, y: float, z: float, **kwargs: Any) -> None:
        await self._run(self.sync.goto_local, x, y, z, **kwargs)

    async def return_to_launch(self, **kwargs: Any) -> None:
        await self._run(self.sync.return_to_launch, **kwargs)

    async def upload_mission(self, plan: Any, **kwargs: Any) -> int:
        return await self._run(self.sync.upload_mission, plan, **kwargs)

    async def start_mission(self, **kwargs: Any) -> None:
        await self._run(self.sync.start_mission, **kwargs)

    async def pause_mission(self, **kwargs: Any) -> None:
        await self._run(self.sync.pause_mission, **kwargs)

    async def resume_mission(self, **kwargs: Any) -> None:
        await self._run(self.sync.resume_mission, **kwargs)

    async def set_envelope(self, **kwargs: Any) -> Any:
        return await self._run(self.sync.set_envelope, **kwargs)

    async def envelope(self, **kwargs: Any) -> Any:
        return await self._run(self.sync.envelope, **kwargs)

    async def reset_envelope(self, **kwargs: Any) -> Any:
        return await self._run(self.sync.reset_envelope, **kwargs)

    async def wait_for_connection(self, timeout: float = 10.0) -> State:
        return await self._run(self.sync.wait_for_connection, timeout)

    async def wait_for_altitude(self, z: float, timeout: float = 30.0, **kw: Any) -> np.ndarray:
        return await self._run(self.sync.wait_for_altitude, z, timeout, **kw)

    async def wait_for_landed_state(self, landed_state: int, timeout: float = 30.0) -> int:
        return await self._run(self.sync.wait_for_landed_state, landed_state, timeout)

    async def wait_for_image(self, camera: str = "frontal", timeout: float = 10.0) -> np.ndarray:
        return await self._run(self.sync.wait_for_image, camera, timeout)

    # ------------------------------------------------------------------ async iterators

    async def _newest(self, topic: Topic[V], **parts: str) -> AsyncIterator[V]:
        """The messages on ``topic`` as they arrive from now on, the newest each time: the
        drone client's holder of the key (the one the getters read; subscribed once per drone,
        until :meth:`close`), whose listener wakes the event loop."""
        loop = asyncio.get_running_loop()
        holder = self.sync.client.inputs.latest(topic, **parts)
        arrived = asyncio.Event()

        def notify() -> None:
            with contextlib.suppress(RuntimeError):  # the loop closed meanwhile
                loop.call_soon_threadsafe(arrived.set)

        holder.listen(notify)
        seen = holder.count
        try:
            while True:
                await arrived.wait()
                arrived.clear()
                got = holder.take(0.0, seen)
                if got is not None:
                    seen, value = got
                    yield value
        finally:
            holder.unlisten(notify)

    async def _stream(self, topic: Topic[V], convert: Callable[[V], T], **parts: str):
        async for msg in self._newest(topic, **parts):
            yield convert(msg)

    def position(self) -> AsyncIterator[np.ndarray]:
        """Positions ``[x, y, z]`` (local ENU m) as they arrive."""
        return self._stream(registry.LOCAL_POSE, telemetry.position_of)

    def orientation(self) -> AsyncIterator[np.ndarray]:
        """Orientations ``[roll, pitch, yaw]`` (rad, ENU) as they arrive."""
        return self._stream(registry.LOCAL_POSE, telemetry.orientation_of)

    def velocity(self) -> AsyncIterator[np.ndarray]:
        """Body FLU velocities ``[vx, vy, vz]`` (m/s) as they arrive."""
        return self._stream(registry.VELOCITY_BODY, telemetry.linear_of)

    def landed_state(self) -> AsyncIterator[int]:
        """MAVROS landed states (1 on ground, 2 in air, ...) as they arrive."""
        return self._stream(registry.EXTENDED_STATE, _landed_state_of)

    def state(self) -> AsyncIterator[State]:
        """Autopilot States (connected, armed, mode ...) as they arrive."""
        return self._stream(registry.STATE, _same)

    def battery(self) -> AsyncIterator[float]:
        """Battery charge fractions 0..1 as they arrive."""
        return self._stream(registry.BATTERY, _percentage_of)

    async def refusal_stream(self) -> AsyncIterator[Refusal]:
        """The bridge's refusals of our setpoints (and overrides of our commands), each as it
        arrives from now on (see :attr:`DroneWrapper.refusals`); at most
        :data:`REFUSAL_BACKLOG` wait for a slow consumer, the oldest dropped first."""
        loop = asyncio.get_running_loop()
        queue: asyncio.Queue[Refusal] = asyncio.Queue()

        def put(refusal: Refusal) -> None:
            if queue.qsize() >= REFUSAL_BACKLOG:
                queue.get_nowait()
            queue.put_nowait(refusal)

        def arrived(refusal: Refusal) -> None:
            with contextlib.suppress(RuntimeError):  # the loop closed meanwhile
                loop.call_soon_threadsafe(put, refusal)

        stop = self.sync.on_refusal(arrived)
        try:
            while True:
                yield await queue.get()
        finally:
            stop()

    async def frames(self, camera: str = "frontal") -> AsyncIterator[np.ndarray]:
        """Camera frames (BGR ``uint8``), the newest each time; slow consumers skip frames."""
        topic: Topic[Any] = (
            registry.IMAGE_COMPRESSED if self.sync.compressed_images else registry.IMAGE_RAW
        )
        async for msg in self._newest(topic, camera=camera_key_name(camera)):
            yield self.sync.decode_image(msg)


def _same(value: T) -> T:
    return value


def _landed_state_of(msg: ExtendedState) -> int:
    return int(msg.landed_state)


def _percentage_of(msg: BatteryState) -> float:
    return float(msg.percentage)


_AWAITABLE = frozenset(
    name for name, value in vars(Drone).items() if asyncio.iscoroutinefunction(value)
)
"""Blocking DroneWrapper methods that Drone replaces with awaitables (never passed through)."""
