"""Many drones for asyncio programs: :class:`dronewrapper.fleet.Fleet` with awaitable commands.

    import asyncio
    from dronewrapper.aio import Fleet

    async def main():
        async with Fleet(count=3) as fleet:                 # finds 3 drones online
            (await fleet.takeoff(h=2.0)).raise_errors()     # all at once, one Outcome each
            async for outcome in fleet.as_completed(lambda d: d.land()):
                print(outcome.name, "landed" if outcome.ok else outcome.error)

    asyncio.run(main())

The calls run on the sync fleet's workers, one per drone (never the event loop's default
executor, whose few threads one slow drone could hold); the loop awaits them. Setpoints and
:meth:`online` are plain calls, as in the sync API.
"""

from __future__ import annotations

import asyncio
from collections.abc import AsyncIterator, Callable, Iterable
from typing import Any, TypeVar

from dronewrapper.drone import DroneWrapper
from dronewrapper.fleet import Fleet as SyncFleet
from dronewrapper.fleet_results import FleetResult, Outcome

T = TypeVar("T")

_PASSED_THROUGH = frozenset(
    {"drones", "names", "online", "set_cmd_pos", "formation", "stop_commanding", "submit"}
)
"""Non-blocking members of the sync fleet, used as they are."""


class Fleet:
    """Several drones for asyncio code: the arguments are :meth:`dronewrapper.fleet.Fleet.connect`'s
    (or give an open sync fleet as ``fleet=``). Use ``async with Fleet(...) as fleet``."""

    def __init__(self, *args: Any, fleet: SyncFleet | None = None, **kwargs: Any) -> None:
        self._args, self._kwargs = args, kwargs
        self._sync = fleet

    async def connect(self) -> Fleet:
        """Find the drones and open each (see :meth:`dronewrapper.fleet.Fleet.connect`)."""
        if self._sync is None:
            self._sync = await asyncio.to_thread(SyncFleet.connect, *self._args, **self._kwargs)
        return self

    async def close(self) -> None:
        if self._sync is not None:
            await asyncio.to_thread(self._sync.close)

    async def __aenter__(self) -> Fleet:
        return await self.connect()

    async def __aexit__(self, *exc: object) -> None:
        await self.close()

    @property
    def sync(self) -> SyncFleet:
        """The underlying synchronous fleet (connected)."""
        if self._sync is None:
            raise RuntimeError("not connected: use `async with Fleet(...)` or await connect()")
        return self._sync

    def __getattr__(self, name: str) -> Any:
        if name in _PASSED_THROUGH:
            return getattr(self.sync, name)
        raise AttributeError(name)

    def __len__(self) -> int:
        return len(self.sync)

    # ---- running a call on every drone

    async def each(
        self,
        call: Callable[[DroneWrapper], T],
        names: Iterable[str] | None = None,
        *,
        wait_s: float | None = None,
        what: str = "fleet call",
    ) -> FleetResult[T]:
        """``call(drone)`` on every drone at once, awaited; each drone's :class:`Outcome` (a
        call still running after ``wait_s`` seconds is a Timeout, as in the sync fleet)."""
        futures = self.sync.submit(call, names)
        waited = [asyncio.wrap_future(future) for future in futures.values()]
        await asyncio.wait(waited, timeout=wait_s)
        return self.sync.collect(futures, 0.0, what)

    async def as_completed(
        self, call: Callable[[DroneWrapper], T], names: Iterable[str] | None = None
    ) -> AsyncIterator[Outcome[T]]:
        """``call(drone)`` on every drone at once; each drone's :class:`Outcome` as it ends."""
        futures = self.sync.submit(call, names)
        by_task = {asyncio.wrap_future(future): name for name, future in futures.items()}
        pending = set(by_task)
        while pending:
            done, pending = await asyncio.wait(pending, return_when=asyncio.FIRST_COMPLETED)
            for task in done:
                name = by_task[task]
                yield self.sync.collect({name: futures[name]}, 0.0)[name]

    # ---- the commands

    async def takeoff(self, h: float = 3.0, *, timeout: float = 30.0, **kw: Any) -> FleetResult:
        return await self.each(lambda d: d.takeoff(h, timeout=timeout), what="takeoff", **kw)

    async def land(self, *, timeout: float = 60.0, **kw: Any) -> FleetResult:
        return await self.each(lambda d: d.land(timeout=timeout), what="land", **kw)

    async def arm(self, **kw: Any) -> FleetResult:
        return await self.each(lambda d: d.arm(), what="arming", **kw)

    async def disarm(self, **kw: Any) -> FleetResult:
        return await self.each(lambda d: d.disarm(), what="disarming", **kw)

    async def set_mode(self, mode: str, **kw: Any) -> FleetResult:
        return await self.each(lambda d: d.set_mode(mode), what=f"set_mode {mode}", **kw)

    async def take_command(self, *, take_over: bool = True, **kw: Any) -> FleetResult:
        call = lambda d: d.take_command(take_over=take_over)  # noqa: E731
        return await self.each(call, what="take_command", **kw)
