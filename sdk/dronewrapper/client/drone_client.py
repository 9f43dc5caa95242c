"""One drone, as every program reaches it: inputs, the setpoint stream, calls, refusals.

A :class:`DroneClient` stands on a node (a service's, the SDK's own, or a
:class:`~dronewrapper.runtime.fake.FakeNode` in tests), never blocks, and owns one of each:

- **inputs**: one newest-value holder per key in the drone's namespace, aged on the node's
  clock (:class:`~dronewrapper.client.inputs.Inputs`: ``state``, ``extended``, ``pose``, ...);
- **the "connected" rule**: :meth:`connected_state` (a State younger than
  :data:`STATE_FRESH_S` that says the autopilot is connected), :meth:`ready` (connected, a
  landed state and a position arrived: what take-off and landing read) and
  :meth:`not_ready_reason`;
- **the setpoint stream** (:class:`~dronewrapper.client.stream.SetpointStreamer`): :meth:`set`
  publishes a PositionTarget at once and repeats it every ``1 / rate_hz`` s until changed or
  :meth:`stop`-ped, from a service's loop (:meth:`poll`, :meth:`next_due`) or on its own
  thread (``threaded_stream``, the SDK's blocking client); after a router gap a command older
  than the bridge's expiry is dropped, never resent. Each setpoint goes out through one timed
  put: the ``commander=NAME`` attachment with the send time (the bridges' late-setpoint rule);
- **calls**: :meth:`call` returns a :class:`~dronewrapper.client.calls.Pending` at once,
  :meth:`ask` waits for the reply; each carries the ``commander`` attachment;
- **refusals**: the bridge's refusals of our setpoints as they arrive
  (:class:`~dronewrapper.refusals.RefusalInbox`).

The controller's loop, the ground station and the SDK's blocking
:class:`~dronewrapper.drone.DroneWrapper` are all this class. Units: seconds (``now``: the
node's monotonic clock; ``stamp``: Unix time of the data a command comes from), metres, m/s,
rad/s.
"""

from __future__ import annotations

import contextlib
import getpass
import os
import socket
from collections.abc import Iterable, Sequence
from pathlib import Path
from typing import Any, TypeVar

from dronewrapper import setpoints
from dronewrapper.client.calls import Calls, Pending
from dronewrapper.client.inputs import FLIGHT_STREAMS, STREAMS, Inputs
from dronewrapper.client.setpoint_stream import DEFAULT_EXPIRY_S
from dronewrapper.client.stream import SetpointStreamer
from dronewrapper.msgs import registry
from dronewrapper.msgs.geometry import PoseStamped
from dronewrapper.msgs.mavros import ExtendedState, PositionTarget, State
from dronewrapper.msgs.registry import Service
from dronewrapper.refusals import RefusalInbox
from dronewrapper.runtime.caller import commander_attachment
from dronewrapper.runtime.contract import NodeApi
from dronewrapper.runtime.latest import Latest
from dronewrapper.runtime.ports import Ports

Req = TypeVar("Req")
Rep = TypeVar("Rep")

STATE_FRESH_S = 3.0
"""The bridge publishes State at >= 1 Hz; older than this means the bridge is gone."""

CLIENT_PORTS = Ports(
    "sdk",
    publishes=(registry.SETPOINT_RAW_LOCAL,),
    subscribes=(
        *STREAMS.values(),
        registry.STATUSTEXT,
        registry.REFUSAL,
        registry.IMAGE_RAW,
        registry.IMAGE_COMPRESSED,
    ),
    calls=(
        registry.FLIGHT_TAKEOFF,
        registry.FLIGHT_LAND,
        registry.FLIGHT_GOTO,
        registry.FLIGHT_RETURN,
        registry.FLIGHT_MISSION,
    ),
)
"""What a :class:`DroneClient` does on its node (its inputs, setpoints and flight steps): the
part of a service's ``PORTS`` it brings (:mod:`dronewrapper.runtime.ports`)."""


def default_commander(identity: str = "") -> str:
    """Our name on the command lease: ``$DRONEWRAPPER_COMMANDER``, the identity's name, or
    ``user@host``."""
    env = os.environ.get("DRONEWRAPPER_COMMANDER")
    if env:
        return env
    if identity:
        return Path(identity).stem if identity.endswith(".crt") else identity
    return f"{getpass.getuser()}@{socket.gethostname()}"


class DroneClient:
    """Inputs, setpoints, calls and refusals of one drone (see the module doc).

    Args:
        node: the node to stand on; its clock is the client's time.
        name: our name on the command lease (the ``commander`` attachment).
        ns: the drone's namespace (default: the node's).
        rate_hz: setpoint repetition rate (>= 20 Hz).
        expiry: the bridge's setpoint expiry (s): a command older than this after a link gap
            is dropped.
        idle_timeout: stop streaming a setpoint not renewed for this many seconds (None:
            stream until changed).
        threaded_stream: repeat setpoints on the stream's own thread instead of :meth:`poll`.
        inline_calls: answer :meth:`call` on the caller's thread (the fake bus, whose services
            answer synchronously; a blocking caller) instead of on a worker thread.
        forbidden: why our certificate's role may not command ("" when it may): every call is
            then refused unsent.
        streams, cameras, compressed_images: the inputs subscribed from the start
            (:class:`~dronewrapper.client.inputs.Inputs`).
    """

    def __init__(
        self,
        node: NodeApi,
        *,
        name: str,
        ns: str | None = None,
        rate_hz: float = 30.0,
        expiry: float = DEFAULT_EXPIRY_S,
        idle_timeout: float | None = None,
        threaded_stream: bool = False,
        inline_calls: bool = False,
        forbidden: str = "",
        streams: Iterable[str] = FLIGHT_STREAMS,
        cameras: Sequence[str] | None = (),
        compressed_images: bool = False,
    ) -> None:
        self.ns = ns or node.ns
        self.name = name
        self.node = node
        self.clock = node.clock
        self.closed = False
        self.stream = SetpointStreamer(
            self._put,
            clock=self.clock,
            rate_hz=rate_hz,
            idle_timeout=idle_timeout,
            expiry=expiry,
            name=f"{self.ns}-setpoints",
            threaded=threaded_stream,
        )
        self.calls = Calls(node, self.ns, name, inline=inline_calls, forbidden=forbidden)
        self.inputs = Inputs(
            node, self.ns, compressed_images=compressed_images, cameras=cameras, streams=streams
        )
        self.refusals = RefusalInbox(self.ns, name, self.clock)
        self.inputs.subscribe(registry.REFUSAL, self.refusals.on_refusal)
        self._setpoints = node.publisher(
            registry.SETPOINT_RAW_LOCAL, key=registry.SETPOINT_RAW_LOCAL.key(self.ns)
        )
        self._matching = self._setpoints.on_matching(self._on_matching)

    def wall(self) -> float:
        """Unix time now on the node's clock (s)."""
        return self.clock.time()

    # ---- inputs and the "connected" rule ----

    @property
    def state(self) -> Latest[State]:
        return self.inputs.state

    @property
    def extended(self) -> Latest[ExtendedState]:
        return self.inputs.extended

    @property
    def pose(self) -> Latest[PoseStamped]:
        return self.inputs.pose

    def connected_state(self) -> State | None:
        """The newest State if it is fresh and says the autopilot is connected, else None."""
        state = self.inputs.state.fresh(STATE_FRESH_S)
        return state if state is not None and state.connected else None

    def is_connected(self) -> bool:
        """True if a fresh State says the bridge's autopilot is connected."""
        return self.connected_state() is not None

    def ready(self) -> bool:
        """True once the autopilot is connected and a landed state and a position arrived
        (what take-off and landing read)."""
        return (
            self.connected_state() is not None
            and self.extended.value is not None
            and self.pose.value is not None
        )

    def not_ready_reason(self) -> str:
        """What :meth:`ready` still misses, in words naming the keys."""
        holder = self.inputs.state
        state = holder.value
        if state is None:
            return f"no State on {holder.name}: is the bridge running?"
        if holder.fresh(STATE_FRESH_S) is None:
            return f"State on {holder.name} is {holder.age():.1f} s old: the bridge stopped"
        if not state.connected:
            return "the bridge is up but its autopilot is not connected"
        missing = [h.name for h in (self.extended, self.pose) if h.value is None]
        return f"nothing arrived on {', '.join(missing)}" if missing else "ready"

    # ---- setpoints ----

    @property
    def target(self) -> PositionTarget | None:
        """The setpoint being streamed, or None."""
        return self.stream.target

    @property
    def published(self) -> int:
        """Setpoints published so far."""
        return self.stream.published

    def set(self, target: PositionTarget, now: float | None = None) -> None:
        """Publish ``target`` now and re-publish it until changed (``now``: the node's
        monotonic time, read here when None)."""
        self.stream.set(target, now)

    def set_velocity(
        self,
        vx: float,
        vy: float,
        vz: float,
        yaw_rate: float,
        now: float,
        *,
        stamp: float | None = None,
    ) -> None:
        """Stream a body-frame (FLU) velocity: m/s and rad/s (CCW positive); ``stamp``: Unix
        time of the data it comes from (default: now). Raises InvalidArgument if not finite."""
        stamp = setpoints.check_stamp(stamp, self.wall())
        self.set(setpoints.velocity_target(vx, vy, vz, yaw_rate, stamp=stamp), now)

    def stop(self) -> None:
        """Stop streaming (the bridge holds position after its setpoint expiry)."""
        self.stream.stop()

    def poll(self, now: float) -> bool:
        """Re-publish the setpoint if one is due; True if it did."""
        return self.stream.poll(now)

    def next_due(self) -> float:
        """When the next re-publication is due (node clock, s; inf when not streaming)."""
        return self.stream.next_due()

    def _put(self, target: PositionTarget) -> None:
        """The one timed put: the send time rides in the attachment (the bridges' late-setpoint
        rule)."""
        sent = self.wall()
        self._setpoints.put(target, attachment=commander_attachment(self.name, sent))

    def _on_matching(self, matching: bool) -> None:
        """The bridge's setpoint subscriber became (un)reachable: a link gap (router restart,
        lost Wi-Fi) withholds setpoints, and a command that went stale meanwhile is not resent
        (see runtime.setpoint_stream)."""
        if not self.closed:
            self.stream.link(matching)

    # ---- services ----

    def call(
        self,
        service: Service[Req, Rep],
        request: Req,
        now: float,
        *,
        timeout: float,
        what: str = "",
    ) -> Pending[Rep]:
        """Send ``request`` to ``service`` in this namespace; returns at once.

        ``timeout`` (s) bounds the wait for the reply, on the loop's clock and on the wire.
        """
        return self.calls.call(service, request, now, timeout=timeout, what=what)

    def ask(self, service: Service[Any, Rep], request: Any, timeout: float) -> Rep:
        """One request and its reply, on this thread (see Calls.ask)."""
        return self.calls.ask(service, request, timeout)

    def close(self) -> None:
        """Stop streaming, drop the subscriptions and calls not started yet (a call under way
        ends by its timeout, or when the node's session closes). Idempotent; the node stays
        open."""
        if self.closed:
            return
        self.closed = True
        self.stream.close()
        self.calls.close()
        for entity in (self._matching, self._setpoints):
            with contextlib.suppress(Exception):  # already gone with the session
                entity.undeclare()
        self.inputs.close()
