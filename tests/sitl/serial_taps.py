"""The paced serial line of the opt-in serial flights, counted and timed.

:func:`paced_relay` is a :class:`~dronewrapper_sim.serial_relay.SerialRelay` with a second
pseudo-terminal for the firmware (``pty``), the autopilot's transmit buffer a Pixhawk TELEM
port's (:data:`TX_BUFFER_BYTES`), and both directions watched: toward the bridge
(:class:`CountingLine`) the frames the autopilot offers, by message name; toward the autopilot
(:class:`SetpointLine`) each SET_POSITION_TARGET_LOCAL_NED frame as its last byte crosses the
line, on the wall clock (``time.time()``, the clock camera frames are stamped with), for
glass-to-setpoint at the autopilot. Used by serial_sitl_flight.py and test_serial_follow_sitl.py.
"""

from __future__ import annotations

import collections
import time

from pymavlink.dialects.v20 import ardupilotmega as dialect

from dronewrapper_sim.serial_line import FrameCutter, SerialLine
from dronewrapper_sim.serial_relay import UPLINK_BUFFER_BYTES, SerialRelay

TX_BUFFER_BYTES = 3000
"""The autopilot's transmit buffer toward the bridge: a Pixhawk's TELEM port (NuttX
``CONFIG_USARTn_TXBUFSIZE`` on fmu-v5/v6x). PX4 SITL writes its bursts to the pseudo-terminal
unchecked (no free-space query on Linux), as it would into that buffer."""
SETPOINT_MSG_ID = 84  # SET_POSITION_TARGET_LOCAL_NED


def message_id(frame: bytes) -> int:
    """The message id of a whole MAVLink 1 or 2 frame."""
    return frame[7] | frame[8] << 8 | frame[9] << 16 if frame[0] == 0xFD else frame[5]


class CountingLine(SerialLine):
    """The autopilot's side of the line, counting the frames it offers by message name."""

    def __init__(self, baud: int, *, now: float) -> None:
        super().__init__(baud, buffer_bytes=TX_BUFFER_BYTES, now=now)
        self.offered: collections.Counter[str] = collections.Counter()

    def offer(self, frame: bytes, now: float) -> bool:
        kind = dialect.mavlink_map.get(message_id(frame))
        self.offered[kind.msgname if kind else str(message_id(frame))] += 1
        return super().offer(frame, now)


class SetpointLine(SerialLine):
    """The bridge's side of the line, noting each setpoint frame as it reaches the autopilot:
    :attr:`setpoints` holds (wall-clock s when its last byte crossed, the frame)."""

    def __init__(self, baud: int, *, now: float) -> None:
        super().__init__(baud, buffer_bytes=UPLINK_BUFFER_BYTES, now=now)
        self._cutter = FrameCutter()
        self.setpoints: collections.deque[tuple[float, bytes]] = collections.deque(maxlen=20000)

    def take(self, now: float) -> bytes:
        out = super().take(now)
        if out:
            crossed = time.time()
            for frame in self._cutter.feed(out):
                if message_id(frame) == SETPOINT_MSG_ID:
                    self.setpoints.append((crossed, frame))
        return out


def paced_relay(baud: int) -> SerialRelay:
    """A relay (not started: ``with`` it) between the bridge's pseudo-terminal and the
    firmware's (:attr:`SerialRelay.autopilot_path`), its two directions watched."""
    relay = SerialRelay(baud, pty=True, buffer_bytes=TX_BUFFER_BYTES)
    now = time.monotonic()
    relay.down = CountingLine(baud, now=now)
    relay.up = SetpointLine(baud, now=now)
    return relay
