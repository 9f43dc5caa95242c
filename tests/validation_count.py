"""The setpoint validations a bridge makes, counted (the rule: one, where a setpoint enters the
core): :func:`count_validations` wraps the shared check where the cores and the converters
would call it."""

from __future__ import annotations

from typing import Any

import pytest

from dronewrapper_bridge_base import guided_core, setpoint_limits


def count_validations(monkeypatch: pytest.MonkeyPatch) -> list[Any]:
    """The targets validated from now on (each call of ``setpoint_limits.validate``, whether
    by name in ``guided_core`` or through the module), in order."""
    calls: list[Any] = []
    real = setpoint_limits.validate

    def counting(target: Any, bounds: Any) -> Any:
        calls.append(target)
        return real(target, bounds)

    monkeypatch.setattr(guided_core, "validate", counting)
    monkeypatch.setattr(setpoint_limits, "validate", counting)
    return calls
