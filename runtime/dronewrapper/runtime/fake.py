"""A fake bus in injected time: run a service's logic on recorded or scripted messages.

:class:`FakeNode` has the surface of :class:`~dronewrapper.runtime.node.Node` a service uses
(``publisher``, ``subscribe``, ``latest``, ``serve``, ``call``, ``stop_event``, ``announce`` ...)
but no Zenoh session: messages go through a :class:`FakeBus` in process. The bus delivers
scheduled messages in time order on the caller's thread, moving its clock (a
:class:`~dronewrapper.runtime.clock.VirtualClock`) to each message's time first, so a service fed
through it sees recorded time, deterministically, however loaded the machine is (openpilot's
process replay idea). A wait on that clock from the test's thread (``node.sleep``, a holder's
``wait``) delivers what is scheduled meanwhile.

    bus = FakeBus(start=t0)
    node = FakeNode("perception", bus)
    service = PerceptionService(node, config)         # subscribes, declares its publisher
    for msg in recording:
        bus.schedule(msg.log_time_ns / 1e9, msg.key, msg.payload)
    while bus.step():                                 # one message delivered, clock moved
        service.spin_once(0.0)
    outputs = bus.published[registry.DETECTIONS.key("drone")]

Payloads are encoded and decoded with the registry's types exactly as on the real bus, so a
malformed one is counted in ``decode_errors`` the same way. Key expressions with wildcards
match as Zenoh matches them, and a publisher's matching listener hears subscribers come and go
(a router gap, as seen from a publisher: :meth:`FakeBus.link_gap`). A node given its
process's ``ports`` refuses what they do not declare, as the real node does.

Size: the bus and the node that speaks on it, one fake kept whole.
"""

from __future__ import annotations

import contextlib
import heapq
import itertools
import logging
import threading
from collections import Counter, defaultdict
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from typing import Any, Generic, TypeVar

import msgspec
import zenoh

from dronewrapper.msgs import codec
from dronewrapper.msgs.registry import ALIVE, Service, Topic
from dronewrapper.runtime import caller
from dronewrapper.runtime.clock import VirtualClock
from dronewrapper.runtime.delivery import SampleErrors, decoding
from dronewrapper.runtime.errors import ServiceError, ServiceUnavailable
from dronewrapper.runtime.latest import Latest
from dronewrapper.runtime.ports import Ports
from dronewrapper.runtime.ports import check as check_port
from dronewrapper.runtime.session import ROUTE_WAIT_S
from dronewrapper.runtime.stopping import Stopping
from dronewrapper.security import acl  # a module: acl imports the runtime's caller

T = TypeVar("T")
Req = TypeVar("Req")
Rep = TypeVar("Rep")


@dataclass(frozen=True)
class Delivered(Generic[T]):
    """A message published on the fake bus, with the bus time it was published at (s)."""

    time: float
    msg: T


class _Subscription:
    def __init__(self, bus: FakeBus, keyexpr: str, on_payload: Callable[..., None]) -> None:
        self.keyexpr = zenoh.KeyExpr(keyexpr)
        self.on_payload = on_payload
        self.active = True
        self._bus = bus

    def undeclare(self) -> None:
        if self.active:
            self.active = False
            self._bus._matching_changed()


class _MatchingListener:
    """A publisher's matching listener: ``callback(matching)`` on every change."""

    def __init__(self, bus: FakeBus, key: str, callback: Callable[[bool], None]) -> None:
        self.key = key
        self.callback = callback
        self.matching = bus.matched(key)
        self._bus = bus

    def undeclare(self) -> None:
        with contextlib.suppress(ValueError):
            self._bus._listeners.remove(self)


class FakeBus:
    """Publish/subscribe in process, in injected time.

    ``published`` keeps, per concrete key, every message published by a node (decoded), with
    the bus time; ``schedule`` queues payloads to be delivered later by :meth:`step`.

    A service that runs its own threads (a camera's reader, a bridge's link loops) may publish
    from them: each message is delivered on the publishing thread, as a real session's direct
    callbacks are. ``schedule``/``step``/``run_until`` belong to one thread, the test's.
    """

    def __init__(self, start: float = 0.0, clock: VirtualClock | None = None) -> None:
        self.clock = clock or VirtualClock(monotonic=start, time=start)
        if self.clock.stepper is None:
            self.clock.stepper = self.run_until
        self.published: defaultdict[str, list[Delivered[Any]]] = defaultdict(list)
        self._subs: list[_Subscription] = []
        self._listeners: list[_MatchingListener] = []
        self._gap = False
        self._held: list[tuple[str, bytes, bytes | None]] | None = None
        self._queue: list[tuple[float, int, str, bytes]] = []
        self._seq = itertools.count()
        self._services: dict[str, Callable[[bytes, bytes | None, str], Any]] = {}
        self.tokens: set[str] = set()
        """The liveliness tokens declared on the bus (``{ns}/alive/{name}``, see
        :meth:`FakeNode.announce`)."""

    def subscribe(self, keyexpr: str, on_payload: Callable[..., None]) -> _Subscription:
        sub = _Subscription(self, keyexpr, on_payload)
        self._subs.append(sub)
        self._matching_changed()
        return sub

    def put(self, key: str, payload: bytes, attachment: bytes | None = None) -> None:
        """Deliver ``payload`` (and its ``attachment``) on concrete ``key`` to every matching
        subscriber, now (nothing during a :meth:`link_gap`; later in a :meth:`held` one)."""
        if self._gap:
            return
        if self._held is not None:
            self._held.append((key, payload, attachment))
            return
        ke = zenoh.KeyExpr(key)
        for sub in list(self._subs):
            if sub.active and sub.keyexpr.intersects(ke):
                if attachment is None:
                    sub.on_payload(key, payload)
                else:
                    sub.on_payload(key, payload, attachment)

    @contextlib.contextmanager
    def held(self) -> Iterator[None]:
        """A stalled link that holds what is published (a router's TCP stream during a cut):
        nothing is delivered inside, everything in a burst, in order, on leaving."""
        self._held = []
        try:
            yield
        finally:
            held, self._held = self._held, None
            for key, payload, attachment in held:
                self.put(key, payload, attachment)

    def matched(self, key: str) -> bool:
        """True while at least one active subscription matches ``key`` (none in a gap)."""
        ke = zenoh.KeyExpr(key)
        return not self._gap and any(
            sub.active and sub.keyexpr.intersects(ke) for sub in list(self._subs)
        )

    def on_matching(self, key: str, callback: Callable[[bool], None]) -> _MatchingListener:
        """Call ``callback(matching)`` whenever subscribers start or stop matching ``key`` (at
        once with True when some already match, as Zenoh's listener does)."""
        listener = _MatchingListener(self, key, callback)
        self._listeners.append(listener)
        if listener.matching:
            callback(True)
        return listener

    def link_gap(self, down: bool) -> None:
        """Cut (``down``) or restore every route, as a router restart does: nothing is
        delivered meanwhile and publishers' matching listeners hear it."""
        self._gap = down
        self._matching_changed()

    def _matching_changed(self) -> None:
        for listener in list(self._listeners):
            matching = self.matched(listener.key)
            if matching != listener.matching:
                listener.matching = matching
                listener.callback(matching)

    def schedule(self, at: float, key: str, msg: Any) -> None:
        """Queue ``msg`` (a message Struct or encoded bytes) for delivery at bus time ``at``."""
        payload = msg if isinstance(msg, bytes | bytearray) else codec.encode(msg)
        heapq.heappush(self._queue, (at, next(self._seq), key, bytes(payload)))

    @property
    def pending(self) -> int:
        return len(self._queue)

    def next_time(self) -> float | None:
        """Bus time of the next scheduled message, or None."""
        return self._queue[0][0] if self._queue else None

    def step(self) -> bool:
        """Deliver the next scheduled message (moving the clock to its time); False if none."""
        if not self._queue:
            return False
        at, _, key, payload = heapq.heappop(self._queue)
        self.clock.advance_to(at)
        self.put(key, payload)
        return True

    def run_until(self, t: float, done: Callable[[], bool] = lambda: False) -> int:
        """Deliver every message scheduled up to ``t`` and move the clock to ``t``; stop early
        once ``done()`` after a delivery. The clock's stepper (see the module doc)."""
        count = 0
        while self._queue and self._queue[0][0] <= t:
            self.step()
            count += 1
            if done():
                return count
        self.clock.advance_to(t)
        return count


class FakePublisher(Generic[T]):
    """A typed publisher on the fake bus (same checks as the real one)."""

    def __init__(self, bus: FakeBus, key: str, msg_type: type[T]) -> None:
        self.key = key
        self.type = msg_type
        self.count = 0
        self._bus = bus

    def put(self, msg: T, *, attachment: bytes | None = None) -> None:
        """Deliver ``msg`` now, with ``attachment`` as on the real bus."""
        if type(msg) is not self.type:
            raise TypeError(f"{self.key} carries {self.type.__name__}, got {type(msg).__name__}")
        self.count += 1
        self._bus.published[self.key].append(Delivered(self._bus.clock(), msg))
        self._bus.put(self.key, codec.encode(msg), attachment)

    def watched(self) -> bool:
        """True while a subscriber on the bus matches this key (as the real one's matching
        status)."""
        return self._bus.matched(self.key)

    def on_matching(self, callback: Callable[[bool], None]) -> _MatchingListener:
        """Call ``callback(matching)`` whenever subscribers start or stop matching this key."""
        return self._bus.on_matching(self.key, callback)

    def undeclare(self) -> None:
        pass


class FakeNode(Stopping):
    """The node contract (:class:`~dronewrapper.runtime.contract.NodeApi`) on a
    :class:`FakeBus`: no network, no threads of its own.

    Subscriber callbacks run on the thread that delivers (``FakeBus.step``); ``latest`` holders
    age and wait on the bus clock; services answer synchronously.
    """

    def __init__(
        self,
        name: str,
        bus: FakeBus,
        *,
        ns: str = "drone",
        bound_name: str = "",
        ports: Ports | None = None,
    ) -> None:
        self.name = name
        self.ports = ports
        """As :attr:`Node.ports`: what this node may declare and call; None: anything."""
        self.ns = ns
        self.bound_name = bound_name
        """As :attr:`Node.bound_name`: the certificate name this node's commands are bound to."""
        self.bus = bus
        self.clock = bus.clock
        self.log = logging.getLogger(name)
        self.stop_event = threading.Event()
        self.sample_errors = SampleErrors(self.log, clock=self.clock)
        self.decode_errors: Counter[str] = self.sample_errors.decode
        self.callback_errors: Counter[str] = self.sample_errors.callback
        self.announced = False

    def sleep(self, seconds: float) -> bool:
        """Let ``seconds`` of bus time pass (delivering what is due) unless stopped; False if
        stopped."""
        return not self.clock.wait(self.stop_event, seconds)

    def spin(self) -> None:
        """Deliver everything scheduled, then return."""
        while not self.stopping and self.bus.step():
            pass

    def announce(self) -> None:
        """Declare the liveliness token ``{ns}/alive/{name}`` on the bus (until :meth:`close`)."""
        self.announced = True
        self.bus.tokens.add(ALIVE.key(self.ns, service=self.name))

    def alive_services(self, ns: str = "*", timeout: float = 0.0) -> set[str]:
        """The liveliness keys (``ns/alive/name``) on the bus now, in ``ns`` or all (the fake
        bus's counterpart of :func:`dronewrapper.discovery.alive_services`)."""
        wanted = zenoh.KeyExpr(ALIVE.wildcard(ns))
        return {key for key in self.bus.tokens if wanted.intersects(zenoh.KeyExpr(key))}

    def linked(self) -> bool:
        """The fake bus is in process: linked but during a :meth:`FakeBus.link_gap`."""
        return not self.bus._gap

    def close(self) -> None:
        self.stop_event.set()
        if self.announced:
            self.bus.tokens.discard(ALIVE.key(self.ns, service=self.name))

    def publisher(
        self,
        topic: Topic[T],
        *,
        key: str | None = None,
        qos: dict[str, Any] | None = None,
        **parts: str,
    ) -> FakePublisher[T]:
        check_port(self.ports, "publishes", topic)
        key = acl.commanding_key(topic, key or topic.key(self.ns, **parts), self.bound_name)
        return FakePublisher(self.bus, key, topic.type)

    def subscribe(
        self,
        topic: Topic[T],
        callback: Callable[[T], None],
        *,
        key: str | None = None,
        keyed: bool = False,
        direct: bool | None = None,  # the fake bus always delivers on the publishing thread
        **parts: str,
    ) -> _Subscription:
        check_port(self.ports, "subscribes", topic)
        keyexpr = key or topic.key(self.ns, **parts)
        deliver = decoding(topic.type, callback, self.sample_errors, keyed=keyed)

        def on_payload(where: str, payload: bytes, attachment: bytes | None = None) -> None:
            deliver(where, payload, attachment)

        if acl.is_commanded(topic):  # as the real node: the bound keys too
            self.bus.subscribe(caller.any_bound(keyexpr), on_payload)
        return self.bus.subscribe(keyexpr, on_payload)

    def latest(self, topic: Topic[T], *, key: str | None = None, **parts: str) -> Latest[T]:
        name = key or topic.key(self.ns, **parts)
        holder: Latest[T] = Latest(name=name, clock=self.clock)
        self.subscribe(topic, holder.update, key=name)
        return holder

    def serve(self, service: Service[Req, Rep], handler: Callable[[Req], Rep], **parts: str) -> str:
        check_port(self.ports, "serves", service)
        key = service.key(self.ns, **parts)

        def answer(payload: bytes, attachment: bytes | None = None, asked: str = "") -> Rep:
            try:
                request = codec.decode(service.request, payload)
            except (msgspec.DecodeError, msgspec.ValidationError) as exc:
                raise ServiceError(f"{key}: bad request: {exc}", "bad_request") from exc
            try:
                with caller.handling(attachment, asked):  # who asks, as the real node records
                    return handler(request)
            except ValueError as exc:
                raise ServiceError(f"{key}: {exc}", "bad_request") from exc

        self.bus._services[key] = answer
        return key

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
        """Ask the node serving ``service`` on the bus, synchronously; ``attachment`` as the
        real call's (e.g. :func:`~dronewrapper.runtime.caller.commander_attachment`)."""
        check_port(self.ports, "calls", service)
        key = service.key(ns or self.ns, **parts)
        answer = self.bus._services.get(key)
        if answer is None:
            waited = min(timeout, ROUTE_WAIT_S)  # as long as a real call asks an absent server
            raise ServiceUnavailable(
                f"no reply from {key}: nothing serves it on the fake bus", waited
            )
        reply = answer(codec.encode(request), attachment, caller.bound_key(key, self.bound_name))
        return codec.decode(service.reply, codec.encode(reply))
