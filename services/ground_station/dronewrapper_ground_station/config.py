"""The ground station's config schema (strict: unknown keys are errors naming the key).

Units: seconds, metres, metres per second, radians per second.
"""

from __future__ import annotations

from typing import Annotated

import msgspec

from dronewrapper.runtime.config_ranges import FinitePositive, check_ranges


class TeleopLimits(msgspec.Struct, kw_only=True, forbid_unknown_fields=True):
    """Saturation of velocity teleop (a full stick deflection asks for these).

    Attributes:
        horizontal: forward and lateral speed, body FLU (m/s).
        vertical: climb and descent speed (m/s).
        yaw_rate: turn rate, CCW positive (rad/s).
        timeout: a velocity command not renewed for this long is replaced by a position hold
            where the drone is (s): a released stick, a hidden tab or a lost browser stop it.
    """

    horizontal: FinitePositive = 2.0
    vertical: FinitePositive = 1.0
    yaw_rate: FinitePositive = 1.0
    timeout: FinitePositive = 0.5

    def __post_init__(self) -> None:
        check_ranges(self, "teleop.")


class Config(msgspec.Struct, kw_only=True, forbid_unknown_fields=True):
    """``dronewrapper station``.

    Attributes:
        host: address the web server listens on. Loopback by default; any other address needs
            the one-time operator token printed at start (observers get a read-only page).
        port: TCP port of the web server (0: any free port, printed at start).
        namespaces: the drones to show; empty: every drone whose bridge is alive.
        discover_period: how often the drones online are listed again (s).
        telemetry_rate_hz: how often each page gets a telemetry snapshot (Hz).
        stale_after: a value older than this many nominal periods of its topic (at least 1 s)
            is shown dimmed as stale.
        takeoff_max: the highest take-off height a page may ask for (m).
        goto_max_distance: the farthest a map click may send a drone from the origin (m).
        object_speed: speed of a simulated object moved by keyboard (m/s).
        token: the operator token; empty: a fresh random one at each start when ``host`` is
            not loopback.
        command_timeout: seconds a command (take-off, land ...) may take before the page is
            told it timed out (s).
    """

    host: Annotated[str, msgspec.Meta(min_length=1)] = "127.0.0.1"
    port: Annotated[int, msgspec.Meta(ge=0, le=65535)] = 8080
    namespaces: list[str] = msgspec.field(default_factory=list)
    discover_period: FinitePositive = 1.0
    telemetry_rate_hz: FinitePositive = 10.0
    stale_after: FinitePositive = 3.0
    takeoff_max: FinitePositive = 30.0
    goto_max_distance: FinitePositive = 200.0
    object_speed: FinitePositive = 1.0
    token: str = ""
    command_timeout: FinitePositive = 60.0
    teleop: TeleopLimits = msgspec.field(default_factory=TeleopLimits)

    def __post_init__(self) -> None:
        check_ranges(self)
        for ns in self.namespaces:
            if not ns or "/" in ns or "*" in ns:
                raise ValueError(f"namespaces: {ns!r} is not one key chunk")
        if self.token and len(self.token) < 16:
            raise ValueError("token must be at least 16 characters (or empty for a random one)")
