"""Which drones are online: their bridges by liveliness, their kind and health (pure where it
can be), and opening many at once; the discovery half of :mod:`dronewrapper.fleet`."""

from __future__ import annotations

import concurrent.futures
import time
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass

from dronewrapper.discovery import BRIDGE_PREFIX
from dronewrapper.drone import DroneWrapper
from dronewrapper.errors import NoData, NotConnected
from dronewrapper.health import stale_after
from dronewrapper.msgs import registry
from dronewrapper.msgs.registry import ALIVE

KIND_OF_BRIDGE = {"bridge_mavlink": "mavlink", "bridge_tello": "tello"}
"""What a bridge's process name says of its aircraft before the first State arrives."""


def bridges_online(alive_keys: Iterable[str]) -> dict[str, str]:
    """{namespace: bridge process name} of the liveliness keys that are bridges, sorted."""
    found: dict[str, str] = {}
    for key in alive_keys:
        parts = ALIVE.match(key)
        if parts is not None and parts["service"].startswith(BRIDGE_PREFIX):
            found.setdefault(parts["ns"], parts["service"])
    return dict(sorted(found.items(), key=lambda item: _natural(item[0])))


def _natural(name: str) -> tuple[str, int]:
    """``drone2`` before ``drone10``."""
    stem = name.rstrip("0123456789")
    digits = name[len(stem) :]
    return stem, int(digits) if digits else -1


@dataclass(frozen=True)
class DroneInfo:
    """A drone online: what it is and how it is.

    Attributes:
        name: its namespace (``drone1`` ...).
        bridge: the bridge process serving it (``bridge_mavlink``, ``bridge_tello``).
        kind: the autopilot (``px4``, ``ardupilotmega``, ``tello``) once its State arrived, else
            what the bridge says (``mavlink``, ``tello``).
        connected: the bridge's autopilot is connected (a fresh State says so).
        armed, mode: from the newest State (False, "" before one arrived).
        battery: charge 0..1, None before the first battery message.
        state_age: seconds since the newest State (inf before one).
        healthy: connected, with fresh telemetry, and no failsafe active.
    """

    name: str
    bridge: str
    kind: str
    connected: bool = False
    armed: bool = False
    mode: str = ""
    battery: float | None = None
    state_age: float = float("inf")
    failsafe: str = ""
    healthy: bool = False


def describe(name: str, bridge: str, drone: DroneWrapper | None) -> DroneInfo:
    """A drone's :class:`DroneInfo` from its wrapper's newest values (None: not opened)."""
    kind = KIND_OF_BRIDGE.get(bridge, bridge.removeprefix(BRIDGE_PREFIX).strip("_") or "?")
    if drone is None:
        return DroneInfo(name, bridge, kind)
    try:
        state = drone.get_state()
    except NoData:
        return DroneInfo(name, bridge, kind)
    try:
        battery: float | None = drone.get_battery()
    except NoData:
        battery = None
    connected = drone.is_connected()
    fresh_pose = drone.age("position") <= stale_after(registry.LOCAL_POSE.rate_hz)
    return DroneInfo(
        name,
        bridge,
        state.autopilot or kind,
        connected=connected,
        armed=state.armed,
        mode=state.mode,
        battery=battery,
        state_age=drone.age("state"),
        failsafe=state.failsafe,
        healthy=connected and fresh_pose and not state.failsafe,
    )


def wait_for_bridges(
    alive: Callable[[], set[str]],
    names: Sequence[str] | None,
    count: int | None,
    deadline: float,
    interval: float = 0.2,
) -> dict[str, str]:
    """{name: bridge} of the drones to open, once enough are online (``names``: each of them;
    else at least ``count``, or at least one).

    Raises:
        NotConnected: not enough online by ``deadline`` (monotonic s); names the missing ones.
    """
    wanted = max(1, count or 1)
    while True:
        online = bridges_online(alive())
        if names is not None:
            missing = [n for n in names if n not in online]
            if not missing:
                return {n: online[n] for n in names}
        elif len(online) >= wanted:
            return online
        if time.monotonic() >= deadline:
            seen = ", ".join(online) or "none"
            if names is not None:
                raise NotConnected(f"no bridge online for {', '.join(missing)} (online: {seen})")
            raise NotConnected(f"{len(online)} drone(s) online, {wanted} wanted (online: {seen})")
        time.sleep(interval)


def open_drones(
    names: Sequence[str], open_one: Callable[[str], DroneWrapper]
) -> dict[str, DroneWrapper]:
    """``open_one(name)`` for every name at once (each waits for its own bridge).

    Raises:
        NotConnected: some did not connect (the others are closed again); names each.
    """
    with concurrent.futures.ThreadPoolExecutor(max(1, len(names))) as pool:
        futures = {name: pool.submit(open_one, name) for name in names}
        concurrent.futures.wait(list(futures.values()))
    opened = {n: f.result() for n, f in futures.items() if f.exception() is None}
    failed = {n: f.exception() for n, f in futures.items() if f.exception() is not None}
    if failed:
        for drone in opened.values():
            drone.close()
        raise NotConnected("; ".join(f"{n}: {e}" for n, e in failed.items()))
    return {name: opened[name] for name in names}
