"""The paper's module name: ``from drone_wrapper import DroneWrapper`` works as in 2022.

Everything here is :mod:`dronewrapper`'s API under the original import path.
"""

from dronewrapper.discovery import list_drones
from dronewrapper.drone import DroneWrapper
from dronewrapper.errors import (
    CommandRefused,
    DroneError,
    InvalidArgument,
    NoData,
    NotConnected,
    Timeout,
)

__all__ = [
    "CommandRefused",
    "DroneError",
    "DroneWrapper",
    "InvalidArgument",
    "NoData",
    "NotConnected",
    "Timeout",
    "list_drones",
]
