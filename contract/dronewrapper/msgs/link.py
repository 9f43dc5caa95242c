"""The state of a bridge's link to its autopilot: how full it is, what it lost."""

from __future__ import annotations

import msgspec

from dronewrapper.msgs.std import Header


class LinkStatus(msgspec.Struct, kw_only=True, frozen=True):
    """The autopilot link as the bridge sees it (about once a second).

    Attributes:
        header: when it was measured.
        kind: ``serial``, ``udp`` or ``tcp``.
        baud: the serial line's rate, bits/s (0 for a network link).
        capacity: bytes/s the line carries each way (``baud / 10``; 0: no known limit).
        received_rate: bytes/s from the autopilot, over the last 2 s.
        sent_rate: bytes/s to the autopilot, over the last 2 s.
        load: the busier direction's share of the line (1.0 = full; 0 for a network link).
        lost: MAVLink frames lost since the bridge started (sequence gaps, unparsable bytes).
        reconnects: times the link came back (reopened after an error, or heartbeats again
            after they stopped).
        rejected: frames dropped for a missing or wrong MAVLink 2 signature.
        stream_scale: the factor the asked stream rates were scaled by to fit the line
            (1.0: as configured).
    """

    header: Header = msgspec.field(default_factory=Header)
    kind: str = ""
    baud: int = 0
    capacity: float = 0.0
    received_rate: float = 0.0
    sent_rate: float = 0.0
    load: float = 0.0
    lost: int = 0
    reconnects: int = 0
    rejected: int = 0
    stream_scale: float = 1.0

    def describe(self) -> str:
        """``link 94 % full (serial 57600 baud: 5.4 / 1.8 kB/s down/up), 0 lost, 0 reconnects``."""
        rates = f"{self.received_rate / 1000:.1f} / {self.sent_rate / 1000:.1f} kB/s down/up"
        if self.kind == "serial":
            head = f"link {self.load * 100:.0f} % full (serial {self.baud} baud: {rates})"
        else:
            head = f"link ({self.kind or 'unknown'}: {rates})"
        scaled = (
            f", streams at {self.stream_scale * 100:.0f} % of their rates"
            if self.stream_scale < 1.0
            else ""
        )
        return f"{head}, {self.lost} lost, {self.reconnects} reconnects{scaled}"
