"""Which telemetry streams the bridge asks of the autopilot (pure; time injected, monotonic s).

Every message the autopilot sends costs the bridge a datagram, a wake-up and a parse in Python,
so the bridge asks for what it publishes and asks the autopilot to stop what it never reads,
with ``MAV_CMD_SET_MESSAGE_INTERVAL`` (param2: interval in µs; -1 stops a stream, 0 restores
its default rate; PX4 and ArduPilot both read it so):

- ``message_rates`` (message name -> Hz): asked at those rates;
- ``unused_streams``: stopped. PX4's onboard link sends ALTITUDE, VFR_HUD and
  POSITION_TARGET_LOCAL_NED at 10 Hz each, which the bridge never reads;
- ATTITUDE (100 Hz on PX4's onboard link) carries the attitude ATTITUDE_QUATERNION carries too.
  It is stopped only while ATTITUDE_QUATERNION arrives (an autopilot may send ATTITUDE only),
  and asked back at its default rate when ATTITUDE_QUATERNION has been silent for
  :data:`QUATERNION_SILENCE_S`.

Nothing is stopped while the bridge forwards the link to a ground station (``forwarding``): the
ground station sees the link as the autopilot streams it.
"""

from __future__ import annotations

import math

from pymavlink.dialects.v20 import common as mavlink

QUATERNION_SILENCE_S = 1.0
"""s without ATTITUDE_QUATERNION after which a stopped ATTITUDE is asked back."""

STOP_US = -1.0
"""SET_MESSAGE_INTERVAL's interval that stops a stream."""
DEFAULT_US = 0.0
"""SET_MESSAGE_INTERVAL's interval that restores a stream's default rate."""

ATTITUDE = mavlink.MAVLINK_MSG_ID_ATTITUDE


def message_id(name: str) -> int | None:
    """The MAVLink id of message ``name`` (``LOCAL_POSITION_NED``), None if there is none."""
    return getattr(mavlink, f"MAVLINK_MSG_ID_{name}", None)


class StreamRequests:
    """The SET_MESSAGE_INTERVAL requests to send, as (message id, interval µs).

    Args:
        rates: message name -> Hz to ask for (names without an id, or rates <= 0, are skipped).
        unused: names of the streams to stop.
        forwarding: the link is forwarded to a ground station: nothing is stopped.
    """

    def __init__(self, rates: dict[str, float], unused: list[str], *, forwarding: bool) -> None:
        self._asked = [
            (msg_id, 1e6 / hz)
            for name, hz in rates.items()
            if (msg_id := message_id(name)) is not None and hz > 0
        ]
        stopped = [] if forwarding else [message_id(name) for name in unused]
        self._stopped = [(msg_id, STOP_US) for msg_id in stopped if msg_id is not None]
        self._forwarding = forwarding
        self._quaternion_at = -math.inf
        self.attitude_stopped = False  # ATTITUDE was asked to stop and not asked back since

    def on_quaternion(self, now: float) -> None:
        """An ATTITUDE_QUATERNION arrived."""
        self._quaternion_at = now

    def quaternion_flows(self, now: float) -> bool:
        """True while ATTITUDE_QUATERNION arrives (one within :data:`QUATERNION_SILENCE_S`)."""
        return now - self._quaternion_at <= QUATERNION_SILENCE_S

    def round(self, now: float) -> list[tuple[int, float]]:
        """One round of requests (the bridge sends a few rounds after it connects): the rates,
        the stops, and ATTITUDE's stop while ATTITUDE_QUATERNION arrives."""
        requests = self._asked + self._stopped
        if not self._forwarding and self.quaternion_flows(now):
            requests = [*requests, (ATTITUDE, STOP_US)]
            self.attitude_stopped = True
        return requests

    def due(self, now: float) -> list[tuple[int, float]]:
        """Requests due now between rounds: ATTITUDE asked back at its default rate when it was
        stopped and ATTITUDE_QUATERNION has gone silent."""
        if self.attitude_stopped and not self.quaternion_flows(now):
            self.attitude_stopped = False
            return [(ATTITUDE, DEFAULT_US)]
        return []
