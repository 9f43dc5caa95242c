"""bridge_mavlink's command-line shortcuts: ``--connection URL`` and ``--baud N`` are
``--set connection=URL`` and ``--set baud=N``."""

from __future__ import annotations

from dronewrapper_bridge_base.shortcuts import Shortcut, Shortcuts

SHORTCUTS = Shortcuts(
    Shortcut(
        "--connection",
        "connection",
        "URL",
        "pymavlink URL: udpin:HOST:PORT, udpout:HOST:PORT, tcp:HOST:PORT, tcpin:HOST:PORT "
        "or a serial device",
    ),
    Shortcut("--baud", "baud", "N", "serial baud rate", int),
)
add_flags = SHORTCUTS.add_flags
as_overrides = SHORTCUTS.as_overrides
