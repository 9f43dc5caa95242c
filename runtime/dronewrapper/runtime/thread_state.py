"""Python thread states kept for the Zenoh threads that run subscriber callbacks directly.

A direct callback (``Node(direct_callbacks=True)``, ``subscribe(direct=True)``) runs on one of
Zenoh's own threads, which Python did not start. Each time, the binding makes that thread a
Python thread state, takes the GIL, runs the callback, and deletes the state again; making and
deleting one maps and unmaps its frame stack (page faults, and a TLB flush on every CPU of the
process). Holding one more ``PyGILState_Ensure`` on such a thread, never released, keeps its
state from one callback to the next: a 64-byte round trip between two processes with direct
callbacks took 0.066 ms with the states made and deleted and 0.037 ms with them kept (one CPU;
``bench.transport_breakdown``). The GIL is still released after every callback.

At most :data:`MAX_KEPT` threads keep a state (Zenoh's pools may start threads and end them
when idle; a state kept for a thread that ended stays allocated until the interpreter ends).
"""

from __future__ import annotations

import threading
from collections.abc import Callable

MAX_KEPT = 32
"""Threads whose Python thread state is kept, at most (a state is a few kB)."""


class ThreadStates:
    """Keeps the Python thread state of the threads that call :meth:`keep` (up to ``limit``).

    ``ensure`` is ``PyGILState_Ensure`` (injected for tests; None: CPython's, looked up at the
    first :meth:`keep`, so that importing this module loads no ``ctypes``); ``ident`` names
    the calling thread.
    """

    def __init__(
        self,
        ensure: Callable[[], object] | None = None,
        ident: Callable[[], int] = threading.get_ident,
        limit: int = MAX_KEPT,
    ) -> None:
        self._ensure = ensure
        self._ident = ident
        self._limit = limit
        self._kept: set[int] = set()
        self._lock = threading.Lock()

    @property
    def kept(self) -> int:
        """How many threads keep their state."""
        return len(self._kept)

    def keep(self) -> None:
        """Keep the calling thread's Python thread state (once per thread; call with the GIL)."""
        ident = self._ident()
        if ident in self._kept:
            return
        with self._lock:
            if ident in self._kept or len(self._kept) >= self._limit:
                return
            if self._ensure is None:
                import ctypes

                self._ensure = ctypes.pythonapi.PyGILState_Ensure
            self._ensure()  # one more Ensure than Release: the state outlives the callback
            self._kept.add(ident)


KEPT = ThreadStates()
"""The process's kept thread states (a thread state belongs to the interpreter)."""
