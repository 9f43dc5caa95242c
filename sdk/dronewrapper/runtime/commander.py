"""Commanding an aircraft from a service's loop without ever blocking it.

The user-facing :class:`~dronewrapper.drone.DroneWrapper` blocks (``takeoff()`` returns at
altitude) and streams setpoints on its own thread. A service's loop must not block: it has
inputs to watch and must stop within one period on SIGINT/SIGTERM. A :class:`Commander` lives
on the service's runtime Node (or a :class:`~dronewrapper.runtime.fake.FakeNode` in tests) and
gives that loop three things, each taking the time as an argument:

- **setpoints the loop streams**: :meth:`Commander.set` publishes a PositionTarget at once,
  :meth:`Commander.poll` re-publishes it every ``1 / rate_hz`` s (>= 20 Hz, the contract's
  setpoint rate) until it is changed or :meth:`Commander.stop`-ped. The rules are the SDK's
  (:class:`~dronewrapper.runtime.setpoint_stream.SetpointStream`), the link-gap rule included:
  after a router gap a command older than the bridge's expiry is dropped, never resent. The
  stream lives in the loop: a loop that hangs stops streaming, and the bridge holds position
  after its setpoint expiry (a deadman for free). :meth:`Commander.next_due` says when the
  loop must wake next.
- **service calls with a deadline**: :meth:`Commander.call` returns a :class:`Pending` at
  once; the loop polls it (``done(now)``, then ``result(now)``). On a real Node the request
  waits on a worker thread owned here; on the fake bus it is answered inline.
- **the bridge's state** as newest-value holders on the loop's clock: ``state``,
  ``extended``, ``pose``, ``status_text`` (the autopilot's newest text), and
  :meth:`Commander.ready` (autopilot connected, State fresh, landed state and position
  present); and ``refusals``, the bridge's refusals of our setpoints as they arrive
  (:class:`~dronewrapper.refusals.RefusalInbox`: the recent ones, a warning line, listeners).

Every setpoint and request carries the ``commander=NAME`` attachment, as the SDK's do, so a
bridge with the command lease on knows who sends it. Units: seconds (``now``: the node's
monotonic clock; ``stamp``: Unix time of the data the command comes from), metres, m/s, rad/s.
"""

from __future__ import annotations

import contextlib
import logging
import math
from concurrent.futures import Future, ThreadPoolExecutor
from typing import Generic, TypeVar

from dronewrapper import setpoints
from dronewrapper.msgs import registry
from dronewrapper.msgs.geometry import PoseStamped
from dronewrapper.msgs.mavros import ExtendedState, PositionTarget, State, StatusText
from dronewrapper.msgs.registry import Service
from dronewrapper.refusals import RefusalInbox
from dronewrapper.runtime.caller import commander_attachment
from dronewrapper.runtime.contract import NodeApi
from dronewrapper.runtime.latest import Latest
from dronewrapper.runtime.setpoint_stream import MIN_RATE_HZ, SetpointStream

Req = TypeVar("Req")
Rep = TypeVar("Rep")

log = logging.getLogger("dronewrapper.commander")

CALL_WORKERS = 4
"""Calls under way at once: a call left waiting for a silent server never holds up the next
one (a landing after a take-off step that got no reply)."""
STATE_FRESH_S = 3.0
"""The bridge publishes State at >= 1 Hz; older than this means the bridge is gone (as the
SDK's ``DroneWrapper.is_connected``)."""


class Pending(Generic[Rep]):
    """A service call under way: poll :meth:`done`, then read :meth:`result`.

    ``deadline`` is on the loop's clock (s): past it the call counts as unanswered even if a
    worker still waits for the reply (whose late answer is then ignored).
    """

    def __init__(self, what: str, future: Future[Rep], deadline: float, timeout: float) -> None:
        self.what = what
        self.deadline = deadline
        self.timeout = timeout
        self._future = future

    def done(self, now: float) -> bool:
        """True once the reply (or an error) is in, or the deadline has passed."""
        return self._future.done() or now >= self.deadline

    def result(self, now: float) -> Rep:
        """The reply.

        Raises:
            ServiceError: the server refused the request (its message says why).
            ServiceUnavailable: nobody answered within the call's timeout.
            TimeoutError: the deadline passed before the reply came.
            RuntimeError: asked before :meth:`done`.
        """
        if self._future.done():
            return self._future.result()
        if now >= self.deadline:
            self._future.cancel()
            raise TimeoutError(f"{self.what}: no reply within {self.timeout:g} s")
        raise RuntimeError(f"{self.what}: the reply is still pending")


class Commander:
    """Setpoints, service calls and bridge state for one aircraft, driven by a service's loop.

    Args:
        node: the service's node; its namespace is the aircraft's, its clock the loop's time
            (the input holders' ages, the stamp of a setpoint given without one).
        name: our name on the command lease (the ``commander`` attachment).
        rate_hz: setpoint repetition rate (>= 20 Hz).
        expiry: the bridge's setpoint expiry (s): a command older than this after a link gap
            is dropped.
        inline_calls: answer calls on the caller's thread (the fake bus, whose services answer
            synchronously) instead of on this commander's worker thread.
    """

    def __init__(
        self,
        node: NodeApi,
        *,
        name: str,
        rate_hz: float = 30.0,
        expiry: float = 0.5,
        inline_calls: bool = False,
    ) -> None:
        if not rate_hz >= MIN_RATE_HZ:
            raise ValueError(f"setpoint rate must be >= {MIN_RATE_HZ:g} Hz, got {rate_hz}")
        self.ns = node.ns
        self.name = name
        self.period = 1.0 / rate_hz
        self._node = node
        self.clock = node.clock
        self._attachment = commander_attachment(name)
        self._setpoints = node.publisher(registry.SETPOINT_RAW_LOCAL)
        self.stream = SetpointStream(self._put, rate_hz=rate_hz, expiry=expiry)
        self._matching = self._setpoints.on_matching(
            lambda matching: self.stream.link(matching, self.clock.monotonic())
        )
        self._pool = (
            None
            if inline_calls
            else ThreadPoolExecutor(
                max_workers=CALL_WORKERS, thread_name_prefix=f"{node.name}-calls"
            )
        )
        self.state: Latest[State] = node.latest(registry.STATE)
        self.extended: Latest[ExtendedState] = node.latest(registry.EXTENDED_STATE)
        self.pose: Latest[PoseStamped] = node.latest(registry.LOCAL_POSE)
        self.status_text: Latest[StatusText] = node.latest(registry.STATUSTEXT)
        self.refusals = RefusalInbox(self.ns, name, self.clock)
        node.subscribe(registry.REFUSAL, self.refusals.on_refusal)

    def wall(self) -> float:
        """Unix time now on the node's clock (s)."""
        return self.clock.time()

    # ---- bridge state ----

    def connected_state(self) -> State | None:
        """The newest State if it is fresh and says the autopilot is connected, else None."""
        state = self.state.fresh(STATE_FRESH_S)
        return state if state is not None and state.connected else None

    def ready(self) -> bool:
        """True once the autopilot is connected and a landed state and a position arrived
        (what take-off and landing read)."""
        return (
            self.connected_state() is not None
            and self.extended.value is not None
            and self.pose.value is not None
        )

    def last_status_text(self) -> str:
        """The autopilot's newest text message ("" before the first), to name a failure."""
        text = self.status_text.value
        return text.text if text is not None else ""

    def not_ready_reason(self) -> str:
        """What :meth:`ready` still misses, in words naming the keys."""
        state = self.state.value
        if state is None:
            return f"no State on {self.state.name}: is the bridge running?"
        if self.state.fresh(STATE_FRESH_S) is None:
            return f"State on {self.state.name} is {self.state.age():.1f} s old: the bridge stopped"
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

    def set(self, target: PositionTarget, now: float) -> None:
        """Publish ``target`` now and re-publish it from :meth:`poll` until changed."""
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
        sent = self.wall()  # the send time: the bridges' late-setpoint rule
        self._setpoints.put(target, attachment=commander_attachment(self.name, sent))

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
        if not (math.isfinite(timeout) and timeout > 0):
            raise ValueError(f"timeout must be > 0 s, got {timeout!r}")
        what = what or service.key(self.ns)

        def ask() -> Rep:
            return self._node.call(service, request, timeout=timeout, attachment=self._attachment)

        if self._pool is None:
            future: Future[Rep] = Future()
            try:
                future.set_result(ask())
            except Exception as exc:
                future.set_exception(exc)
        else:
            future = self._pool.submit(ask)
        return Pending(what, future, now + timeout, timeout)

    def close(self) -> None:
        """Stop streaming and drop calls not started yet (a call under way ends by its
        timeout, or when the node's session closes)."""
        self.stop()
        with contextlib.suppress(Exception):  # already gone with the session
            self._matching.undeclare()
        if self._pool is not None:
            self._pool.shutdown(wait=False, cancel_futures=True)
