"""The Zenoh runtime every DroneWrapper process uses (services, simulator, SDK, tools)."""

from dronewrapper.runtime.errors import ServiceError, ServiceTimeout, ServiceUnavailable
from dronewrapper.runtime.latest import Latest
from dronewrapper.runtime.node import Node, Publisher, call_service, encoding_for, open_session
from dronewrapper.runtime.options import (
    DEFAULT_ROUTER,
    ZenohOptions,
    add_zenoh_args,
    options_from_args,
    zenoh_config,
)
from dronewrapper.runtime.rate import Ratekeeper

__all__ = [
    "DEFAULT_ROUTER",
    "Latest",
    "Node",
    "Publisher",
    "Ratekeeper",
    "ServiceError",
    "ServiceTimeout",
    "ServiceUnavailable",
    "ZenohOptions",
    "add_zenoh_args",
    "call_service",
    "encoding_for",
    "open_session",
    "options_from_args",
    "zenoh_config",
]
