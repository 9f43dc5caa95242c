"""Zenoh quality of service for each transport class of the registry.

A slow link (a laptop on Wi-Fi) must lose camera frames, never control: the router's queue to
that link sends higher priorities first and drops only ``stream`` samples when it is full.

=============  ==================  ==================  =======
class          priority            congestion control  express
=============  ==================  ==================  =======
``command``    INTERACTIVE_HIGH    BLOCK               yes
``telemetry``  DATA_HIGH           DROP                no
``stream``     DATA_LOW            DROP                no
=============  ==================  ==================  =======

Telemetry is not ``BLOCK``: a bridge must never stall because one subscriber is slow; its
high-priority queue only fills when the link carries nothing at all. Service queries travel
like commands, and their replies at their query's priority.
"""

from __future__ import annotations

from typing import Any

import zenoh

from dronewrapper.msgs.registry import COMMAND, STREAM, TELEMETRY, Topic

_QOS: dict[str, dict[str, Any]] = {
    COMMAND: {
        "priority": zenoh.Priority.INTERACTIVE_HIGH,
        "congestion_control": zenoh.CongestionControl.BLOCK,
        "express": True,
    },
    TELEMETRY: {
        "priority": zenoh.Priority.DATA_HIGH,
        "congestion_control": zenoh.CongestionControl.DROP,
    },
    STREAM: {
        "priority": zenoh.Priority.DATA_LOW,
        "congestion_control": zenoh.CongestionControl.DROP,
    },
}

SERVICE_QOS: dict[str, Any] = {
    "priority": zenoh.Priority.INTERACTIVE_HIGH,
    "congestion_control": zenoh.CongestionControl.BLOCK,
}
"""Options of service queries (replies travel at their query's priority)."""


def qos_for(topic: Topic[Any]) -> dict[str, Any]:
    """The publisher options of ``topic``'s transport class (a fresh dict)."""
    return class_qos(topic.transport)


def class_qos(transport: str) -> dict[str, Any]:
    """The publisher options of a transport class (``command``, ``telemetry``, ``stream``;
    a fresh dict), for keys outside the registry that travel as one of them."""
    return dict(_QOS[transport])
