"""A LiPo battery: charge drawn by the motors, and the pack voltage under load.

Pure: ``step(current_a, dt)`` is the only way time passes. The open-circuit cell voltage
follows a typical LiPo discharge curve; the pack voltage sags with the internal resistance.
"""

from __future__ import annotations

import itertools

from dronewrapper_sim.dynamics import GRAVITY

# (remaining fraction, open-circuit cell voltage V): a typical LiPo curve
_CELL_CURVE = (
    (0.0, 3.30),
    (0.05, 3.50),
    (0.10, 3.60),
    (0.20, 3.70),
    (0.50, 3.80),
    (0.80, 3.95),
    (0.95, 4.10),
    (1.00, 4.20),
)

IDLE_CURRENT_A = 0.4  # electronics, motors off
ARMED_IDLE_CURRENT_A = 2.0  # motors spinning at idle
HOVER_CURRENT_A = 16.0  # at hover thrust (1 g)


def motor_current(armed: bool, thrust_accel: float) -> float:
    """Current drawn (A) for a collective thrust (m/s^2): rotor power grows as thrust^1.5."""
    if not armed:
        return IDLE_CURRENT_A
    load = max(0.0, thrust_accel / GRAVITY)
    return IDLE_CURRENT_A + ARMED_IDLE_CURRENT_A + HOVER_CURRENT_A * load**1.5


class Battery:
    """Charge state of a ``cells``-S pack of ``capacity_mah`` (mAh)."""

    def __init__(
        self, cells: int = 4, capacity_mah: float = 5000.0, resistance_ohm: float = 0.015
    ) -> None:
        if cells < 1 or capacity_mah <= 0:
            raise ValueError("battery needs >= 1 cell and a positive capacity")
        self.cells = cells
        self.capacity_mah = capacity_mah
        self.resistance_ohm = resistance_ohm
        self.consumed_mah = 0.0
        self.current_a = 0.0

    def step(self, current_a: float, dt: float) -> None:
        """Draw ``current_a`` amperes for ``dt`` seconds."""
        self.current_a = current_a
        self.consumed_mah = min(self.capacity_mah, self.consumed_mah + current_a * dt / 3.6)

    @property
    def remaining(self) -> float:
        """Remaining charge, fraction 0..1."""
        return max(0.0, 1.0 - self.consumed_mah / self.capacity_mah)

    def cell_voltage(self) -> float:
        """Loaded voltage of one cell (V)."""
        frac = self.remaining
        for (f0, v0), (f1, v1) in itertools.pairwise(_CELL_CURVE):
            if frac <= f1:
                ocv = v0 + (v1 - v0) * (frac - f0) / (f1 - f0)
                break
        else:
            ocv = _CELL_CURVE[-1][1]
        return ocv - self.current_a * self.resistance_ohm / self.cells

    @property
    def voltage(self) -> float:
        """Loaded pack voltage (V)."""
        return self.cell_voltage() * self.cells
