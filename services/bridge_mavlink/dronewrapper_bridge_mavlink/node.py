"""The bridge process: MAVLink autopilot <-> MAVROS-equivalent Zenoh keys (see README.md).

Only I/O here: the link, the ground-station forwarding, the threads. Everything the bridge
decides (the commander lease included) is in
:class:`~dronewrapper_bridge_mavlink.core.BridgeCore` (pure, time as an argument); the wiring
every bridge shares (driver, publishers, services, setpoints, tick loop) is
:class:`~dronewrapper_bridge_base.bridge_node.BridgeNode`. Threads: a receive loop (MAVLink in;
in a host, a UDP link's socket is read by the host's one loop thread instead,
:func:`~dronewrapper.runtime.host.shared_poller`), a stream loop at ``stream_rate_hz`` (the
core's tick: failsafe stream, our heartbeat, periodic samples; in a host, its one thread ticking
every hosted bridge, :func:`~dronewrapper.runtime.host.shared_ticker`), Zenoh callbacks
(setpoints forwarded at once) and the Node's service workers, which start an operation in the
core and wait until it is done. Time is the node's clock alone: the core starts at it, the
driver and the loops read and wait on it, and it makes the loops' threads (on a fake bus they
run in its virtual time).
"""

from __future__ import annotations

import logging
import math
import sys
import threading
from typing import Any

from pymavlink.dialects.v20 import common as mavlink

from dronewrapper.msgs import registry
from dronewrapper.msgs.link import LinkStatus
from dronewrapper.msgs.mavros import State
from dronewrapper.msgs.registry import Service
from dronewrapper.msgs.std import Header
from dronewrapper.runtime import Node
from dronewrapper.runtime.contract import NodeApi
from dronewrapper.runtime.host import shared_poller, shared_ticker
from dronewrapper.runtime.poller import NO_FILE
from dronewrapper.runtime.ports import Ports
from dronewrapper_bridge_base.bridge_node import (
    BRIDGE_PUBLISHED,
    BridgeNode,
    Operation,
    bridge_ports,
)
from dronewrapper_bridge_mavlink import actions, flight, missions, parameters, receive
from dronewrapper_bridge_mavlink import operations as ops
from dronewrapper_bridge_mavlink.config import Config
from dronewrapper_bridge_mavlink.core import BridgeCore, Outbox
from dronewrapper_bridge_mavlink.gcs import GcsForwarder, is_loopback, parse_gcs_url
from dronewrapper_bridge_mavlink.link import MavLink, network_exposure
from dronewrapper_bridge_mavlink.link_load import LinkLoad, LoadAlarm, Reconnects
from dronewrapper_bridge_mavlink.modes import canonical_mode
from dronewrapper_bridge_mavlink.wire import wanted_ids

log = logging.getLogger("bridge_mavlink")

PUBLISHED = (
    *BRIDGE_PUBLISHED,
    registry.GLOBAL_POSITION,
    registry.LINK_STATUS,
    registry.MISSION_WAYPOINTS,
    registry.MISSION_REACHED,
)
SERVICES: dict[Service[Any, Any], Operation] = {
    registry.FLIGHT_TAKEOFF: flight.takeoff_to,
    registry.FLIGHT_LAND: flight.land_here,
    registry.FLIGHT_GOTO: actions.goto_point,
    registry.FLIGHT_RETURN: actions.return_home,
    registry.FLIGHT_MISSION: actions.mission_action,
    registry.MISSION_CONTROL: actions.control,
    registry.ARMING: ops.arming,
    registry.TAKEOFF: ops.takeoff,
    registry.LAND: ops.land,
    registry.SET_MODE: ops.set_mode,
    registry.PARAM_GET: parameters.param_get,
    registry.PARAM_SET: parameters.param_set,
}


def serve_services(bridge: BridgeNode[Any]) -> None:
    """Serve this bridge's services on ``bridge``: :data:`SERVICES`, and
    ``missions.SERVICES`` (the mission services, the fence upload and the envelope), which
    only the command lease's holder may call."""
    bridge.serve(SERVICES, missions.SERVICES)


PORTS = bridge_ports("bridge_mavlink", PUBLISHED, SERVICES, missions.SERVICES) | Ports(
    "bridge_mavlink",
    publishes=(registry.MAVLINK_FROM_AUTOPILOT,),  # gcs_over_zenoh
    subscribes=(registry.MAVLINK_TO_AUTOPILOT,),
)
"""What this bridge publishes, subscribes to and serves (:mod:`dronewrapper.runtime.ports`)."""


class Bridge(BridgeNode[BridgeCore]):
    """The core wired to one Node and one MAVLink link."""

    def __init__(self, node: NodeApi, config: Config, link: MavLink | None = None) -> None:
        publishers = {topic: node.publisher(topic) for topic in PUBLISHED}
        super().__init__(node, BridgeCore(config, node.clock.monotonic()), publishers, log)
        self.config = config
        self.gcs: GcsForwarder | None = None  # ground-station forwarding, made at start()
        self.link = link or MavLink(
            config.connection,
            baud=config.baud,
            source_system=config.source_system,
            source_component=config.source_component,
            signing_key_file=config.signing_key_file,
            wanted=wanted_ids(BridgeCore.read_messages(), mavlink),
            clock=node.clock,
        )
        self.link_status = publishers[registry.LINK_STATUS]
        self.load = LinkLoad(self.core.budget.capacity)
        self.load_alarm = LoadAlarm(config.link_warn_load)
        self.reconnects = Reconnects()  # under _reconnects_lock (receive and status threads)
        self._reconnects_lock = threading.Lock()
        self.failures: list[BaseException] = []
        """What failed this bridge on its host's shared loop (``run`` raises the first)."""

    # ---- what the core knows

    def current_state(self) -> State:
        """State as published now."""
        with self.driver.cond:
            return self.core.current_state()

    # ---- feeding the core

    def send(self, out: Outbox) -> None:
        for peer in out.peers:
            self.link.peer = peer
        for message in out.sends:
            self.link.send(message)
        for error in out.errors:
            self.node.callback_errors[error] += 1

    def handle_mavlink(self, msg: Any, source: Any = None) -> None:
        """One received MAVLink message (``source``: the UDP address it came from, or None)."""
        self.driver.feed(self.core.on_mavlink, msg, source)

    def _on_command_ack(self, msg: Any, _stamp: float = 0.0, _now: float = 0.0) -> None:
        """A COMMAND_ACK straight to the ack routing, at the bridge's own time (the signature
        tests/integration/test_gcs_forwarding.py uses)."""
        self.driver.feed(self.core.on_command_ack, msg)

    # ---- lifecycle

    def start(self) -> list[threading.Thread]:
        """Open the link, subscribe, serve, and start the loops (returns the threads)."""
        self._open_link()
        serve_services(self)
        clock, stop = self.node.clock, self.node.stop_event
        threads = [clock.thread(self._link_status_loop, "link-status")]
        poller = shared_poller()  # a host's, for its members (None outside a host)
        if poller is not None and self.link.is_udp:
            poller.add(SharedReceive(self), stop, self.failures.append, due=math.inf)
        else:
            threads.append(clock.thread(self._receive_loop, "mavlink-rx"))
        rate_hz = self.config.stream_rate_hz
        ticker = shared_ticker(rate_hz)  # a host's, for all its bridges (the real clock)
        if ticker is not None:
            ticker.join(lambda: self.tick_once("stream"), stop)
        else:
            threads.append(clock.thread(lambda: self.tick_loop(rate_hz, "stream"), "stream"))
        self.gcs = self._make_gcs_forwarder()
        if (gcs := self.gcs) is not None:
            threads.append(clock.thread(lambda: gcs.run(stop), "gcs"))
        for thread in threads:
            thread.start()
        self.driver.feed(self.core.on_started)
        return threads

    def _make_gcs_forwarder(self) -> GcsForwarder | None:
        """The ground-station forwarder of ``gcs_url`` / ``gcs_over_zenoh``, or None."""
        address = parse_gcs_url(self.config.gcs_url) if self.config.gcs_url else None
        if address is None and not self.config.gcs_over_zenoh:
            return None
        publish = None
        if self.config.gcs_over_zenoh:
            publisher = self.node.publisher(registry.MAVLINK_FROM_AUTOPILOT)
            publish = publisher.put
        forwarder = GcsForwarder(self.link.write_raw, address, publish, clock=self.node.clock)
        self.link.tap = forwarder.from_autopilot  # every frame, read or not
        if self.config.gcs_over_zenoh:
            self.node.subscribe(registry.MAVLINK_TO_AUTOPILOT, forwarder.from_zenoh)
        if address is not None and not is_loopback(address[0]):
            log.warning(
                "forwarding the autopilot's MAVLink to %s beyond loopback: anyone there can "
                "command the autopilot unless MAVLink signing is on",
                self.config.gcs_url,
            )
        log.info(
            "ground-station forwarding: %s%s",
            self.config.gcs_url or "no UDP",
            ", and over Zenoh" if self.config.gcs_over_zenoh else "",
        )
        return forwarder

    def _open_link(self) -> bool:
        try:
            self.link.open()
        except (OSError, ValueError) as exc:
            log.warning("cannot open %s: %s (retrying)", self.config.connection, exc)
            self.link.close()
            return False
        log.info("MAVLink link open on %s", self.config.connection)
        with self._reconnects_lock:
            self.reconnects.opened()
        return True

    def _link_status_loop(self) -> None:
        """Once a second: the link's load, losses and reconnects on ``LINK_STATUS``, and a
        warning in the log when a serial line is nearly full."""
        log.info("%s", self.core.budget.describe())
        clock, stop = self.node.clock, self.node.stop_event
        while not clock.wait(stop, 1.0):
            try:
                self.link_status.put(self.measure_link(clock.monotonic()))
            except Exception:
                self.node.callback_errors["link status"] += 1
                log.exception("link status")

    def measure_link(self, now: float) -> LinkStatus:
        """The link as it is at ``now`` (the node's monotonic s; counts heartbeats regained
        as a reconnect), stamped with the node's clock."""
        with self._reconnects_lock:
            self.reconnects.heartbeat(self.core.connected)
        counts = self.link.counts()
        self.load.add(now, counts.received, counts.sent)
        received, sent = self.load.rates()
        budget = self.core.budget
        status = LinkStatus(
            header=Header(stamp=self.node.clock.time()),
            kind=link_kind(self.config.connection),
            baud=self.config.baud if budget.capacity > 0 else 0,
            capacity=budget.capacity,
            received_rate=received,
            sent_rate=sent,
            load=self.load.load(),
            lost=counts.lost,
            reconnects=self.reconnects.count,
            rejected=self.link.rejected,
            stream_scale=budget.scale,
        )
        if budget.capacity > 0:
            warning = self.load_alarm.update(status.load, f"serial {self.config.baud} baud")
            if warning is not None:
                (log.warning if self.load_alarm.raised else log.info)("%s", warning)
        return status

    def _receive_loop(self) -> None:
        clock, stop = self.node.clock, self.node.stop_event
        while not stop.is_set():
            if not self.link.is_open:
                if not self._open_link():
                    clock.wait(stop, 1.0)
                continue
            try:
                batch = self.link.recv_batch(0.1)
            except (OSError, ValueError) as exc:  # serial unplugged, socket error ...
                log.warning("link error on %s: %s; reopening", self.config.connection, exc)
                self.link.close()
                clock.wait(stop, 1.0)
                continue
            self.handle_batch(batch)

    def handle_batch(self, batch: list[Any]) -> None:
        """One wake-up's messages in one call of the core (``receive.on_batch``); an error
        executing their effects is logged and counted (``mavlink``)."""
        if not batch:
            return
        try:
            self.driver.feed(receive.on_batch, self.core, batch)
        except Exception:
            self.node.callback_errors["mavlink"] += 1
            log.exception("error executing the effects of %d message(s)", len(batch))


class SharedReceive:
    """A bridge's UDP link read by its host's shared loop (:mod:`dronewrapper.runtime.poller`)
    instead of a receive thread: what a readable socket holds is drained and handled as one
    batch, as the thread does; a link error closes the link, which is reopened a second later
    (the loop calls :meth:`on_due` then)."""

    REOPEN_S = 1.0

    def __init__(self, bridge: Bridge) -> None:
        self.bridge = bridge

    def fileno(self) -> int:
        link = self.bridge.link
        return link.fileno() if link.is_open else NO_FILE

    def on_readable(self) -> float | None:
        bridge = self.bridge
        try:
            batch = bridge.link.drain()
        except (OSError, ValueError) as exc:
            log.warning("link error on %s: %s; reopening", bridge.config.connection, exc)
            bridge.link.close()
            return bridge.node.clock.monotonic() + self.REOPEN_S
        bridge.handle_batch(batch)
        return None

    def on_due(self, now: float) -> float:
        """Reopen a closed link; the next try a second later if it fails."""
        bridge = self.bridge
        if bridge.link.is_open or bridge._open_link():
            return math.inf
        return now + self.REOPEN_S


def link_kind(url: str) -> str:
    """``serial``, ``udp`` or ``tcp`` for a pymavlink URL."""
    scheme = url.partition(":")[0]
    if scheme.startswith("udp"):
        return "udp"
    if scheme.startswith("tcp"):
        return "tcp"
    return "serial"


def run(node: Node, config: Config) -> int:
    """The service body: start the bridge, announce readiness, run until stopped."""
    # The receive loop parses hundreds of MAVLink messages/s in Python; a 1 ms GIL switch
    # interval (default 5 ms) keeps a setpoint arriving meanwhile from waiting behind it.
    sys.setswitchinterval(0.001)
    try:
        bridge = Bridge(node, config)
    except ValueError as exc:  # e.g. an unknown commander_lost_action
        log.error("bad config: %s", exc)
        return 2
    exposure = network_exposure(config.connection)
    if exposure is not None:
        log.warning("autopilot link beyond loopback (a deliberate setting): %s", exposure)
    threads = bridge.start()
    node.announce()
    log.info("bridge_mavlink ready on %s (namespace %s)", config.connection, node.ns)
    node.spin()
    for thread in threads:
        thread.join(timeout=2.0)
    bridge.link.close()
    if bridge.gcs is not None:
        bridge.gcs.close()
    if bridge.failures:
        raise bridge.failures[0]
    return 0


__all__ = ["Bridge", "canonical_mode", "run"]
