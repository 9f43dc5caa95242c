"""A node's stop request, shared by :class:`~dronewrapper.runtime.node.Node` and
:class:`~dronewrapper.runtime.fake.FakeNode`: ``stop_event`` (set by :meth:`Stopping.stop`, by a
signal or by ``close``), read through :attr:`Stopping.stopping`, and the ``with`` block that
closes the node at its end."""

from __future__ import annotations

import threading
from typing import TypeVar

S = TypeVar("S", bound="Stopping")


class Stopping:
    """The stop request of a node whose class sets ``stop_event`` and defines ``close``."""

    stop_event: threading.Event

    def __enter__(self: S) -> S:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def close(self) -> None:
        raise NotImplementedError

    @property
    def stopping(self) -> bool:
        """True once a stop was requested (a signal, :meth:`stop` or ``close``)."""
        return self.stop_event.is_set()

    def stop(self) -> None:
        """Ask the process's loops to end."""
        self.stop_event.set()
