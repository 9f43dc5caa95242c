"""Zenoh's own log lines, relayed into this process's logging with their meaning.

The Zenoh library writes its log to standard output (fd 1) once ``zenoh.init_log_from_env_or``
is called. A router with a TLS listener calls :func:`relay_zenoh_log` first: fd 1 becomes a
pipe that a thread reads; Python's ``sys.stdout`` keeps writing where fd 1 went before. Each
line of Zenoh's is parsed (:func:`parse`) and decided by :class:`Relay` (pure, time passed in):

- a rejected TLS handshake (``zenoh_link_tls``: "received fatal alert: UnknownCA. Hint:
  increase the system open file limit") becomes what it means for the drone, once per cause and
  interval with a count (:class:`~dronewrapper.security.handshake.RejectionLog`); Zenoh names
  no peer address in that line, so the interval is per cause;
- any other Zenoh line is logged at its level under the logger ``zenoh``;
- a line that is not Zenoh's (a child process writing to the inherited fd 1) passes through.

Only errors, and warnings of the TLS link, are asked of Zenoh unless ``RUST_LOG`` says more.
"""

from __future__ import annotations

import logging
import os
import re
import sys
import threading
import time
from dataclasses import dataclass

from dronewrapper.security.handshake import RejectionLog, router_meaning

ANSI = re.compile(r"\x1b\[[0-9;]*m")
LINE = re.compile(
    r"^\S+\s+(?P<level>TRACE|DEBUG|INFO|WARN|ERROR)\s+(?:\S+\s+ThreadId\(\d+\)\s+)?"
    r"(?P<target>[\w:]+):\s(?P<message>.*)$"
)
LEVELS = {
    "TRACE": logging.DEBUG,
    "DEBUG": logging.DEBUG,
    "INFO": logging.INFO,
    "WARN": logging.WARNING,
    "ERROR": logging.ERROR,
}
DIRECTIVES = "error,zenoh_link_tls=warn"
"""What is asked of Zenoh's log when ``RUST_LOG`` is not set."""
TLS_TARGET = "zenoh_link_tls"


@dataclass(frozen=True)
class ZenohLine:
    """One parsed line of Zenoh's log."""

    level: int  # a logging level
    target: str  # the Rust module, e.g. zenoh_link_tls::unicast
    message: str


def parse(line: str) -> ZenohLine | None:
    """The Zenoh log line in ``line`` (colours stripped), None when it is not one (pure).

    >>> parse("2026-11-27T22:46:22.9Z  WARN acc-0 ThreadId(04) zenoh_link_tls::unicast: x")
    ZenohLine(level=30, target='zenoh_link_tls::unicast', message='x')
    """
    match = LINE.match(ANSI.sub("", line.rstrip("\n")))
    if match is None:
        return None
    return ZenohLine(LEVELS[match["level"]], match["target"], match["message"])


class Relay:
    """What to log for each line (pure): ``handle(line, now)`` -> ``(level, text)`` to log,
    ``(None, line)`` to pass through unchanged, or None to stay quiet."""

    def __init__(self, interval_s: float = 30.0) -> None:
        self.rejections = RejectionLog(interval_s)

    def handle(self, line: str, now: float) -> tuple[int | None, str] | None:
        parsed = parse(line)
        if parsed is None:
            return None, line
        if parsed.target.startswith(TLS_TARGET) and parsed.level >= logging.WARNING:
            cause, sentence = router_meaning(parsed.message)
            said = self.rejections.note(cause, sentence, now)
            return None if said is None else (logging.WARNING, said)
        return parsed.level, f"{parsed.target}: {parsed.message}"


_started = False


def relay_zenoh_log(log: logging.Logger, interval_s: float = 30.0) -> None:
    """Start Zenoh's log and relay it into ``log`` (see the module doc); once per process."""
    global _started
    if _started:
        return
    _started = True
    import zenoh

    shown = os.dup(1)
    read_end, write_end = os.pipe()
    sys.stdout.flush()
    os.dup2(write_end, 1)
    os.close(write_end)
    terminal = os.fdopen(shown, "w", buffering=1)
    sys.stdout = terminal
    relay = Relay(interval_s)

    def pump() -> None:
        with os.fdopen(read_end, "r", errors="replace") as lines:
            for line in lines:
                decided = relay.handle(line, time.monotonic())
                if decided is None:
                    continue
                level, text = decided
                if level is None:
                    terminal.write(line)
                else:
                    log.log(level, "%s", text)

    threading.Thread(target=pump, name="zenoh-log", daemon=True).start()
    zenoh.init_log_from_env_or(DIRECTIVES)
