"""Node: a process's Zenoh session with typed publishers, inputs, services and a clean exit.

    with Node("perception", options) as node:
        detections = node.publisher(registry.DETECTIONS)
        frames = node.latest(registry.IMAGE_RAW, camera="cam_frontal")
        node.announce()                     # liveliness token: "ready"
        rate = Ratekeeper(30, stop=node.stop_event, clock=node.clock)
        while rate.sleep():
            ...

Every subscriber decodes at the boundary with the registry's type; bytes that do not decode are
counted (``node.decode_errors``) and logged, and the subscriber keeps working. Services are
Zenoh queryables whose handlers run on a worker pool; a bad request gets an error reply that says
what is wrong, never silence. SIGINT and SIGTERM set ``stop_event``; the session is always
closed on exit (an unclosed session can hang the interpreter).

A node with a certificate (``options.identity``) sends its calls and the topics an operator
publishes on keys bound to its certificate's name (``KEY/@by/NAME``, see
:mod:`dronewrapper.runtime.caller`); every node serves, and subscribes to those topics, on the
bound keys too, and a handler's commander is the bound name.

A Node satisfies the node contract (:class:`~dronewrapper.runtime.contract.NodeApi`): the bus
and the clock (``node.clock``, the real clocks unless given another); with ``ports`` it refuses
what its process does not declare (:mod:`dronewrapper.runtime.ports`).

Size: the contract's every verb (publish, subscribe, serve, call) and the lifecycle, one class
on one session.
"""

from __future__ import annotations

import contextlib
import logging
import os
import signal
import threading
import time
from collections import Counter
from collections.abc import Callable
from typing import TYPE_CHECKING, Any, TypeVar

import msgspec
import zenoh

from dronewrapper.msgs import codec
from dronewrapper.msgs.registry import ALIVE, Service, Topic
from dronewrapper.msgs.std import ErrorReply
from dronewrapper.runtime import caller
from dronewrapper.runtime.clock import REAL, Clock
from dronewrapper.runtime.delivery import SampleErrors, decoding
from dronewrapper.runtime.errors import ServiceError
from dronewrapper.runtime.latest import Latest
from dronewrapper.runtime.options import LOW_LATENCY_MAX_BYTES, ZenohOptions
from dronewrapper.runtime.ports import Ports
from dronewrapper.runtime.ports import check as check_port
from dronewrapper.runtime.publisher import Publisher
from dronewrapper.runtime.qos import qos_for
from dronewrapper.runtime.session import (
    ERROR_ENCODING,
    alive_services,
    call_service,
    encoding_for,
    open_session,
)
from dronewrapper.runtime.shm import remove_stale_segments
from dronewrapper.runtime.shm_put import ShmWriter
from dronewrapper.runtime.stopping import Stopping
from dronewrapper.runtime.thread_state import KEPT
from dronewrapper.security import acl  # a module: acl imports the runtime's caller

if TYPE_CHECKING:
    from concurrent.futures import ThreadPoolExecutor

T = TypeVar("T")
Req = TypeVar("Req")
Rep = TypeVar("Rep")

log = logging.getLogger("dronewrapper.runtime")

__all__ = ["Node", "Publisher", "alive_services", "call_service", "encoding_for", "open_session"]


class Node(Stopping):
    """One process's presence on the Zenoh network (use as a context manager).

    Args:
        name: default process name (the liveliness token is ``{ns}/alive/{name}``);
            ``options.name`` overrides it.
        options: session options (mode, endpoints, namespace).
        handle_signals: turn SIGINT/SIGTERM into ``stop_event`` (main thread only).
        linger: seconds to wait before closing so the last messages leave (Zenoh drops
            messages still queued when a session closes).
        open_timeout: seconds to keep trying to open the session.
        clock: the process's time (ages, waits, stamps); the real clocks by default.
        direct_callbacks: run subscriber callbacks on Zenoh's own thread (no Python thread
            per subscriber; keep them short): for a library inside someone else's process,
            where no thread of ours may hold up the interpreter's exit.
        session: an open session to share (several services in one process, see
            :mod:`dronewrapper.runtime.host`): this node declares on it and undeclares what it
            declared when it closes, and leaves the session open for the others.
        ports: what this process may publish, subscribe to, serve and call
            (:mod:`dronewrapper.runtime.ports`); anything else raises PortRefused. None: all.
    """

    def __init__(
        self,
        name: str,
        options: ZenohOptions | None = None,
        *,
        handle_signals: bool = True,
        linger: float = 0.05,
        open_timeout: float = 10.0,
        clock: Clock = REAL,
        direct_callbacks: bool = False,
        session: zenoh.Session | None = None,
        ports: Ports | None = None,
    ) -> None:
        self.ports = ports
        self.options = options or ZenohOptions()
        self.clock = clock
        self._direct = direct_callbacks
        self.name = self.options.name or name
        self.ns = self.options.namespace
        self.log = logging.getLogger(self.name)
        self.stop_event = threading.Event()
        self.sample_errors = SampleErrors(self.log, clock=clock)
        self.decode_errors: Counter[str] = self.sample_errors.decode
        self.callback_errors: Counter[str] = self.sample_errors.callback
        self._linger = linger
        self._declared: list[Any] = []
        self._token: Any = None
        self._pool: ThreadPoolExecutor | None = None  # made by the first serve()
        self._closed = False
        self._old_handlers: dict[int, Any] = {}
        self._parent_pid = os.getppid()
        self.shm_writer = ShmWriter() if self.options.shared_memory else None
        """Writes large messages (images) straight into Zenoh shared memory; None when off."""
        self.bound_name = caller.bound_name(self.options)
        """The certificate's name this node's commands are bound to ("" without identity)."""
        if handle_signals and threading.current_thread() is threading.main_thread():
            for sig in (signal.SIGINT, signal.SIGTERM):
                self._old_handlers[sig] = signal.signal(sig, self._on_signal)
        self._owns_session = session is None
        self.session = session or open_session(self.options, timeout=open_timeout)

    # ---- lifecycle (``with``, ``stopping`` and ``stop``: Stopping's) ----

    def _on_signal(self, signum: int, _frame: object) -> None:
        """First SIGINT/SIGTERM: stop cleanly. A second one: exit at once (code 128 + signum).

        Except when this process was orphaned: a parent-death signal (``prctl``
        PR_SET_PDEATHSIG, which the launcher sets) is repeated once for every thread of the
        dying parent, so repeats then are not a person insisting, and the clean stop (say, a
        controller landing on exit) goes on. "At once" is ``os._exit``: raising SystemExit in
        the middle of closing Zenoh can leave its callback threads parked and the interpreter
        waiting for them forever.
        """
        name = signal.Signals(signum).name
        if not self.stop_event.is_set():
            self.log.info("%s received, stopping", name)
            self.stop_event.set()
        elif os.getppid() != self._parent_pid:
            self.log.debug("%s repeated after the parent died; still stopping", name)
        else:
            self.log.warning("second %s: exiting now", name)
            logging.shutdown()
            os._exit(128 + signum)

    def sleep(self, seconds: float) -> bool:
        """Sleep unless stopped; False if a stop was requested."""
        return not self.clock.wait(self.stop_event, seconds)

    def spin(self) -> None:
        """Block until a stop is requested."""
        while not self.clock.wait(self.stop_event, 0.5):
            pass

    def announce(self) -> None:
        """Declare the liveliness token ``{ns}/alive/{name}``: this process is ready."""
        if self._token is None:
            self._token = self.session.liveliness().declare_token(
                ALIVE.key(self.ns, service=self.name)
            )

    @property
    def announced(self) -> bool:
        """True once :meth:`announce` declared the liveliness token."""
        return self._token is not None

    def alive_services(self, ns: str = "*", timeout: float = 1.0) -> set[str]:
        """The liveliness keys (``ns/alive/name``) present now, in ``ns`` or all."""
        return alive_services(self.session, ns, timeout)

    def linked(self) -> bool:
        """True while the session reaches a router or a peer."""
        try:
            info = self.session.info
            return bool(list(info.routers_zid()) or list(info.peers_zid()))
        except zenoh.ZError:
            return False

    def close(self) -> None:
        """Withdraw the token, undeclare everything and close the session (idempotent)."""
        if self._closed:
            return
        self._closed = True
        self.stop_event.set()
        if self._pool is not None:
            self._pool.shutdown(wait=True, cancel_futures=True)
        if self._linger > 0:
            time.sleep(self._linger)
        try:
            if self._token is not None:
                self._token.undeclare()
            for entity in reversed(self._declared):
                with contextlib.suppress(Exception):  # already gone with the session
                    entity.undeclare()
        finally:
            if self._owns_session:
                self.session.close()
            for sig, handler in self._old_handlers.items():
                signal.signal(sig, handler)
            remove_stale_segments()

    # ---- publish / subscribe ----

    def publisher(
        self,
        topic: Topic[T],
        *,
        key: str | None = None,
        qos: dict[str, Any] | None = None,
        **parts: str,
    ) -> Publisher[T]:
        """A typed publisher for ``topic`` in this node's namespace (``parts`` fill the key).

        Its Zenoh options come from the topic's transport class in the registry (see
        :mod:`dronewrapper.runtime.qos`); ``qos`` overrides single options.
        """
        check_port(self.ports, "publishes", topic)
        options = {**qos_for(topic), **(qos or {})}
        shm = self.shm_writer if "data" in getattr(topic.type, "__struct_fields__", ()) else None
        max_bytes = LOW_LATENCY_MAX_BYTES if self.options.low_latency else None
        pub = Publisher(
            self.session,
            acl.commanding_key(topic, key or topic.key(self.ns, **parts), self.bound_name),
            topic.type,
            shm=shm,
            max_bytes=max_bytes,
            **options,
        )
        self._declared.append(pub)
        return pub

    def subscribe(
        self,
        topic: Topic[T],
        callback: Callable[[T], None],
        *,
        key: str | None = None,
        keyed: bool = False,
        direct: bool | None = None,
        **parts: str,
    ) -> zenoh.Subscriber:
        """Call ``callback(msg)`` for every decodable sample on ``topic``.

        ``key`` may be a key expression with wildcards instead of this node's namespace;
        ``keyed``: call ``callback(key, msg)`` with each sample's concrete key instead;
        ``direct``: run the callback on the thread that delivers the sample (for this
        session's own puts, the putting thread, before ``put`` returns; keep it short),
        None: the node's ``direct_callbacks``.
        Undecodable samples are counted in ``decode_errors`` and logged; exceptions in the
        callback are counted in ``callback_errors`` and logged; neither ends the subscription.
        """
        check_port(self.ports, "subscribes", topic)
        keyexpr = key or topic.key(self.ns, **parts)
        deliver = decoding(topic.type, callback, self.sample_errors, keyed=keyed)

        inline = self._direct if direct is None else direct

        def on_sample(sample: zenoh.Sample) -> None:
            if inline:  # on a Zenoh thread: keep its Python thread state (see thread_state)
                KEPT.keep()
            deliver(str(sample.key_expr), sample.payload.to_bytes(), sample.attachment)

        handler = zenoh.handlers.Callback(on_sample, indirect=not inline)
        sub = self.session.declare_subscriber(keyexpr, handler)
        self._declared.append(sub)
        if acl.is_commanded(topic):  # the same commands from certified commanders
            bound = zenoh.handlers.Callback(on_sample, indirect=not inline)
            self._declared.append(self.session.declare_subscriber(caller.any_bound(keyexpr), bound))
        return sub

    def latest(self, topic: Topic[T], *, key: str | None = None, **parts: str) -> Latest[T]:
        """Subscribe to ``topic`` and keep only its newest value and its age (node clock)."""
        name = key or topic.key(self.ns, **parts)
        holder: Latest[T] = Latest(name=name, clock=self.clock)
        self.subscribe(topic, holder.update, key=name)
        return holder

    # ---- services ----

    def serve(
        self,
        service: Service[Req, Rep],
        handler: Callable[[Req], Rep],
        **parts: str,
    ) -> zenoh.Queryable:
        """Answer ``service`` requests with ``handler(request) -> reply`` on a worker thread.

        A request that does not decode, or a handler raising ValueError or ServiceError, gets an
        error reply (ErrorReply) saying what is wrong; the queryable keeps serving.
        """
        check_port(self.ports, "serves", service)
        key = service.key(self.ns, **parts)
        dec = codec.decoder(service.request)
        reply_encoding = encoding_for(service.reply)
        if self._pool is None:  # a node that serves nothing starts no workers
            from concurrent.futures import ThreadPoolExecutor

            self._pool = ThreadPoolExecutor(max_workers=4, thread_name_prefix=f"{self.name}-srv")
        pool = self._pool

        def answer(query: zenoh.Query) -> None:
            try:
                if query.payload is None:
                    raise ServiceError(
                        f"{key}: empty request, expected a {service.request.__name__}",
                        "bad_request",
                    )
                try:
                    request = dec.decode(query.payload.to_bytes())
                except (msgspec.DecodeError, msgspec.ValidationError) as exc:
                    self.decode_errors[key] += 1
                    raise ServiceError(
                        f"{key}: bad {service.request.__name__} request: {exc}", "bad_request"
                    ) from exc
                asked = str(query.key_expr)
                with caller.handling(query.attachment, asked):
                    reply = handler(request)
                answered = caller.bound_key(key, caller.split_bound(asked)[1])
                query.reply(answered, codec.encode(reply), encoding=reply_encoding)
            except ServiceError as exc:
                err = ErrorReply(message=exc.message, code=exc.code)
                query.reply_err(codec.encode(err), encoding=ERROR_ENCODING)
            except ValueError as exc:
                err = ErrorReply(message=f"{key}: {exc}", code="bad_request")
                query.reply_err(codec.encode(err), encoding=ERROR_ENCODING)
            except Exception as exc:
                self.log.exception("service %s failed", key)
                err = ErrorReply(message=f"{key}: internal error: {exc}", code="internal")
                query.reply_err(codec.encode(err), encoding=ERROR_ENCODING)
            finally:
                query.drop()

        def on_query(query: zenoh.Query) -> None:
            try:
                pool.submit(answer, query)
            except RuntimeError:  # pool shut down: the node is closing
                query.drop()

        queryable = self.session.declare_queryable(key, on_query)
        self._declared.append(queryable)
        self._declared.append(self.session.declare_queryable(caller.any_bound(key), on_query))
        return queryable

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
        """Send ``request`` to ``service`` and return the reply (``attachment``: see
        :func:`call_service`).

        Raises:
            ServiceError: the server answered with an error reply (its message says why).
            ServiceUnavailable: nobody answered within ``timeout`` seconds.
            ServiceTimeout: (a ServiceUnavailable) Zenoh ended the query at its timeout.
        """
        check_port(self.ports, "calls", service)
        return call_service(
            self.session,
            service,
            request,
            ns=ns or self.ns,
            timeout=timeout,
            attachment=attachment,
            bound_to=self.bound_name,
            **parts,
        )
