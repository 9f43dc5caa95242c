"""What a call on many drones returns: one :class:`Outcome` per drone, in a :class:`FleetResult`
(the results half of :mod:`dronewrapper.fleet`)."""

from __future__ import annotations

import time
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any, Generic, TypeVar

from dronewrapper.drone import DroneWrapper
from dronewrapper.errors import DroneError

T = TypeVar("T")


@dataclass(frozen=True)
class Outcome(Generic[T]):
    """One drone's result of a fleet call: its ``value``, or the ``error`` it raised."""

    name: str
    value: T | None = None
    error: BaseException | None = None
    seconds: float = 0.0
    """How long the call ran (s; until the fleet stopped waiting, if it was still running)."""

    @property
    def ok(self) -> bool:
        return self.error is None

    def unwrap(self) -> T | None:
        """The value; raises the drone's error."""
        if self.error is not None:
            raise self.error
        return self.value

    def __repr__(self) -> str:
        what = f"value={self.value!r}" if self.ok else f"error={self.error!r}"
        return f"Outcome({self.name!r}, {what}, {self.seconds:.2f} s)"


class FleetError(DroneError):
    """Some drones' calls failed; ``outcomes`` holds every drone's :class:`Outcome`."""

    def __init__(self, what: str, outcomes: Mapping[str, Outcome[Any]]) -> None:
        self.outcomes = dict(outcomes)
        failed = [f"{name}: {o.error}" for name, o in outcomes.items() if not o.ok]
        super().__init__(f"{what} failed on {len(failed)} of {len(outcomes)}: " + "; ".join(failed))


class FleetResult(dict[str, Outcome[T]]):
    """Every drone's :class:`Outcome` of one fleet call, by drone name."""

    what: str = "fleet call"

    @property
    def ok(self) -> bool:
        """Every drone succeeded."""
        return all(o.ok for o in self.values())

    @property
    def failed(self) -> dict[str, BaseException]:
        """{name: error} of the drones whose call failed."""
        return {name: o.error for name, o in self.items() if o.error is not None}

    def results(self) -> dict[str, T | None]:
        """{name: value} of the drones whose call succeeded."""
        return {name: o.value for name, o in self.items() if o.ok}

    def raise_errors(self) -> FleetResult[T]:
        """Raise :class:`FleetError` if any drone failed; else return self."""
        if not self.ok:
            raise FleetError(self.what, self)
        return self


def timed(call: Callable[[DroneWrapper], T], drone: DroneWrapper) -> tuple[T, float]:
    started = time.monotonic()
    try:
        return call(drone), time.monotonic() - started
    except BaseException as exc:
        exc._fleet_s = time.monotonic() - started  # type: ignore[attr-defined]
        raise
