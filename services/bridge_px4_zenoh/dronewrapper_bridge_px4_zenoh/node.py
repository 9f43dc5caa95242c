"""The bridge process: PX4's own Zenoh (uORB topics in rmw_zenoh's format) <-> the
MAVROS-equivalent keys every bridge presents (see README.md).

Only I/O here. Everything the bridge decides is in
:class:`~dronewrapper_bridge_px4_zenoh.core.Px4ZenohCore` (pure); the wiring every bridge shares
(driver, publishers, services, setpoints, the lease, the tick loop) is
:class:`~dronewrapper_bridge_base.bridge_node.BridgeNode`. PX4's samples arrive on one
subscriber per topic the bridge reads (``<domain>/fmu/out/<topic>/*/*``, any version: a
subscriber to all of ``/fmu/out`` would also take sensor_combined (~245 Hz) and the rest, and a
slow reader pushes back on PX4); those of the high-rate topics (:data:`~.core.COALESCED`,
~100-230 Hz each) keep only their newest sample, in Zenoh (a ring of one: no Python runs per
sample), which the stream loop moves to the core's inbox (:mod:`.newest`) before each tick;
the others (a few Hz) feed the core from their callbacks; and its tokens on a liveliness
subscriber (with history), all on the node's own session: the router PX4's zenoh-pico dials is
the project's. What the core writes to ``/fmu/in`` is CDR-encoded with rmw_zenoh's attachment
(:mod:`dronewrapper_ros2_codec`, the ROS 2 codec) on the exact key of the bridge's version,
and the bridge announces its publishers with liveliness tokens as an rmw_zenoh node would.
Time is the node's clock alone (the core starts at it, the driver and the stream loop read
it, the attachment's stamp is its wall time). Threads: Zenoh callbacks (samples, tokens,
setpoints), a stream loop at ``stream_rate_hz`` (the high-rate samples collected, then the
core's tick) and the node's service workers.
"""

from __future__ import annotations

import contextlib
import hashlib
import itertools
import logging
import threading
from collections.abc import Callable
from typing import Any

import zenoh

from dronewrapper.msgs import registry
from dronewrapper.msgs.registry import Service
from dronewrapper.runtime import Node
from dronewrapper.runtime.qos import class_qos
from dronewrapper_bridge_base.bridge_node import (
    BRIDGE_PUBLISHED,
    BridgeNode,
    Operation,
    bridge_ports,
)
from dronewrapper_bridge_px4_zenoh import envelope_rules as rules
from dronewrapper_bridge_px4_zenoh import flight
from dronewrapper_bridge_px4_zenoh import operations as ops
from dronewrapper_bridge_px4_zenoh import topics as t
from dronewrapper_bridge_px4_zenoh.config import Config
from dronewrapper_bridge_px4_zenoh.core import COALESCED, Outbox, Px4ZenohCore
from dronewrapper_ros2_codec import attachment, cdr
from dronewrapper_ros2_codec.names import PUBLISHER, NodeName, parse_endpoint, qos_text

log = logging.getLogger("bridge_px4_zenoh")

PUBLISHED = (*BRIDGE_PUBLISHED, registry.GLOBAL_POSITION)
SERVICES: dict[Service[Any, Any], Operation] = {
    registry.FLIGHT_TAKEOFF: flight.takeoff_to,
    registry.FLIGHT_LAND: flight.land_here,
    registry.FLIGHT_GOTO: flight.goto_point,
    registry.FLIGHT_RETURN: flight.return_home,
    registry.ARMING: ops.arming,
    registry.TAKEOFF: ops.takeoff,
    registry.LAND: ops.land,
    registry.SET_MODE: ops.set_mode,
}
GUARDED = ((registry.ENVELOPE_SET, rules.set_envelope, "envelope"),)
"""(service, operation, the command-lease action that guards it)."""
PORTS = bridge_ports("bridge_px4_zenoh", PUBLISHED, SERVICES, GUARDED)
"""What this bridge publishes, subscribes to and serves on the registry's keys
(:mod:`dronewrapper.runtime.ports`); PX4's own ``fmu/`` keys are declared on the session."""
WRITTEN = (t.OFFBOARD_MODE, t.TRAJECTORY, t.COMMAND)
WRITE_QOS = class_qos(registry.COMMAND)
"""How the writes to PX4 travel: as commands (blocking, express, interactive priority). With
Zenoh's default (droppable, batched) the router was measured to stop forwarding them to PX4's
zenoh-pico for over 1 s while they kept reaching it (PX4 left OFFBOARD: offboard signal lost,
docs/px4_zenoh.md); a blocking put is never dropped on the way."""
NODE_NAME = "dronewrapper_bridge_px4_zenoh"


def gid_of(token: str) -> bytes:
    """A 16-byte id for an endpoint, derived from its token (receivers only carry it)."""
    return hashlib.blake2b(token.encode(), digest_size=attachment.GID_SIZE).digest()


class Writer:
    """The bridge's publisher of one ``/fmu/in`` topic, on the key of its version."""

    def __init__(
        self, publisher: Any, topic: t.Px4Topic, gid: bytes, wall: Callable[[], float]
    ) -> None:
        self.publisher, self.topic, self.gid, self.wall = publisher, topic, gid, wall
        self._seq = itertools.count(1)

    def __call__(self, value: dict[str, Any]) -> None:
        payload = cdr.encode(self.topic.type_name, value)
        meta = attachment.pack(next(self._seq), int(self.wall() * 1e9), self.gid)
        self.publisher.put(payload, attachment=meta)


class Bridge(BridgeNode[Px4ZenohCore]):
    """The core wired to one Node and the Zenoh session PX4 shares (the node's own, or
    ``session`` in tests)."""

    def __init__(self, node: Node, config: Config, session: Any = None) -> None:
        publishers = {topic: node.publisher(topic) for topic in PUBLISHED}
        super().__init__(node, Px4ZenohCore(config, node.clock.monotonic()), publishers, log)
        self.config = config
        self.session = session if session is not None else node.session
        self.writers: dict[str, Writer] = {}
        self._declared: list[Any] = []
        self._rings: list[tuple[str, Any]] = []  # (topic name, its ring subscriber)

    def start(self) -> list[threading.Thread]:
        """Declare PX4's side and the services (:meth:`declare`); start the stream loop."""
        self.declare()
        rate = self.config.stream_rate_hz
        thread = self.node.clock.thread(lambda: self.tick_loop(rate, "stream"), "px4z-stream")
        thread.start()
        return [thread]

    def declare(self) -> None:
        """Declare PX4's side (the bridge's tokens and publishers, the subscribers to PX4's
        samples and tokens) and serve the services."""
        domain = self.config.domain
        me = NodeName(domain, str(self.session.zid()), 0, "/", NODE_NAME)
        liveliness = self.session.liveliness()
        self._declared.append(liveliness.declare_token(me.token()))
        for entity_id, topic in enumerate(WRITTEN, start=1):
            key = self.core.versions.key(topic)
            token = me.endpoint_token(
                entity_id,
                PUBLISHER,
                topic.name,
                topic.type_name,
                self.core.versions.expected[topic.name],
                qos_text(),
            )
            self._declared.append(liveliness.declare_token(token))
            publisher = self.session.declare_publisher(key, **WRITE_QOS)
            self._declared.append(publisher)
            self.writers[topic.name] = Writer(publisher, topic, gid_of(token), self.node.clock.time)
        for topic in t.TOPICS:  # only those it reads: PX4 publishes ~50 topics
            if topic.direction == t.OUT:
                key = topic.any_version(domain)
                if topic in COALESCED:  # the newest sample kept in Zenoh, no Python per sample
                    ring = self.session.declare_subscriber(key, zenoh.handlers.RingChannel(1))
                    self._rings.append((topic.name, ring))
                    self._declared.append(ring)
                else:
                    sub = self.session.declare_subscriber(key, self.on_px4_sample)
                    self._declared.append(sub)
        self._declared.append(
            liveliness.declare_subscriber(f"@ros2_lv/{domain}/**", self.on_token, history=True)
        )
        self.serve(SERVICES, GUARDED)

    # ---- PX4's side

    def on_px4_sample(self, sample: Any) -> None:
        """A sample on ``<domain>/fmu/out/**``."""
        self.driver.feed(self.core.on_data, str(sample.key_expr), sample.payload.to_bytes())

    def collect(self) -> None:
        """Move each high-rate topic's newest sample from its subscriber's ring (one sample,
        replaced in Zenoh as PX4 publishes) into the core's inbox, for the tick to decode."""
        put = self.core.inbox.put
        for name, ring in self._rings:
            sample = ring.try_recv()
            if sample is not None:
                put(name, str(sample.key_expr), sample.payload.to_bytes())

    def tick_once(self, what: str) -> None:
        """One stream tick: PX4's newest high-rate samples collected, then the core's tick."""
        try:
            self.collect()
        except Exception:
            self.node.callback_errors[what] += 1
            self.log.exception("%s collect error", what)
        super().tick_once(what)

    def on_token(self, sample: Any) -> None:
        """A liveliness token appearing (a vanished one changes nothing the bridge decodes)."""
        if sample.kind == zenoh.SampleKind.DELETE:
            return
        endpoint = parse_endpoint(str(sample.key_expr))
        if endpoint is not None:
            self.driver.feed(self.core.on_token, endpoint)

    def send(self, out: Outbox) -> None:
        """Write the core's px4_msgs values to PX4; count its dropped inputs."""
        for topic, value in out.writes:
            self.writers[topic.name](value)
        for name in out.errors:
            self.node.callback_errors[name] += 1

    def close(self) -> None:
        for entity in reversed(self._declared):
            with contextlib.suppress(zenoh.ZError):
                entity.undeclare()


def run(node: Node, config: Config) -> int:
    """The service body: start the bridge, announce readiness, run until stopped."""
    bridge = Bridge(node, config)
    threads = bridge.start()
    node.announce()
    log.info("bridge_px4_zenoh ready (PX4 domain %d, namespace %s)", config.domain, node.ns)
    try:
        node.spin()
    finally:
        for thread in threads:
            thread.join(timeout=2.0)
        bridge.close()
    return 0


__all__ = ["Bridge", "run"]
