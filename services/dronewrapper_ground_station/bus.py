"""A wildcard subscription that hands over each sample's key, on a runtime ``Node`` or a
``FakeNode`` (the one thing the station needs that their shared surface lacks: a world
object's name is only in its key).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, TypeVar

import zenoh

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
