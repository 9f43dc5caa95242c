"""The SDK's progress on stderr for a script, as djitellopy prints its own: connecting,
taking off, climbing, landing, each one line at INFO (``[dronewrapper] takeoff: ...``).

:func:`show_progress` attaches one handler to the ``dronewrapper`` logger. It stays silent
while the application configures logging itself (the root logger has a handler, as after
``logging.basicConfig`` or in the project's services), so no line is printed twice. A script
that wants only warnings: ``logging.getLogger("dronewrapper").setLevel(logging.WARNING)``.
"""

from __future__ import annotations

import logging
import sys

FORMAT = "[%(name)s] %(message)s"


class _UnlessConfigured(logging.Filter):
    """Passes a record only while the root logger has no handler of its own."""

    def filter(self, record: logging.LogRecord) -> bool:
        return not logging.getLogger().handlers


class ProgressHandler(logging.StreamHandler):
    """The SDK's own stderr handler (one per process)."""

    def __init__(self) -> None:
        super().__init__(sys.stderr)
        self.setFormatter(logging.Formatter(FORMAT))
        self.addFilter(_UnlessConfigured())

    @property
    def stream(self):  # stderr as it is now (a test or a tool may have replaced it)
        return sys.stderr

    @stream.setter
    def stream(self, _value) -> None:
        pass


def show_progress(logger: logging.Logger | None = None) -> None:
    """Print the SDK's INFO progress on stderr unless the application configured logging
    (idempotent; a level the application set on the logger is kept)."""
    logger = logger or logging.getLogger("dronewrapper")
    if any(isinstance(h, ProgressHandler) for h in logger.handlers):
        return
    logger.addHandler(ProgressHandler())
    if logger.level == logging.NOTSET:
        logger.setLevel(logging.INFO)
