"""What a serial autopilot link can carry, and the stream rates that fit in it (pure).

A UART at ``baud`` (8N1) carries ``baud / 10`` bytes a second each way. A MAVLink 2 frame is
a 10-byte header, the payload (at most the message's full length: MAVLink 2 trims trailing
zero bytes, so real frames are often shorter) and a 2-byte checksum, plus a 13-byte signature
on a signed link. The streams the bridge asks for (``message_rates``) cost
``sum(rate * frame bytes)``; when that exceeds ``share`` of the line, every rate is scaled down
by the same factor, so the autopilot's heartbeat, command acks, status texts, parameter and
mission traffic keep the rest. A 57600-baud line (5760 B/s) with the default rates asks
about 5.8 kB/s of the autopilot at full payloads: more than the whole line.
"""

from __future__ import annotations

from dataclasses import dataclass

from pymavlink.dialects.v20 import common as mavlink

BITS_PER_BYTE = 10
HEADER_BYTES, CHECKSUM_BYTES, SIGNATURE_BYTES = 10, 2, 13
DEFAULT_SHARE = 0.6
"""Of the line's bytes, the share the asked streams may take (the rest: everything else)."""
MIN_RATE_HZ = 1.0
"""A scaled stream keeps at least this rate (or its asked rate when that is lower)."""


NETWORK_SCHEMES = ("udpin", "udpout", "udp", "udpbcast", "tcp", "tcpin")


def is_serial_url(url: str) -> bool:
    """True for a serial device (``/dev/ttyACM0``, ``COM3``), False for a pymavlink network
    URL (``udpin:...``, ``tcp:...``)."""
    scheme, sep, _ = url.partition(":")
    return not (sep and scheme in NETWORK_SCHEMES)


def line_capacity(baud: int) -> float:
    """Bytes a second a UART at ``baud`` carries each way (8N1)."""
    if baud <= 0:
        raise ValueError(f"baud must be > 0, got {baud!r}")
    return baud / BITS_PER_BYTE


def frame_bytes(name: str, *, signed: bool) -> int:
    """The largest frame of message ``name`` (bytes, MAVLink 2); KeyError for an unknown name."""
    msg_id = getattr(mavlink, f"MAVLINK_MSG_ID_{name}", None)
    if msg_id is None:
        raise KeyError(f"{name!r} is not a MAVLink message name")
    payload = mavlink.mavlink_map[msg_id].unpacker.size
    return HEADER_BYTES + payload + CHECKSUM_BYTES + (SIGNATURE_BYTES if signed else 0)


def stream_cost(rates: dict[str, float], *, signed: bool) -> float:
    """Bytes a second the streams at ``rates`` (name -> Hz) cost, at full payloads."""
    return sum(hz * frame_bytes(name, signed=signed) for name, hz in rates.items() if hz > 0)


@dataclass(frozen=True)
class Budget:
    """The rates to ask for on a link, and why.

    Attributes:
        rates: message name -> Hz to ask for.
        scale: the factor every asked rate was multiplied by (1.0: they fit as configured).
        cost: bytes/s the asked rates cost (full payloads).
        capacity: bytes/s the line carries each way (0: a network link, no budget).
    """

    rates: dict[str, float]
    scale: float
    cost: float
    capacity: float

    def describe(self) -> str:
        """One line for the log."""
        if self.capacity <= 0:
            return "network link: streams asked at their configured rates"
        share = self.cost / self.capacity * 100
        if self.scale >= 1.0:
            return f"streams fit: {self.cost:.0f} B/s of {self.capacity:.0f} ({share:.0f} %)"
        return (
            f"streams scaled to {self.scale * 100:.0f} % of their rates to fit the line: "
            f"{self.cost:.0f} B/s of {self.capacity:.0f} ({share:.0f} %)"
        )


def fit_rates(
    rates: dict[str, float],
    baud: int | None,
    *,
    signed: bool,
    share: float = DEFAULT_SHARE,
) -> Budget:
    """The rates to ask for on a serial line at ``baud`` (None: a network link, unchanged).

    Every rate is scaled by one factor so the streams cost at most ``share`` of the line; a
    rate that would go below :data:`MIN_RATE_HZ` (or its asked rate, if lower) stays there and
    the others share what is left, so on a line too slow for even the floors the cost stays
    above the share (``Budget.cost`` says so)."""
    if not 0 < share <= 1:
        raise ValueError(f"share must be in (0, 1], got {share!r}")
    asked = {name: hz for name, hz in rates.items() if hz > 0}
    cost = stream_cost(asked, signed=signed)
    if baud is None:
        return Budget(dict(asked), 1.0, cost, 0.0)
    capacity = line_capacity(baud)
    budget = share * capacity
    if cost <= budget:
        return Budget(dict(asked), 1.0, cost, capacity)
    floors = {name: min(hz, MIN_RATE_HZ) for name, hz in asked.items()}
    floored: set[str] = set()
    while True:  # the rates at their floor are fixed; the others share what is left
        free = {name: hz for name, hz in asked.items() if name not in floored}
        left = budget - stream_cost({n: floors[n] for n in floored}, signed=signed)
        scale = max(0.0, left) / stream_cost(free, signed=signed) if free else 0.0
        newly = {name for name, hz in free.items() if hz * scale < floors[name]}
        if not newly:
            break
        floored |= newly
    fitted = {n: floors[n] if n in floored else hz * scale for n, hz in asked.items()}
    if not free:  # every rate at its floor: the factor is the largest cut
        scale = min(fitted[n] / asked[n] for n in asked)
    return Budget(fitted, scale, stream_cost(fitted, signed=signed), capacity)
