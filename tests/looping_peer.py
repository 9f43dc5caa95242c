"""A fake autopilot that sends and receives on two daemon threads, for the bridge tests.

A subclass defines ``_send_loop`` and ``_recv_loop`` (each returning once ``_stop`` is set) and
``_close_link`` (its socket), and calls :meth:`LoopingPeer._start_loops` at the end of its
construction; :meth:`LoopingPeer.close` stops both loops (each joined for up to 2 s) and closes
the link.
"""

from __future__ import annotations

import threading


class LoopingPeer:
    """The two loops of a fake peer and their stop (see module docstring)."""

    _stop: threading.Event
    _threads: list[threading.Thread]

    def _start_loops(self) -> None:
        self._stop = threading.Event()
        self._threads = [
            threading.Thread(target=self._send_loop, daemon=True),
            threading.Thread(target=self._recv_loop, daemon=True),
        ]
        for thread in self._threads:
            thread.start()

    def close(self) -> None:
        self._stop.set()
        for thread in self._threads:
            thread.join(2)
        self._close_link()

    def _send_loop(self) -> None:
        raise NotImplementedError

    def _recv_loop(self) -> None:
        raise NotImplementedError

    def _close_link(self) -> None:
        raise NotImplementedError
