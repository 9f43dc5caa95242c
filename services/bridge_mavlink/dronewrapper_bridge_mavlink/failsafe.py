"""The failsafe contract for a MAVLink autopilot: the guided-mode failsafe every bridge to a
PX4 or ArduPilot shares (:mod:`dronewrapper_bridge_base.guided_failsafe`), under its old name."""

from dronewrapper_bridge_base.guided_failsafe import (
    ACTIONS,
    HOLD,
    LAND,
    NONE,
    RETURN,
    Failsafe,
    FailsafeConfig,
    Tick,
    Transition,
    is_airborne,
)

__all__ = [
    "ACTIONS",
    "HOLD",
    "LAND",
    "NONE",
    "RETURN",
    "Failsafe",
    "FailsafeConfig",
    "Tick",
    "Transition",
    "is_airborne",
]
