"""A PID controller with real time steps, anti-windup, a filtered derivative and output limits.

The original apps computed ``D = kd * (e - e_prev)`` once per loop iteration (no time step) and
never saturated anything. Here every update gets the time ``t`` (seconds, any monotonic time
base: the source frame's stamp in the controller) and the step is ``dt = t - t_prev``:

    u = kp * e + ki * integral(e dt) + kd * d/dt(lowpass(e))

- Anti-windup: the integral is clamped to ``+-i_limit`` (in units of error x seconds) and is not
  grown while the output is saturated in the direction the error pushes (conditional integration).
- Derivative: on the error passed through a first-order low-pass filter of time constant
  ``d_tau`` seconds (0 = no filter); the first update after a reset has no D term (no kick).
- Output: clamped to ``[-out_limit, +out_limit]``.
- A step ``dt`` that is not positive (same frame twice) changes nothing and returns the last
  output; a step longer than ``max_dt`` (a gap in the input) restarts the I and D state.
"""

from __future__ import annotations

import math

import msgspec

from dronewrapper.runtime.config_ranges import NonNegative, Positive, check_ranges


class PidGains(msgspec.Struct, kw_only=True, forbid_unknown_fields=True):
    """Gains and limits of one PID (units: command unit per error unit, per second for ki...).

    Attributes:
        kp: proportional gain (command / error).
        ki: integral gain (command / (error * s)).
        kd: derivative gain (command / (error / s)).
        out_limit: output saturation, symmetric (command units, e.g. m/s or rad/s).
        i_limit: clamp of the integral state (error * s); inf = no clamp beyond conditional
            integration.
        d_tau: time constant of the derivative's low-pass filter (s); 0 = unfiltered.
        max_dt: a step longer than this (s) restarts the I and D state.
    """

    kp: float = 0.0
    ki: float = 0.0
    kd: float = 0.0
    out_limit: Positive = 1.0
    i_limit: NonNegative = math.inf
    d_tau: NonNegative = 0.1
    max_dt: Positive = 1.0

    def __post_init__(self) -> None:
        check_ranges(self, "PID ")  # a range refuses NaN too
        for name in ("kp", "ki", "kd"):  # any gain but NaN: no range a Meta can say
            if math.isnan(getattr(self, name)):
                raise ValueError(f"PID {name} is NaN")


def clamp(value: float, limit: float) -> float:
    """``value`` limited to ``[-limit, +limit]``."""
    return max(-limit, min(limit, value))


class Pid:
    """One PID loop; call :meth:`update` with the error and its time, :meth:`reset` on a gap."""

    def __init__(self, gains: PidGains) -> None:
        self.gains = gains
        self.reset()

    def reset(self) -> None:
        """Forget the past: no integral, no derivative history, output 0."""
        self.integral = 0.0
        self.output = 0.0
        self.p = self.i = self.d = 0.0
        self._t_prev: float | None = None
        self._e_filtered: float | None = None
        self._d_filtered = 0.0

    def update(self, error: float, t: float) -> float:
        """The command for ``error`` measured at time ``t`` (s), saturated to ``out_limit``.

        Raises:
            ValueError: ``error`` or ``t`` is NaN or infinite.
        """
        if not (math.isfinite(error) and math.isfinite(t)):
            raise ValueError(f"PID input must be finite, got error={error} t={t}")
        g = self.gains
        dt = None if self._t_prev is None else t - self._t_prev
        if dt is not None and dt <= 0:
            return self.output
        if dt is not None and dt > g.max_dt:
            self.reset()
            dt = None
        self._t_prev = t

        self.p = g.kp * error
        self.d = 0.0
        if dt is None:
            self._e_filtered = error
            self._d_filtered = 0.0
        else:
            assert self._e_filtered is not None
            alpha = 1.0 if g.d_tau <= 0 else dt / (g.d_tau + dt)
            e_filtered = self._e_filtered + alpha * (error - self._e_filtered)
            d_raw = (e_filtered - self._e_filtered) / dt
            self._e_filtered = e_filtered
            self._d_filtered = d_raw
            self.d = g.kd * d_raw
            if g.ki != 0.0:
                candidate = clamp(self.integral + error * dt, g.i_limit)
                unsat = self.p + g.ki * candidate + self.d
                pushes_out = (unsat > g.out_limit and error * g.ki > 0) or (
                    unsat < -g.out_limit and error * g.ki < 0
                )
                if not pushes_out:
                    self.integral = candidate
        self.i = g.ki * self.integral
        self.output = clamp(self.p + self.i + self.d, g.out_limit)
        return self.output
