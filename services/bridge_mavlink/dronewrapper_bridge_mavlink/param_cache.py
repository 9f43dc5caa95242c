"""The autopilot's parameters as the bridge heard them (PARAM_VALUE), kept so that a parameter
exchange (:mod:`~dronewrapper_bridge_mavlink.parameters`) finds the answers that came after
its request."""

from __future__ import annotations

from collections import deque
from typing import Any

HISTORY = 16  # PARAM_VALUEs kept per parameter, so overlapping exchanges each find theirs


class ParamCache:
    """The autopilot's parameters as heard (PARAM_VALUE), each with its arrival number, so an
    exchange knows which answers came after its request; the last :data:`HISTORY` values of
    each parameter are kept, as several may arrive between two resumptions of an exchange."""

    def __init__(self) -> None:
        self._values: dict[str, deque[tuple[float, int, int]]] = {}  # id -> (raw, type, no.)
        self.received = 0  # PARAM_VALUEs so far

    def on_value(self, msg: Any) -> None:
        """One PARAM_VALUE."""
        param_id = msg.param_id
        if isinstance(param_id, bytes | bytearray):
            param_id = bytes(param_id).decode("ascii", "replace")
        self.received += 1
        heard = self._values.setdefault(param_id.split("\x00", 1)[0], deque(maxlen=HISTORY))
        heard.append((float(msg.param_value), int(msg.param_type), self.received))

    def get(self, param_id: str) -> tuple[float, int, int] | None:
        """(raw float, MAV_PARAM_TYPE, arrival number) of ``param_id`` as last heard, None if
        never heard."""
        heard = self._values.get(param_id)
        return heard[-1] if heard else None

    def since(self, param_id: str, after: int) -> list[tuple[float, int, int]]:
        """The values of ``param_id`` heard after arrival number ``after``, oldest first."""
        return [entry for entry in self._values.get(param_id, ()) if entry[2] > after]
