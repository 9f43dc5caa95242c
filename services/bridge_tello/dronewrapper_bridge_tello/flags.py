"""bridge_tello's command-line shortcuts: ``--tello ADDRESS`` and ``--local ADDRESS`` are
``--set tello_address=ADDRESS`` and ``--set local_address=ADDRESS``."""

from __future__ import annotations

from dronewrapper_bridge_base.shortcuts import Shortcut, Shortcuts

SHORTCUTS = Shortcuts(
    Shortcut("--tello", "tello_address", "ADDRESS", "the Tello's IP address"),
    Shortcut("--local", "local_address", "ADDRESS", "address our sockets bind"),
)
add_flags = SHORTCUTS.add_flags
as_overrides = SHORTCUTS.as_overrides
