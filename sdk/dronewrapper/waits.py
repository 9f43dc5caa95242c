"""A DroneWrapper's waits: block until a condition on the inputs holds, on the node's clock.

Each wait polls its condition every ``interval`` s of the drone client's clock (the node's:
injected time in tests) and raises :class:`~dronewrapper.errors.Timeout` naming what it waited
for and what it saw; ``NoData`` from a getter counts as "not yet".
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TypeVar

import numpy as np

from dronewrapper import setpoints
from dronewrapper.client.inputs import Inputs
from dronewrapper.errors import NoData, Timeout
from dronewrapper.getters import Getters
from dronewrapper.runtime.clock import Clock

T = TypeVar("T")


def _satisfied(value: object) -> bool:
    """Truthiness for wait_for: any numpy array counts as a result (not "ambiguous")."""
    if isinstance(value, np.ndarray):
        return True
    return bool(value)


class Waits:
    """The blocking waits of one drone (see the module doc); a part a DroneWrapper owns.

    Args:
        clock: the node's clock; ``getters``: the drone's getters (and their inputs).
    """

    def __init__(self, clock: Clock, getters: Getters) -> None:
        self.clock = clock
        self.getters = getters
        self.inputs: Inputs = getters.inputs

    def wait_for(
        self,
        predicate: Callable[[], T | None],
        timeout: float,
        what: str = "condition",
        *,
        interval: float = 0.02,
    ) -> T:
        """Poll ``predicate()`` until it returns a truthy value, which is returned.

        A numpy array counts as truthy (``wait_for(drone.get_global_position, 5)`` returns the
        first fix); ``NoData`` raised by the predicate counts as "not yet".

        Raises:
            Timeout: still false after ``timeout`` seconds (the message names ``what``).
        """
        deadline = self.clock.monotonic() + timeout
        while True:
            try:
                value = predicate()
            except NoData:
                value = None
            if value is not None and _satisfied(value):
                return value
            if self.clock.monotonic() >= deadline:
                raise Timeout(f"timed out after {timeout:g} s waiting for {what}")
            self.clock.sleep(interval)

    def wait_for_altitude(
        self, z: float, timeout: float = 30.0, *, tolerance: float = 0.1
    ) -> np.ndarray:
        """Block until the local ENU altitude is within ``tolerance`` m of ``z``; the position.

        Raises:
            Timeout: not there within ``timeout`` seconds (the message gives the altitude).
        """
        z = setpoints.finite("z", z)
        try:
            return self.wait_for(
                lambda: p if abs((p := self.getters.get_position())[2] - z) <= tolerance else None,
                timeout,
                f"altitude {z:.2f} m",
            )
        except Timeout as exc:
            raise Timeout(f"{exc} (now {self._altitude_text()})") from None

    def wait_for_landed_state(self, landed_state: int, timeout: float = 30.0) -> int:
        """Block until :meth:`get_landed_state` equals ``landed_state``; returns it."""
        self.wait_for(
            lambda: self.getters.get_landed_state() == landed_state,
            timeout,
            f"landed state {landed_state}",
        )
        return landed_state

    def wait_for_image(self, camera: str = "frontal", timeout: float = 10.0) -> np.ndarray:
        """Block until ``camera`` delivered a frame; returns the newest one (BGR).

        Raises:
            Timeout: no frame within ``timeout`` s (no camera publishing on the key).
        """
        holder = self.inputs.camera(camera)
        if holder is None:
            return self.getters.get_image(camera)  # raises NoData naming the cameras= argument
        try:
            holder.wait(timeout)
        except TimeoutError:
            raise Timeout(
                f"no image on {holder.name} within {timeout:g} s: is a camera running "
                f"in namespace {self.inputs.ns!r}?"
            ) from None
        return self.getters.get_image(camera)

    def _altitude_text(self) -> str:
        pose = self.inputs.pose.value
        return "no position" if pose is None else f"z={pose.pose.position.z:.2f} m"
