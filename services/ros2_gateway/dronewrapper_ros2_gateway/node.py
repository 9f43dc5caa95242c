"""The gateway process: each drone's keys as ROS 2 entities on rmw_zenoh's wire (README.md).

Only I/O here; the formats are :mod:`dronewrapper_ros2_codec`'s and the table is :mod:`entities`.
Per drone it holds a node token (``/<ns>/<node_name>``) and, per entity, an endpoint token
and one Zenoh declaration on the ROS 2 key:

- out (telemetry, images): our sample -> CDR -> ``put`` with the rmw_zenoh attachment (cameras
  are subscribed only while a ROS 2 subscriber matches);
- in (``setpoint_raw/local``): CDR -> PositionTarget -> the project's setpoint rules -> our
  setpoint key, under the gateway's commander name and with the ROS 2 publisher's send time,
  so the bridge's lease, late-setpoint rule and failsafe apply;
- services: CDR request -> our request -> the bridge's service -> its reply as the ROS 2
  response; a refusal (lease, bad request) is ``success: false`` with MAV_RESULT_DENIED, no
  reply from the bridge is MAV_RESULT_FAILED (ROS 2 clients get no error channel).

It also reads every ROS 2 endpoint's token on its domain and logs each type disagreement with
one of its own entities (:mod:`dronewrapper_ros2_codec.mismatch`). :func:`run` is the gateway as a
process of its own; :mod:`dronewrapper_ros2_gateway.hosted` runs the same :class:`Gateway`
inside a bridge.

Size: one class holds every declaration of both directions, which share its ids, tokens and
close; the formats, rules and checks are in the modules named.
"""

from __future__ import annotations

import contextlib
import hashlib
import itertools
import logging
import math
import threading
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from typing import Any

import zenoh

from dronewrapper.msgs import registry
from dronewrapper.msgs.mavros import MAV_RESULT_DENIED, MAV_RESULT_FAILED
from dronewrapper.runtime.caller import commander_attachment
from dronewrapper.runtime.clock import Clock
from dronewrapper.runtime.contract import NodeApi
from dronewrapper.runtime.errors import ServiceError, ServiceUnavailable
from dronewrapper.runtime.node import Node, open_session
from dronewrapper.runtime.options import ZenohOptions
from dronewrapper.runtime.qos import qos_for
from dronewrapper_bridge_base.setpoint_limits import SetpointError, validate
from dronewrapper_ros2_codec import attachment, cdr
from dronewrapper_ros2_codec.convert import (
    position_target,
    refusal_of,
    request_of,
    response_of,
    to_ros,
)
from dronewrapper_ros2_codec.mismatch import disagreements
from dronewrapper_ros2_codec.names import (
    ADMIN,
    PUBLISHER,
    SERVICE,
    SUBSCRIBER,
    Endpoint,
    NodeName,
    parse_endpoint,
    topic_key,
)
from dronewrapper_ros2_codec.typehash import type_hash
from dronewrapper_ros2_gateway.config import Config
from dronewrapper_ros2_gateway.entities import IN, OUT, SERVE, Entity, selected
from dronewrapper_ros2_gateway.presence import PresenceWatch

log = logging.getLogger("ros2_gateway")

DEFAULT_COMMANDER = "ros2_gateway"


@dataclass(frozen=True)
class WideBounds:
    """The gateway's own check takes any value the project's rules could ever accept; the
    bridge's limits decide (it checks every setpoint again)."""

    max_distance: float = 1e6
    min_altitude: float = -1e4
    max_altitude: float = 1e5
    max_horizontal_speed: float = 1e3
    max_vertical_speed: float = 1e3
    max_yaw_rate: float = 1e3


def gid_of(token: str) -> bytes:
    """A 16-byte id for an endpoint, derived from its token (as rmw_zenoh derives its own;
    receivers only carry it)."""
    return hashlib.blake2b(token.encode(), digest_size=attachment.GID_SIZE).digest()


def _ns(clock: Clock) -> int:
    """``clock``'s Unix time in integer nanoseconds (a ROS 2 attachment's stamp)."""
    return round(clock.time() * 1e9)


class Outgoing:
    """Our samples of one key, republished on its ROS 2 key, each attachment stamped with
    ``clock`` (the node's)."""

    def __init__(self, publisher: Any, ros_type: str, gid: bytes, clock: Clock) -> None:
        self.publisher = publisher
        self.clock = clock
        self.ros_type = ros_type
        self.gid = gid
        self.count = 0
        self._seq = itertools.count(1)
        self.subscription: Any = None

    def __call__(self, msg: Any) -> None:
        payload = cdr.encode(self.ros_type, to_ros(msg))
        meta = attachment.pack(next(self._seq), _ns(self.clock), self.gid)
        self.publisher.put(payload, attachment=meta)
        self.count += 1

    def wanted(self) -> bool:
        try:
            return bool(self.publisher.matching_status.matching)
        except zenoh.ZError:
            return False


def commander_name(config: Config, identity: str) -> str:
    """The name the gateway commands under: ``config.commander``, else the name of
    ``identity`` (a name or a path to ``NAME.crt``), else :data:`DEFAULT_COMMANDER`."""
    name = config.commander or identity or DEFAULT_COMMANDER
    return name.rsplit("/", 1)[1].removesuffix(".crt") if "/" in name else name


class Gateway:
    """The gateway's declarations on one node and one ROS 2 session (see the module doc).

    Args:
        node: the bus our keys live on.
        config: what it presents.
        ros_session: the Zenoh session of the ROS 2 entities.
        commander: the name its setpoints and commands carry (:func:`commander_name`).
        inline: take our telemetry with direct callbacks: on the node's own session, each of
            its puts is converted and sent on to ROS 2 on the putting thread, before the put
            returns (:mod:`dronewrapper_ros2_gateway.hosted`); cameras stay on Zenoh's
            callback threads either way.
    """

    def __init__(
        self,
        node: NodeApi,
        config: Config,
        ros_session: zenoh.Session,
        *,
        commander: str = DEFAULT_COMMANDER,
        inline: bool = False,
    ) -> None:
        self.node = node
        self.config = config
        self.session = ros_session
        self.zid = str(ros_session.zid())
        self.commander = commander
        self.inline = inline
        self.refused: dict[str, int] = {}
        self.declared: dict[str, int] = {}  # ROS 2 endpoint kind (MP, MS, SS) -> how many
        self.mismatches: list[str] = []
        self.outgoing: list[tuple[str, Entity, Outgoing]] = []
        self._declared: list[Any] = []
        self._tokens: list[Any] = []
        self._ids = itertools.count(0)  # node and entity ids: one counter, as rmw_zenoh's
        self._endpoints: dict[str, Endpoint] = {}
        self._lock = threading.Lock()
        self._pool = ThreadPoolExecutor(max_workers=4, thread_name_prefix="ros2-srv")
        self._last_refusal_log = -math.inf
        self._setpoint_publishers: dict[str, Any] = {}

    # ---- declarations ----

    def start(self) -> None:
        """Declare every drone's entities, then watch the ROS 2 graph's tokens."""
        for ns in self.config.drones or [self.node.ns]:
            self._declare_drone(ns)
        watched = f"{ADMIN}/{self.config.domain_id}/**"
        self._declared.append(
            self.session.liveliness().declare_subscriber(watched, self._on_token, history=True)
        )

    def _token(self, token: str) -> None:
        self._tokens.append(self.session.liveliness().declare_token(token))
        endpoint = parse_endpoint(token)
        if endpoint is not None:
            with self._lock:
                self._endpoints[token] = endpoint

    def _declare_drone(self, ns: str) -> None:
        ros_node = NodeName(
            self.config.domain_id, self.zid, next(self._ids), f"/{ns}", self.config.node_name
        )
        self._token(ros_node.token())
        for entity in selected(self.config.keys):
            key = topic_key(
                self.config.domain_id,
                entity.ros_name(ns),
                entity.ros_type,
                type_hash(entity.ros_type),
            )
            kind = {OUT: PUBLISHER, IN: SUBSCRIBER, SERVE: SERVICE}[entity.direction]
            token = ros_node.endpoint_token(
                next(self._ids),
                kind,
                entity.ros_name(ns),
                entity.ros_type,
                type_hash(entity.ros_type),
                entity.qos,
            )
            if entity.direction == OUT:
                self._declare_out(ns, entity, key, gid_of(token))
            elif entity.direction == IN:
                self._declare_in(ns, key)
            else:
                self._declare_service(ns, entity, key)
            self._token(token)
            self.declared[kind] = self.declared.get(kind, 0) + 1
            log.debug("%s %s", kind, key)

    def _declare_out(self, ns: str, entity: Entity, key: str, gid: bytes) -> None:
        # the registry's transport class (priority, drop under congestion); telemetry leaves
        # at once rather than waiting for a batch, as it arrived
        options = qos_for(entity.registry_entry)
        options["express"] = entity.registry_entry.transport != registry.STREAM
        publisher = self.session.declare_publisher(key, **options)
        self._declared.append(publisher)
        out = Outgoing(publisher, entity.ros_type, gid, self.node.clock)
        self.outgoing.append((ns, entity, out))
        if entity.registry_entry.transport != registry.STREAM:
            out.subscription = self._subscribe(ns, entity, out)

    def _subscribe(self, ns: str, entity: Entity, out: Outgoing) -> Any:
        direct = self.inline and entity.registry_entry.transport != registry.STREAM
        return self.node.subscribe(entity.registry_entry, out, key=entity.key(ns), direct=direct)

    def follow_demand(self) -> None:
        """Subscribe to each camera while a ROS 2 subscriber wants it, and only then."""
        for ns, entity, out in self.outgoing:
            if entity.registry_entry.transport != registry.STREAM:
                continue
            wanted = out.wanted()
            if wanted and out.subscription is None:
                out.subscription = self._subscribe(ns, entity, out)
                log.info("a ROS 2 subscriber wants %s: forwarding it", entity.key(ns))
            elif not wanted and out.subscription is not None:
                out.subscription.undeclare()
                out.subscription = None

    def _declare_in(self, ns: str, key: str) -> None:
        publisher = self.node.publisher(
            registry.SETPOINT_RAW_LOCAL, key=registry.SETPOINT_RAW_LOCAL.key(ns)
        )
        self._setpoint_publishers[ns] = publisher

        def on_sample(sample: zenoh.Sample) -> None:
            self.on_setpoint(ns, sample.payload.to_bytes(), _raw(sample.attachment))

        self._declared.append(self.session.declare_subscriber(key, on_sample))

    def _declare_service(self, ns: str, entity: Entity, key: str) -> None:
        def on_query(query: zenoh.Query) -> None:
            try:
                self._pool.submit(self._answer, ns, entity, query)
            except RuntimeError:  # shutting down
                query.drop()

        self._declared.append(self.session.declare_queryable(key, on_query, complete=True))

    # ---- traffic in ----

    def _refuse(self, what: str, reason: str) -> None:
        self.refused[what] = self.refused.get(what, 0) + 1
        now = self.node.clock.monotonic()
        if now - self._last_refusal_log >= 2.0:
            self._last_refusal_log = now
            log.warning("refused a ROS 2 %s (%d so far): %s", what, self.refused[what], reason)

    def on_setpoint(self, ns: str, payload: bytes, raw_attachment: bytes | None) -> bool:
        """One ROS 2 PositionTarget: forwarded under our commander name if it is well formed
        and passes the project's setpoint rules; else counted and dropped. True if forwarded.

        Its send time for the bridges' late-setpoint rule is the ROS 2 publisher's source
        timestamp (rmw_zenoh's attachment), so a burst held on the ROS 2 side's link is refused
        as an SDK app's would be; our clock's now when the publisher gave none (0)."""
        try:
            meta = attachment.unpack(raw_attachment)
            target = position_target(cdr.decode("mavros_msgs/msg/PositionTarget", payload))
            validate(target, WideBounds())
        except (attachment.AttachmentError, cdr.CdrError, SetpointError) as exc:
            self._refuse("setpoint", str(exc))
            return False
        except (KeyError, TypeError, ValueError) as exc:
            self._refuse("setpoint", f"malformed PositionTarget: {exc}")
            return False
        sent = meta.timestamp_ns / 1e9 if meta.timestamp_ns > 0 else self.node.clock.time()
        self._setpoint_publishers[ns].put(
            target, attachment=commander_attachment(self.commander, sent)
        )
        return True

    def serve(self, ns: str, entity: Entity, payload: bytes | None) -> dict[str, Any]:
        """The ROS 2 response to one request on ``entity`` of drone ``ns``: the bridge's reply,
        or a refusal."""
        service = entity.registry_entry
        try:
            if payload is None:
                raise ValueError("empty request")
            value = cdr.decode(f"{entity.ros_type}_Request", payload)
            request = request_of(service.request, value)
            reply = self.node.call(
                service,
                request,
                ns=ns,
                timeout=self.config.service_timeout_s,
                attachment=commander_attachment(self.commander),
            )
        except ServiceUnavailable as exc:
            self._refuse(entity.name, str(exc))
            return refusal_of(service.request, MAV_RESULT_FAILED)
        except ServiceError as exc:
            self._refuse(entity.name, exc.message)
            return refusal_of(service.request, MAV_RESULT_DENIED)
        except (cdr.CdrError, KeyError, TypeError, ValueError) as exc:
            self._refuse(entity.name, f"bad request: {exc}")
            return refusal_of(service.request, MAV_RESULT_DENIED)
        return response_of(reply)

    def _answer(self, ns: str, entity: Entity, query: zenoh.Query) -> None:
        try:
            try:
                meta = attachment.unpack(_raw(query.attachment))
            except attachment.AttachmentError:
                meta = attachment.Attachment(0, 0, bytes(attachment.GID_SIZE))
            payload = query.payload.to_bytes() if query.payload is not None else None
            response = self.serve(ns, entity, payload)
            reply = cdr.encode(f"{entity.ros_type}_Response", response)
            back = attachment.pack(meta.sequence, _ns(self.node.clock), meta.gid)
            query.reply(query.key_expr, reply, attachment=back)
        except Exception:
            log.exception("answering %s failed", entity.name)
        finally:
            query.drop()

    # ---- the ROS 2 graph ----

    def _on_token(self, sample: zenoh.Sample) -> None:
        key = str(sample.key_expr)
        with self._lock:
            if sample.kind == zenoh.SampleKind.DELETE:
                self._endpoints.pop(key, None)
                return
            endpoint = parse_endpoint(key)
            if endpoint is None:
                return
            self._endpoints[key] = endpoint
            found = [d for d in disagreements(self._endpoints.values()) if d.involves(self.zid)]
        for problem in found:
            text = problem.describe()
            if text not in self.mismatches:
                self.mismatches.append(text)
                log.warning("%s", text)

    def close(self) -> None:
        self._pool.shutdown(wait=True, cancel_futures=True)
        for token in self._tokens:
            token.undeclare()
        for entity in reversed(self._declared):
            with contextlib.suppress(zenoh.ZError):
                entity.undeclare()


def _raw(value: Any) -> bytes | None:
    return None if value is None else value.to_bytes()


def ros_session_for(node: Node, config: Config) -> tuple[zenoh.Session, bool]:
    """The session the ROS 2 entities live on, and whether it is the gateway's own to close."""
    if not config.ros_connect:
        return node.session, False
    options = ZenohOptions(mode=config.ros_mode, connect=config.ros_connect, shared_memory=False)
    return open_session(options), True


def follow_demand_until_stopped(
    gateway: Gateway,
    done: threading.Event | None = None,
    tick: Callable[[], None] | None = None,
) -> None:
    """:meth:`Gateway.follow_demand` (and ``tick``) every ``image_check_s`` until the node
    stops (or ``done`` is set)."""
    node, period = gateway.node, gateway.config.image_check_s
    while not node.clock.wait(done or node.stop_event, period) and not node.stopping:
        gateway.follow_demand()
        if tick is not None:
            tick()


def log_started(gateway: Gateway, how: str) -> None:
    """Log, in one line, what the gateway presents, to which domain, under which commander
    name (each ROS 2 key at DEBUG)."""
    config = gateway.config
    counts = gateway.declared
    log.info(
        "ROS 2 domain %d: %s as %s (commander %r, %s): %d topics out, %d in, %d services "
        "(--log-level DEBUG lists their keys)",
        config.domain_id,
        ", ".join(config.drones or [gateway.node.ns]),
        config.node_name,
        gateway.commander,
        how,
        counts.get(PUBLISHER, 0),
        counts.get(SUBSCRIBER, 0),
        counts.get(SERVICE, 0),
    )


def run(node: Node, config: Config) -> int:
    """The gateway until stopped; the exit status."""
    session, own = ros_session_for(node, config)
    commander = commander_name(config, node.options.identity)
    gateway = Gateway(node, config, session, commander=commander)
    try:
        gateway.start()
        node.announce()
        log_started(gateway, "its own process")
        watch = PresenceWatch(node, config.drones or [node.ns], log.log)
        follow_demand_until_stopped(gateway, tick=watch.tick)
    finally:
        gateway.close()
        if own:
            session.close()
    return 0
