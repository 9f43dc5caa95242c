"""DroneWrapper: fly real or simulated drones and run vision apps in a few lines of Python.

    from dronewrapper import DroneWrapper
    drone = DroneWrapper()
    drone.takeoff(h=2.5)
    drone.set_cmd_vel(az=1)   # spin
    drone.land()

The SDK talks to the aircraft's bridge over Zenoh (see docs/design.md for keys, frames and units).
Heavy parts load on first use: ``import dronewrapper`` loads no other module (not even
``typing``), so it stays light for the runtime's tools.

``dronewrapper`` is one package in four distributions, each importing only those below it: the
contract (``dronewrapper.msgs``, from ``contract/``), the runtime (``dronewrapper.runtime`` and
``dronewrapper.security``, from ``runtime/``), this client, and the tools (``dronewrapper.cli``,
``doctor``, ``echo``, ``record``, ``router``, ..., from ``tools/``). Installed from wheels they
share one folder; installed editable (``make setup``) each is its own path entry, which
``__path__`` below joins.
"""

import os
import sys

TYPE_CHECKING = False  # typing.TYPE_CHECKING without importing typing (type checkers: True)

__path__ = [  # the other distributions' parts of this package (as pkgutil.extend_path)
    *__path__,
    *(
        part
        for entry in sys.path
        if isinstance(entry, str)
        and os.path.isdir(part := os.path.realpath(os.path.join(entry or ".", __name__)))
        and part not in map(os.path.realpath, __path__)
    ),
]

__version__ = "0.1.0"

__all__ = [
    "Cancelled",
    "CommandRefused",
    "DroneError",
    "DroneWrapper",
    "InvalidArgument",
    "NoData",
    "NotConnected",
    "Timeout",
    "list_drones",
]

_LAZY = {
    "DroneWrapper": "dronewrapper.drone",
    "list_drones": "dronewrapper.discovery",
    "Cancelled": "dronewrapper.errors",
    "CommandRefused": "dronewrapper.errors",
    "DroneError": "dronewrapper.errors",
    "InvalidArgument": "dronewrapper.errors",
    "NoData": "dronewrapper.errors",
    "NotConnected": "dronewrapper.errors",
    "Timeout": "dronewrapper.errors",
}

if TYPE_CHECKING:
    from dronewrapper.discovery import list_drones
    from dronewrapper.drone import DroneWrapper
    from dronewrapper.errors import (
        Cancelled,
        CommandRefused,
        DroneError,
        InvalidArgument,
        NoData,
        NotConnected,
        Timeout,
    )


def __getattr__(name: str) -> object:
    module = _LAZY.get(name)
    if module is None:
        raise AttributeError(f"module 'dronewrapper' has no attribute {name!r}")
    import importlib

    value = getattr(importlib.import_module(module), name)
    globals()[name] = value
    return value
