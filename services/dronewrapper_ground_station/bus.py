"""How the station reaches the bus: through a runtime ``Node``, or a ``FakeNode`` in tests.

The two share the surface a service uses (subscribe, publisher, call ...); the little here
covers what that surface lacks for the station: a wildcard subscription that hands over each
sample's key, the liveliness tokens present, and a view of the node in one drone's namespace.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, TypeVar

import zenoh

from dronewrapper.discovery import alive_services
from dronewrapper.msgs.registry import Topic
from dronewrapper.runtime.delivery import decoding

T = TypeVar("T")


def subscribe_keyed(
    node: Any, topic: Topic[T], keyexpr: str, callback: Callable[[str, T], None]
) -> Any:
    """Call ``callback(key, msg)`` for every decodable sample on ``keyexpr`` (a wildcard).

    The runtime's ``node.subscribe`` hands its callback the message only, and a world object's
    name is in its key (``sim/objects/{name}/pose``), so this one subscription reaches the
    node's transport (the real session, or the fake bus) and decodes through the runtime's one
    decode path (:func:`~dronewrapper.runtime.delivery.decoding`, errors counted on the node).
    """

    def deliver(key: str, payload: bytes, attachment: Any = None) -> None:
        decoding(topic.type, lambda msg: callback(key, msg), node.sample_errors)(
            key, payload, attachment
        )

    if node.session is None:  # a FakeNode: its bus
        return node.bus.subscribe(keyexpr, deliver)
    # a direct callback (decode and store only): no Python thread for this subscriber
    handler = zenoh.handlers.Callback(
        lambda s: deliver(str(s.key_expr), s.payload.to_bytes(), s.attachment), indirect=False
    )
    return node.session.declare_subscriber(keyexpr, handler)


def alive_keys(node: Any) -> set[str]:
    """The liveliness keys (``{ns}/alive/{name}``) present now: the router's, or the fake
    bus's tokens."""
    if node.session is None:  # a FakeNode
        return node.alive_services("*")
    return alive_services(node.session, "*", timeout=1.0)


class DroneNode:
    """The station's node seen from one drone's namespace, for that drone's DroneWrapper.

    ``DroneWrapper(node=...)`` keys its subscriptions, setpoints and service calls in the
    node's own namespace; the station's node serves many drones, so this view fills in the
    drone's namespace and forwards everything else.
    """

    def __init__(self, node: Any, ns: str) -> None:
        self.node = node
        self.ns = ns
        self.session = node.session
        self.sample_errors = node.sample_errors

    def subscribe(self, topic: Topic[T], callback: Callable[[T], None], **parts: str) -> Any:
        return self.node.subscribe(topic, callback, key=topic.key(self.ns, **parts))

    def publisher(self, topic: Topic[T], **parts: str) -> Any:
        return self.node.publisher(topic, key=topic.key(self.ns, **parts))

    def call(self, service: Any, request: Any, **options: Any) -> Any:
        return self.node.call(service, request, **{**options, "ns": self.ns})
