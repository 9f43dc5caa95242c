"""The simulator's Tello as bridge_tello's link, in process, on the node's clock.

:class:`ClockedTello` has the surface of :class:`~dronewrapper_bridge_tello.link.TelloLink` the
bridge uses (``send``, a ``command`` and a ``state`` socket to receive from, no video) but no
socket: each command is the SDK's text handed to the simulator's
:class:`~dronewrapper_sim.tello.protocol.TelloProtocol`, whose replies and 10 Hz state strings
come back through the two receiving ends. The flight moves (at 100 Hz) to the clock's
``monotonic()`` whenever the link is used, and a receive waits through the clock, so the real
``Bridge`` (its reply, state and control threads) runs on a fake bus's virtual time.
"""

from __future__ import annotations

import threading
from collections import deque

from dronewrapper.runtime.clock import Clock
from dronewrapper_sim.tello.flight import TelloFlight
from dronewrapper_sim.tello.protocol import TelloProtocol
from dronewrapper_sim.tello.state_string import format_state

PHYSICS_S = 0.01
"""One step of the flight (s)."""
STATE_S = 0.1
"""The state string's period (s), the Tello's 10 Hz."""
BRIDGE = ("127.0.0.1", 9000)
"""The address the bridge's commands come from (the simulated Tello answers it)."""


class ClockedEnd:
    """One receiving socket of the bridge: ``recvfrom`` waits through the clock, at most
    ``timeout`` s as the real socket's, then raises TimeoutError."""

    def __init__(self, owner: ClockedTello, timeout: float = 0.2) -> None:
        self.inbox: deque[bytes] = deque()
        self._owner = owner
        self._timeout = timeout

    def recvfrom(self, _size: int) -> tuple[bytes, tuple[str, int]]:
        owner = self._owner
        deadline = owner.clock.monotonic() + self._timeout
        while True:
            with owner.lock:
                owner.catch_up()
                if self.inbox:
                    return self.inbox.popleft(), ("192.168.10.1", 8889)
            left = deadline - owner.clock.monotonic()
            if left <= 0 or owner.clock.wait(owner.stop, min(left, PHYSICS_S * 2)):
                raise TimeoutError


class ClockedTello:
    """The simulated Tello behind a bridge's link on ``clock`` (see the module doc); ``stop``:
    the bridge node's stop event; ``flight``: the aircraft (a default Tello if None)."""

    def __init__(
        self, clock: Clock, stop: threading.Event, flight: TelloFlight | None = None
    ) -> None:
        self.clock, self.stop = clock, stop
        self.protocol = TelloProtocol(flight or TelloFlight())
        self.lock = threading.Lock()  # the flight, shared by the bridge's threads
        self.command, self.state = ClockedEnd(self), ClockedEnd(self)
        self.video = None
        self.sent: list[tuple[float, str]] = []  # (clock's monotonic s, command text)
        self._t0 = clock.monotonic()
        self._next_state = 0.0

    def send(self, text: str) -> None:
        """One SDK command from the bridge; its reply queued on the command end."""
        with self.lock:
            self.catch_up()
            now = self.clock.monotonic()
            self.sent.append((now, text))
            self._reply(self.protocol.handle(text.encode("ascii"), BRIDGE, now - self._t0))

    def close(self) -> None:
        pass

    def catch_up(self) -> None:
        """The flight moved to the clock's now, replies and state strings queued on the way
        (under ``lock``)."""
        protocol, now = self.protocol, self.clock.monotonic() - self._t0
        while protocol.flight.time_s + PHYSICS_S <= now:
            self._reply(protocol.tick(PHYSICS_S, protocol.flight.time_s + PHYSICS_S))
            if protocol.sdk_mode and protocol.flight.time_s >= self._next_state:
                self._next_state = protocol.flight.time_s + STATE_S
                self.state.inbox.append(format_state(protocol).encode("ascii"))

    def _reply(self, replies: list) -> None:
        self.command.inbox.extend(reply.text.encode("utf-8") for reply in replies)
