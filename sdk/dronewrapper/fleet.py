"""Many drones at once: find them online, command them all concurrently, one result per drone.

    from dronewrapper.fleet import Fleet

    with Fleet.connect(count=5) as fleet:          # waits until 5 bridges are online
        print(fleet.online())                      # name, kind and health of each
        fleet.takeoff(h=2.0).raise_errors()        # all at once; one Outcome per drone
        fleet.formation({"drone1": (0, 0), "drone2": (2, 0)}, z=2.0)
        fleet.land()

A :class:`Fleet` holds one :class:`~dronewrapper.drone.DroneWrapper` per drone, all on one
node (one Zenoh session). Every drone has its own worker thread: a command to all is one call
per drone, each on that drone's worker, so a drone that answers slowly (or not at all) delays
only itself.
A call returns a :class:`FleetResult`, a mapping of drone name to :class:`Outcome` (the value,
or the exception that drone's call raised, and how long it took). Setpoints never block, as in
the one-drone API; they are returned as outcomes too (a refused setpoint is an error there).

Each drone keeps its own local frame (ENU, origin at its take-off point): a formation is given
in one shared frame, and the drones' take-off points in that frame (``origins``) are subtracted.
"""

from __future__ import annotations

import concurrent.futures
import contextlib
import functools
import time
from collections.abc import Callable, Iterable, Mapping, Sequence
from typing import Any, TypeVar

from dronewrapper.connection import open_node
from dronewrapper.discovery import BRIDGE_PREFIX, default_connect
from dronewrapper.drone import DroneWrapper
from dronewrapper.errors import NotConnected, Timeout
from dronewrapper.fleet_online import (
    DroneInfo,
    bridges_online,
    describe,
    open_drones,
    wait_for_bridges,
)
from dronewrapper.fleet_results import FleetError, FleetResult, Outcome, timed
from dronewrapper.msgs.refusal import Refusal
from dronewrapper.msgs.registry import DEFAULT_NAMESPACE
from dronewrapper.runtime.contract import NodeApi

__all__ = ["DroneInfo", "Fleet", "FleetError", "FleetResult", "Outcome"]

T = TypeVar("T")


class Fleet:
    """Several drones, commanded together (see the module doc).

    Args:
        drones: {name: DroneWrapper}, already open (:meth:`connect` opens them from the router).
        bridges: {name: bridge process name}, for :meth:`online` (default: each drone's bridge
            is looked up by liveliness).
        alive: returns the liveliness keys online now (default: each drone's own bridge).
        owns: close the drones (and ``node``) in :meth:`close`.
        node: the node the drones stand on, closed in :meth:`close` when ``owns``.
    """

    def __init__(
        self,
        drones: Mapping[str, DroneWrapper],
        *,
        bridges: Mapping[str, str] | None = None,
        alive: Callable[[], set[str]] | None = None,
        owns: bool = False,
        node: NodeApi | None = None,
    ) -> None:
        if not drones:
            raise NotConnected("a fleet needs at least one drone")
        self.drones: dict[str, DroneWrapper] = dict(drones)
        self._bridges = dict(bridges or {})
        self._alive = alive
        self._owns = owns
        self._node = node
        self._workers = {
            name: concurrent.futures.ThreadPoolExecutor(1, thread_name_prefix=f"fleet-{name}")
            for name in self.drones
        }
        self._closed = False

    # ---- opening and closing

    @classmethod
    def connect(
        cls,
        names: Sequence[str] | None = None,
        connect: str | None = None,
        timeout: float = 10.0,
        *,
        count: int | None = None,
        mode: str = "client",
        identity: str = "",
        **drone_options: Any,
    ) -> Fleet:
        """Find the drones online and open each (one node for all).

        Args:
            names: the drones to open; None: every drone whose bridge is online.
            connect: the router endpoint (default env ``DRONEWRAPPER_CONNECT`` or loopback).
            timeout: seconds to reach the router, to find the drones and to connect to each.
            count: with ``names`` None, wait until at least this many bridges are online.
            drone_options: more :class:`DroneWrapper` arguments (``service_timeout`` ...).

        Raises:
            NotConnected: no router, no drone online, fewer than ``count`` after ``timeout``, or
                a named drone not connected (the message names each missing one).
        """
        endpoint = connect or default_connect()
        deadline = time.monotonic() + timeout
        node = open_node(DEFAULT_NAMESPACE, endpoint, timeout, mode=mode, identity=identity)
        try:
            bridges = wait_for_bridges(
                lambda: node.alive_services("*", timeout=1.0), names, count, deadline
            )
            drones = open_drones(
                list(bridges),
                lambda name: DroneWrapper(
                    name,
                    endpoint,
                    max(0.5, deadline - time.monotonic()),
                    node=node,
                    identity=identity,
                    **drone_options,
                ),
            )
        except BaseException:
            node.close()
            raise
        return cls(
            drones,
            bridges=bridges,
            alive=lambda: node.alive_services("*", timeout=1.0),
            owns=True,
            node=node,
        )

    def __enter__(self) -> Fleet:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def close(self) -> None:
        """Stop every drone's commanding and close them if ours (the bridges hover, then land
        after their ``commander_lost_timeout``); idempotent."""
        if self._closed:
            return
        self._closed = True
        for worker in self._workers.values():
            worker.shutdown(wait=False, cancel_futures=True)
        for drone in self.drones.values():
            with contextlib.suppress(Exception):
                drone.stop_commanding()
                if self._owns:
                    drone.close()
        if self._owns and self._node is not None:
            with contextlib.suppress(Exception):
                self._node.close()

    @property
    def names(self) -> list[str]:
        return list(self.drones)

    def __len__(self) -> int:
        return len(self.drones)

    def __getitem__(self, name: str) -> DroneWrapper:
        return self.drones[name]

    def __iter__(self):
        return iter(self.drones.values())

    def __repr__(self) -> str:
        return f"Fleet({', '.join(self.drones)})"

    # ---- who is online

    def online(self) -> list[DroneInfo]:
        """Every drone whose bridge is online now (ours and any other), with kind and health."""
        if self._alive is not None:
            bridges = bridges_online(self._alive())
        else:
            bridges = {name: self._bridges.get(name, BRIDGE_PREFIX) for name in self.drones}
        return [describe(name, bridge, self.drones.get(name)) for name, bridge in bridges.items()]

    # ---- what the bridges refused

    def refusals(self) -> dict[str, list[Refusal]]:
        """Each drone's recent refusals of our setpoints (see ``DroneWrapper.refusals``)."""
        return {name: drone.refusals for name, drone in self.drones.items()}

    def on_refusal(self, callback: Callable[[str, Refusal], None]) -> Callable[[], None]:
        """Call ``callback(name, refusal)`` as each drone's refusals arrive (on a Zenoh
        thread: keep it short). Returns a function that stops the calls."""
        stops = [
            drone.on_refusal(functools.partial(callback, name))
            for name, drone in self.drones.items()
        ]

        def stop() -> None:
            for one in stops:
                one()

        return stop

    # ---- running a call on every drone

    def submit(
        self, call: Callable[[DroneWrapper], T], names: Iterable[str] | None = None
    ) -> dict[str, concurrent.futures.Future[tuple[T, float]]]:
        """Start ``call(drone)`` on each drone's worker (all of them, or ``names``); returns at
        once with one future per drone, whose result is ``(value, seconds the call took)``
        (:meth:`collect` makes them outcomes)."""
        chosen = self._chosen(names)
        return {name: self._workers[name].submit(timed, call, self.drones[name]) for name in chosen}

    def collect(
        self,
        futures: Mapping[str, concurrent.futures.Future[Any]],
        wait_s: float | None = None,
        what: str = "fleet call",
    ) -> FleetResult[Any]:
        """Each drone's outcome: waits for every future, or at most ``wait_s`` seconds; a call
        still running then is reported as a :class:`~dronewrapper.errors.Timeout` (it keeps
        running on its drone's worker)."""
        started = time.monotonic()
        concurrent.futures.wait(list(futures.values()), timeout=wait_s)
        result: FleetResult[Any] = FleetResult()
        result.what = what
        for name, future in futures.items():
            if not future.done():
                waited = time.monotonic() - started
                error = Timeout(f"{what}: {name} still busy after {waited:.1f} s")
                result[name] = Outcome(name, error=error, seconds=waited)
                continue
            exc = future.exception()
            if exc is not None:
                result[name] = Outcome(name, error=exc, seconds=getattr(exc, "_fleet_s", 0.0))
            else:
                value, seconds = future.result()
                result[name] = Outcome(name, value=value, seconds=seconds)
        return result

    def each(
        self,
        call: Callable[[DroneWrapper], T],
        names: Iterable[str] | None = None,
        *,
        wait_s: float | None = None,
        what: str = "fleet call",
    ) -> FleetResult[T]:
        """``call(drone)`` on every drone at once; each drone's :class:`Outcome`."""
        return self.collect(self.submit(call, names), wait_s, what)

    def _chosen(self, names: Iterable[str] | None) -> list[str]:
        chosen = list(self.drones) if names is None else list(names)
        unknown = [n for n in chosen if n not in self.drones]
        if unknown:
            raise KeyError(
                f"not in this fleet: {', '.join(unknown)} (have {', '.join(self.drones)})"
            )
        return chosen

    # ---- the commands, on every drone at once (``names=[...]``: on those; ``wait_s``: see
    # collect)

    def takeoff(self, h: float = 3.0, *, timeout: float = 30.0, **kw: Any) -> FleetResult[None]:
        """Every drone takes off to ``h`` m above its take-off point (see DroneWrapper.takeoff)."""
        return self.each(lambda d: d.takeoff(h, timeout=timeout), what="takeoff", **kw)

    def land(self, *, timeout: float = 60.0, **kw: Any) -> FleetResult[None]:
        """Every drone lands where it is and returns on the ground, disarmed."""
        return self.each(lambda d: d.land(timeout=timeout), what="land", **kw)

    def arm(self, **kw: Any) -> FleetResult[None]:
        return self.each(lambda d: d.arm(), what="arming", **kw)

    def disarm(self, **kw: Any) -> FleetResult[None]:
        return self.each(lambda d: d.disarm(), what="disarming", **kw)

    def set_mode(self, mode: str, **kw: Any) -> FleetResult[None]:
        return self.each(lambda d: d.set_mode(mode), what=f"set_mode {mode}", **kw)

    def take_command(self, *, take_over: bool = True, **kw: Any) -> FleetResult[str]:
        """Take every drone's command lease (see DroneWrapper.take_command)."""
        return self.each(lambda d: d.take_command(take_over=take_over), what="take_command", **kw)

    def stop_commanding(self) -> None:
        """Stop every drone's setpoint stream (the bridges hover)."""
        for drone in self.drones.values():
            drone.stop_commanding()

    def set_cmd_pos(
        self, targets: Mapping[str, Sequence[float]], yaw: float | None = None
    ) -> FleetResult[None]:
        """Position setpoints ``{name: (x, y, z)}`` (or ``(x, y, z, yaw)``) in each drone's local
        frame; never blocks (a refused target is that drone's error)."""
        result: FleetResult[None] = FleetResult()
        result.what = "set_cmd_pos"
        for name in self._chosen(targets):
            target = tuple(targets[name])
            args: tuple[Any, ...] = target if len(target) == 4 else (*target, yaw)
            started = time.monotonic()
            try:
                self.drones[name].set_cmd_pos(*args)
                result[name] = Outcome(name, seconds=time.monotonic() - started)
            except Exception as exc:
                result[name] = Outcome(name, error=exc, seconds=time.monotonic() - started)
        return result

    def formation(
        self,
        offsets: Mapping[str, Sequence[float]],
        *,
        center: Sequence[float] = (0.0, 0.0),
        z: float | None = None,
        yaw: float | None = None,
        origins: Mapping[str, Sequence[float]] | None = None,
    ) -> FleetResult[None]:
        """Hold a formation: drone ``name`` goes to ``center + offsets[name]`` in the shared
        frame (ENU m; an offset is ``(dx, dy)`` at altitude ``z``, or ``(dx, dy, z)``), that is
        minus its take-off point ``origins[name]`` (default: all at the shared origin) in its
        own local frame. Never blocks."""
        targets = {}
        for name, offset in offsets.items():
            if len(offset) not in (2, 3):
                raise ValueError(f"formation offset of {name}: (dx, dy) or (dx, dy, z)")
            height = offset[2] if len(offset) == 3 else z
            if height is None:
                raise ValueError(f"formation: give z, or (dx, dy, z) for {name}")
            origin = (origins or {}).get(name, (0.0, 0.0, 0.0))
            targets[name] = (
                center[0] + offset[0] - origin[0],
                center[1] + offset[1] - origin[1],
                height - (origin[2] if len(origin) > 2 else 0.0),
            )
        return self.set_cmd_pos(targets, yaw=yaw)
