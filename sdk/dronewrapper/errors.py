"""The exceptions the DroneWrapper SDK raises. Catch :class:`DroneError` to catch them all.

DroneError
├── NotConnected      (also a ConnectionError) no router, no bridge, or no autopilot link
├── CommandRefused    the bridge or the autopilot said no; ``result`` and ``reason`` say why
├── Timeout           (also a TimeoutError) the outcome did not come in time
├── NoData            a getter was called before the first message of its kind arrived
└── InvalidArgument   (also ValueError and TypeError) NaN, inf, a bool or a non-number
"""

from __future__ import annotations


class DroneError(Exception):
    """Base class of every error the SDK raises on purpose."""


class NotConnected(DroneError, ConnectionError):
    """The SDK cannot talk to the drone: no router, no bridge, or the autopilot is not linked."""


class CommandRefused(DroneError):
    """A command was refused by the bridge or the autopilot.

    Attributes:
        command: what was asked (``arming``, ``set_mode OFFBOARD``, ``takeoff`` ...).
        result: the MAV_RESULT code of the reply (``-1``: no acknowledgement; ``None``: the
            bridge rejected the request itself, e.g. a malformed or unsupported request).
        reason: the autopilot's or the bridge's reason, for a person to read.
        limit: the envelope's field the command is beyond (``max_altitude``, ``fence`` ...),
            ``""`` when no envelope limit is the cause.
    """

    def __init__(
        self, command: str, reason: str, result: int | None = None, *, limit: str = ""
    ) -> None:
        code = "" if result is None else f" (result {result})"
        super().__init__(f"{command} refused{code}: {reason or 'no reason given'}")
        self.command = command
        self.reason = reason
        self.result = result
        self.limit = limit


class Timeout(DroneError, TimeoutError):
    """A blocking call gave up: the message names what was awaited and what was seen."""


class NoData(DroneError):
    """Nothing has arrived yet on the key a getter reads (the message names the key)."""


class InvalidArgument(DroneError, ValueError, TypeError):
    """A command argument is not a finite real number (NaN, inf, bool, str, None ...)."""


class Cancelled(DroneError):
    """A blocking take-off or landing was cancelled (its ``cancel`` event set, or its asyncio
    task cancelled): it took no further step and the wrapper stopped commanding."""
