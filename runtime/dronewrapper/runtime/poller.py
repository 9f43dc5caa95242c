"""One thread that waits on many members' sockets and deadlines: a host's shared loop.

N sims and N bridges hosted in one process (:mod:`dronewrapper.runtime.host`) would each wake
a thread of their own: a sim 50 times a second to step its physics, a bridge at every burst of
datagrams. Each wake-up takes the interpreter's lock for a few tens of microseconds of work,
and N threads contending for it cost more than the work. A :class:`Poller` waits once for all
of them: each member adds a :class:`Pollable` (a socket to read when it is readable, a deadline
to be called at), and one thread calls, in turn, every one whose deadline has come, then waits
(``poll``) for the first socket readable or the next deadline and reads every readable one.
The sims that step at the same instants (their wake-ups on one grid, :mod:`dronewrapper_sim`)
send their datagrams together, and the bridges read them all in the next round, without a
second wake-up.

What the members share: a call that takes long delays the others' calls of that round (each
is short: a sim's steps, a bridge's batch of messages; a member that needs to wait does not
join); a deadline is kept to within the longest round. What they do not share: an exception
out of one member's call is logged and counted (``errors``), that member's ``failed`` is called
with it and it leaves (every entry of its ``stop``: its node ends, see the host), and the
others go on. A member leaves when its ``stop`` is set (checked every round, at least every
:data:`MAX_WAIT_S`). The thread ends when the last entry has left; a new one starts when
another is added.
"""

from __future__ import annotations

import logging
import math
import select
import threading
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from functools import partial
from typing import Protocol

from dronewrapper.runtime.clock import REAL, Clock

log = logging.getLogger("poller")

MAX_WAIT_S = 0.05
"""The longest one wait lasts (s): how soon a stop or a new entry is noticed at worst."""
NO_FILE = -1
"""``fileno()`` of an entry with no socket to wait on now (a timer, a link not open)."""


class Pollable(Protocol):
    """What a member adds: its socket and its deadline."""

    def fileno(self) -> int:
        """The descriptor to wait on for reading, :data:`NO_FILE` for none now."""
        ...

    def on_readable(self) -> float | None:
        """Its socket is readable: read what waits (without blocking); returns a new deadline
        (monotonic s), or None to keep the one it has."""
        ...

    def on_due(self, now: float) -> float:
        """Its deadline has come (``now``: the clock's monotonic s); returns the next one
        (``math.inf``: none)."""
        ...


class Readiness(Protocol):
    """Waits until some descriptors are readable or a timeout passes."""

    def wait(self, fds: Sequence[int], timeout: float) -> list[int]:
        """The readable ones of ``fds`` (at most ``timeout`` s from now; [] at the timeout)."""
        ...


class PollReadiness:
    """:class:`Readiness` by ``select.poll`` (no limit on descriptor numbers), the set of
    descriptors registered once and changed only when it changes."""

    def __init__(self) -> None:
        self._poll = select.poll()
        self._fds: set[int] = set()

    def wait(self, fds: Sequence[int], timeout: float) -> list[int]:
        wanted = set(fds)
        if wanted != self._fds:
            for fd in self._fds - wanted:
                self._poll.unregister(fd)
            for fd in wanted - self._fds:
                self._poll.register(fd, select.POLLIN)
            self._fds = wanted
        events = self._poll.poll(max(0.0, timeout) * 1000.0)
        return [fd for fd, _ in events]


@dataclass
class _Entry:
    item: Pollable
    stop: threading.Event
    failed: Callable[[BaseException], None]
    due: float


class Poller:
    """Serves every added :class:`Pollable` from one thread (made with ``clock``).

    Args:
        clock: the clock the deadlines are kept on (the real one unless given).
        name: the thread's name.
        readiness: how the thread waits for sockets (``poll`` unless given); with no socket
            to wait on it waits on ``clock``.
    """

    def __init__(
        self, clock: Clock = REAL, name: str = "poller", readiness: Readiness | None = None
    ) -> None:
        self.clock = clock
        self.name = name
        self.readiness = readiness or PollReadiness()
        self.errors = 0
        self.rounds = 0
        self._lock = threading.Lock()
        self._entries: list[_Entry] = []
        self._thread: threading.Thread | None = None

    @property
    def entries(self) -> int:
        """How many entries are served now."""
        with self._lock:
            return len(self._entries)

    def add(
        self,
        item: Pollable,
        stop: threading.Event,
        failed: Callable[[BaseException], None],
        due: float = -math.inf,
    ) -> None:
        """Serve ``item`` until ``stop`` is set: read it when readable, call it at ``due``
        (monotonic s; at once unless given) and then at each deadline it returns. An exception
        out of it calls ``failed(exc)`` (which should set ``stop``) and it leaves."""
        with self._lock:
            self._entries.append(_Entry(item, stop, failed, due))
            if self._thread is None:
                self._thread = self.clock.thread(self._run, self.name)
                self._thread.start()

    def once(self) -> bool:
        """One round: every entry whose deadline has come is called, then the thread waits
        for a socket or the next deadline and reads every readable entry. False when no
        entry is left (the thread then ends)."""
        with self._lock:
            self._entries = [e for e in self._entries if not e.stop.is_set()]
            entries = list(self._entries)
            if not entries:
                self._thread = None
                return False
        self.rounds += 1
        now = self.clock.monotonic()
        for entry in entries:
            if entry.due <= now and not entry.stop.is_set():
                self._call(entry, partial(self._wake, entry, now))
        by_fd: dict[int, _Entry] = {}
        for entry in entries:
            if not entry.stop.is_set():
                fd = entry.item.fileno()
                if fd != NO_FILE:
                    by_fd[fd] = entry
        next_due = min((e.due for e in entries if not e.stop.is_set()), default=math.inf)
        timeout = min(max(next_due - self.clock.monotonic(), 0.0), MAX_WAIT_S)
        if by_fd:
            ready = self.readiness.wait(list(by_fd), timeout)
        else:
            ready = []
            if timeout > 0:
                self.clock.sleep(timeout)
        for fd in ready:
            entry = by_fd[fd]
            if not entry.stop.is_set():
                self._call(entry, partial(self._read, entry))
        return True

    @staticmethod
    def _wake(entry: _Entry, now: float) -> None:
        entry.due = entry.item.on_due(now)

    @staticmethod
    def _read(entry: _Entry) -> None:
        due = entry.item.on_readable()
        if due is not None:
            entry.due = due

    def _call(self, entry: _Entry, call: Callable[[], object]) -> None:
        """``call()``; an exception out of it fails ``entry``'s member (it leaves)."""
        try:
            call()
        except Exception as exc:
            self.errors += 1
            entry.due = math.inf
            log.exception("%s: a member failed", self.name)
            try:
                entry.failed(exc)
            except Exception:
                log.exception("%s: reporting a failure failed", self.name)
            entry.stop.set()

    def _run(self) -> None:
        while self.once():
            pass
