"""Which telemetry PX4 streams on which link, at which rate, and the scheduler that paces it.

Rates are those measured on PX4 SITL (messages per second). The onboard/API link is the one a
companion computer uses; the SITL start script raises some streams on the GCS link.
``SET_MESSAGE_INTERVAL`` changes a stream (refused for HEARTBEAT, which stays at 1 Hz);
``GET_MESSAGE_INTERVAL`` reads one.
"""

from __future__ import annotations

import math

from pymavlink.dialects.v20 import common as mavlink

HEARTBEAT = mavlink.MAVLINK_MSG_ID_HEARTBEAT
SYS_STATUS = mavlink.MAVLINK_MSG_ID_SYS_STATUS
GPS_RAW_INT = mavlink.MAVLINK_MSG_ID_GPS_RAW_INT
ATTITUDE = mavlink.MAVLINK_MSG_ID_ATTITUDE
ATTITUDE_QUATERNION = mavlink.MAVLINK_MSG_ID_ATTITUDE_QUATERNION
LOCAL_POSITION_NED = mavlink.MAVLINK_MSG_ID_LOCAL_POSITION_NED
GLOBAL_POSITION_INT = mavlink.MAVLINK_MSG_ID_GLOBAL_POSITION_INT
POSITION_TARGET_LOCAL_NED = mavlink.MAVLINK_MSG_ID_POSITION_TARGET_LOCAL_NED
VFR_HUD = mavlink.MAVLINK_MSG_ID_VFR_HUD
ALTITUDE = mavlink.MAVLINK_MSG_ID_ALTITUDE
BATTERY_STATUS = mavlink.MAVLINK_MSG_ID_BATTERY_STATUS
HOME_POSITION = mavlink.MAVLINK_MSG_ID_HOME_POSITION
EXTENDED_SYS_STATE = mavlink.MAVLINK_MSG_ID_EXTENDED_SYS_STATE
AUTOPILOT_VERSION = mavlink.MAVLINK_MSG_ID_AUTOPILOT_VERSION

ONBOARD_RATES: dict[int, float] = {
    HEARTBEAT: 1.0,
    ATTITUDE: 100.0,
    ATTITUDE_QUATERNION: 50.0,
    GLOBAL_POSITION_INT: 50.0,
    LOCAL_POSITION_NED: 30.0,
    ALTITUDE: 10.0,
    POSITION_TARGET_LOCAL_NED: 10.0,
    VFR_HUD: 10.0,
    GPS_RAW_INT: 8.0,
    SYS_STATUS: 5.0,
    EXTENDED_SYS_STATE: 5.0,
    HOME_POSITION: 0.5,
    BATTERY_STATUS: 0.5,
}

GCS_RATES: dict[int, float] = {
    HEARTBEAT: 1.0,
    ATTITUDE: 50.0,
    ATTITUDE_QUATERNION: 50.0,
    GLOBAL_POSITION_INT: 50.0,
    LOCAL_POSITION_NED: 50.0,
    POSITION_TARGET_LOCAL_NED: 50.0,
    ALTITUDE: 10.0,
    GPS_RAW_INT: 5.0,
    VFR_HUD: 4.0,
    SYS_STATUS: 1.0,
    EXTENDED_SYS_STATE: 1.0,
    HOME_POSITION: 0.5,
    BATTERY_STATUS: 0.5,
}

# messages the vehicle can produce (SET_MESSAGE_INTERVAL / REQUEST_MESSAGE accept these)
AVAILABLE: frozenset[int] = frozenset(ONBOARD_RATES) | {AUTOPILOT_VERSION}

MAX_RATE_HZ = 250.0


class StreamScheduler:
    """Per-link stream rates and the next time each stream is due (seconds, monotonic)."""

    def __init__(self, rates: dict[int, float], now: float = 0.0) -> None:
        self.defaults = dict(rates)
        self.rates = dict(rates)
        # stagger the first sends so streams do not all fire in the same tick
        self._next = {msgid: now + (i % 10) * 0.001 for i, msgid in enumerate(self.rates)}

    def set_interval(self, msgid: int, interval_us: float, now: float) -> bool:
        """SET_MESSAGE_INTERVAL: -1 stops the stream, 0 restores the default, > 0 sets it.

        Returns False (refused) for HEARTBEAT and for messages this vehicle cannot send.
        """
        if msgid == HEARTBEAT or msgid not in AVAILABLE or not math.isfinite(interval_us):
            return False
        if interval_us < 0:
            self.rates.pop(msgid, None)
            self._next.pop(msgid, None)
            return True
        if interval_us == 0:
            rate = self.defaults.get(msgid)
            if rate is None:
                self.rates.pop(msgid, None)
                self._next.pop(msgid, None)
                return True
        else:
            rate = min(1e6 / interval_us, MAX_RATE_HZ)
        self.rates[msgid] = rate
        self._next[msgid] = now
        return True

    def interval_us(self, msgid: int) -> int:
        """MESSAGE_INTERVAL value: the interval (us), -1 if stopped, 0 if not available."""
        if msgid not in AVAILABLE:
            return 0
        rate = self.rates.get(msgid)
        return round(1e6 / rate) if rate else -1

    def due(self, now: float, ahead_s: float = 0.0) -> list[int]:
        """Streams to send now: those due by ``now + ahead_s`` (a loop that wakes every
        2 x ``ahead_s`` sends what falls due before its next wake-up's midpoint, so a stream
        as fast as the loop keeps its rate); each is then scheduled one period later. A
        stream that fell behind by more than a period restarts its schedule from now, due
        ``ahead_s`` before a period has passed (mid-way between two such wake-ups)."""
        out = []
        until = now + ahead_s
        for msgid, when in self._next.items():
            if until >= when:
                out.append(msgid)
                period = 1.0 / self.rates[msgid]
                when += period
                if when < now:  # fell behind by more than one period: restart the schedule
                    when = now + max(period - ahead_s, 0.0)
                self._next[msgid] = when
        return out
