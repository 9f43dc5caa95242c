"""The node contract: what a process sees of the world, the bus and the clock.

A process is ``run(node, config)``; ``node`` satisfies :class:`NodeApi`. Two classes do:
:class:`~dronewrapper.runtime.node.Node` (a Zenoh session, the real clocks) and
:class:`~dronewrapper.runtime.fake.FakeNode` (the fake bus in process, virtual time). A service,
the :class:`~dronewrapper.client.DroneClient` and the SDK's
:class:`~dronewrapper.drone.DroneWrapper` are written against this contract only, and
``tests/node_contract.py`` checks both classes against it.

Time: ``node.clock`` is a :class:`~dronewrapper.runtime.clock.Clock`: ``monotonic()`` (s) for
intervals, ages and deadlines, ``time()`` (Unix s) for stamps, and its waits (``sleep``,
``wait``, ``wait_for``) and ``thread``. Newest-value holders from ``latest`` age and wait on it.
"""

from __future__ import annotations

import logging
import threading
from collections import Counter
from collections.abc import Callable
from typing import Any, Protocol, TypeVar, runtime_checkable

from dronewrapper.msgs.registry import Service, Topic
from dronewrapper.runtime.clock import Clock
from dronewrapper.runtime.delivery import SampleErrors
from dronewrapper.runtime.latest import Latest

T = TypeVar("T")
Req = TypeVar("Req")
Rep = TypeVar("Rep")


class Declared(Protocol):
    """Something declared on the bus (a subscription, a queryable, a matching listener)."""

    def undeclare(self) -> None: ...


@runtime_checkable
class PublisherApi(Protocol[T]):
    """A typed publisher on one concrete key."""

    key: str
    type: type[T]
    count: int

    def put(self, msg: T, *, attachment: bytes | None = None) -> None:
        """Publish ``msg`` (of this publisher's type, else TypeError)."""

    def watched(self) -> bool:
        """True while at least one subscriber matches the key."""

    def on_matching(self, callback: Callable[[bool], None]) -> Declared:
        """Call ``callback(matching)`` when subscribers start or stop matching the key."""

    def undeclare(self) -> None: ...


@runtime_checkable
class NodeApi(Protocol):
    """One process's presence on the bus, with its clock (see the module doc)."""

    name: str
    ns: str
    log: logging.Logger
    clock: Clock
    stop_event: threading.Event
    sample_errors: SampleErrors
    decode_errors: Counter[str]
    callback_errors: Counter[str]

    @property
    def stopping(self) -> bool:
        """True once a stop was requested."""

    def stop(self) -> None:
        """Ask the process's loops to end."""

    def sleep(self, seconds: float) -> bool:
        """Let ``seconds`` pass on the node's clock unless stopped; False if stopped."""

    def spin(self) -> None:
        """Run until a stop is requested (the fake bus: until nothing is scheduled)."""

    def announce(self) -> None:
        """Declare the liveliness token ``{ns}/alive/{name}``."""

    def alive_services(self, ns: str = "*", timeout: float = 1.0) -> set[str]:
        """The liveliness keys (``ns/alive/name``) present now, in ``ns`` or all."""

    def linked(self) -> bool:
        """True while the node reaches a router or a peer (the fake bus: always)."""

    def close(self) -> None:
        """Withdraw the token and everything declared (idempotent)."""

    def publisher(
        self,
        topic: Topic[T],
        *,
        key: str | None = None,
        qos: dict[str, Any] | None = None,
        **parts: str,
    ) -> PublisherApi[T]:
        """A typed publisher for ``topic`` (the registry's QoS) in this node's namespace."""

    def subscribe(
        self,
        topic: Topic[T],
        callback: Callable[..., None],
        *,
        key: str | None = None,
        keyed: bool = False,
        direct: bool | None = None,
        **parts: str,
    ) -> Declared:
        """Call ``callback(msg)`` (``keyed``: ``callback(key, msg)``) for every decodable
        sample; errors are counted, never end the subscription. ``direct``: on the thread that
        delivers the sample (the putting thread for the node's own puts)."""

    def latest(self, topic: Topic[T], *, key: str | None = None, **parts: str) -> Latest[T]:
        """Subscribe to ``topic`` and keep its newest value, aged on :attr:`clock`."""

    def serve(self, service: Service[Req, Rep], handler: Callable[[Req], Rep], **parts: str) -> Any:
        """Answer ``service`` requests with ``handler``; bad requests get an error reply."""

    def call(
        self,
        service: Service[Req, Rep],
        request: Req,
        *,
        timeout: float = 5.0,
        ns: str | None = None,
        attachment: bytes | None = None,
        **parts: str,
    ) -> Rep:
        """Ask ``service`` and return its reply (ServiceError, ServiceUnavailable)."""
