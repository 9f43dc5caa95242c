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


class ProgressHandler(logging.Handler):
    """The SDK's own handler (one per process): each line to ``sys.stderr`` as it is when the
    line is written (a tool or a test may have replaced it)."""

    def __init__(self) -> None:
        super().__init__()
        self.setFormatter(logging.Formatter(FORMAT))
        self.addFilter(_UnlessConfigured())

    def emit(self, record: logging.LogRecord) -> None:
        try:
            sys.stderr.write(self.format(record) + "\n")
            sys.stderr.flush()
        except Exception:
            self.handleError(record)


def show_progress(logger: logging.Logger | None = None) -> None:
    """Print the SDK's INFO progress on stderr unless the application configured logging
    (idempotent; a level the application set on the logger is kept)."""
    logger = logger or logging.getLogger("dronewrapper")
    if any(isinstance(h, ProgressHandler) for h in logger.handlers):
        return
    logger.addHandler(ProgressHandler())
    if logger.level == logging.NOTSET:
        logger.setLevel(logging.INFO)
