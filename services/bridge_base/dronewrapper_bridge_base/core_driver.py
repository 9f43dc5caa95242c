"""What a pure bridge core shares (:class:`PureCore`), and the thin node's side of it
(:class:`CoreDriver`: feed the core under one lock, in the node's time, execute its effects).

A bridge's core (bridge_mavlink's ``BridgeCore``, bridge_tello's ``TelloCore``) takes inputs
with the time as arguments and queues what to send and publish in an outbox. It applies the
commander lease itself (:class:`~.commander_lease.LeaseGate`): a setpoint or command
from anyone but the lease holder is refused in the core, so the rule is held by the core's
tests. Every setpoint the core refuses (lease, late, validation, envelope) and every breach
that overrides a commander is published to that commander on ``{ns}/dronewrapper/refusal``
(:meth:`PureCore.refuse`, repeats throttled by :class:`~.refusals.RefusalThrottle`).

:class:`CoreDriver` is the only place a node touches a core: every input goes through
:meth:`CoreDriver.feed` (the core called under the lock with the monotonic and wall-clock time
of the driver's clock, the node's, its outbox executed after the lock is released), and a
service call runs its operation to the end with :meth:`CoreDriver.call`, waiting through that
clock on the lock's condition until the operation ends, asks to be resumed, or the node stops.
On a fake bus's :class:`~dronewrapper.runtime.clock.VirtualClock` a waiting call moves the bus
time itself (it is the test's thread) or waits in virtual time (a worker's).
"""

from __future__ import annotations

import logging
import math
import threading
from collections.abc import Callable
from typing import TYPE_CHECKING, Any, Generic, TypeVar

from dronewrapper.msgs import registry
from dronewrapper.msgs.flight import CANCELLED, CancelRequest, FlightResult
from dronewrapper.msgs.lease import LeaseReply, LeaseRequest
from dronewrapper.msgs.refusal import BREACH, ENVELOPE, LATE, LEASE, VALIDATION, Refusal
from dronewrapper.msgs.registry import Topic
from dronewrapper.msgs.std import Header
from dronewrapper.runtime.clock import REAL, Clock
from dronewrapper.runtime.errors import ServiceError
from dronewrapper_bridge_base.commander_lease import LeaseDecision, LeaseGate
from dronewrapper_bridge_base.operation import Operation, Operations, Steps
from dronewrapper_bridge_base.refusals import RefusalThrottle
from dronewrapper_bridge_base.setpoint_delay import DEFAULT_THRESHOLD_S, SetpointDelay
from dronewrapper_bridge_base.setpoint_limits import SetpointError

MAX_WAIT_S = 0.05
"""A waiting service call looks at its operation at least this often (s)."""


class PureCore:
    """What every bridge's pure core shares: the time of the input being handled (``now``,
    monotonic s; ``stamp``, Unix s), the outbox of effects the node executes after each call,
    the running operations (service calls that wait on the aircraft) and the commander lease
    (``commander``: its holder, shown on State).

    Args:
        now: where the core's time starts (monotonic s).
        outbox: makes an empty outbox (the core's own ``Outbox`` dataclass).
        log: where a background operation's failure and the lease's changes are logged.
        lease_ttl_s: the commander lease's ttl (s); None: no lease, every commander obeyed.
        late_setpoint_s: a setpoint arriving this much later after its sending than its
            commander's usually do is refused (:mod:`~dronewrapper_bridge_base.setpoint_delay`).
    """

    if TYPE_CHECKING:  # every bridge's core has one, with its own arguments
        tick: Callable[..., Any]

    def __init__(
        self,
        now: float,
        outbox: Callable[[], Any],
        log: logging.Logger,
        *,
        lease_ttl_s: float | None = None,
        late_setpoint_s: float = DEFAULT_THRESHOLD_S,
    ) -> None:
        self.now, self.stamp = now, 0.0
        self._outbox = outbox
        self._log = log
        self.out = outbox()
        self.operations = Operations(log)
        self._command_busy = False  # one command exchange with the aircraft at a time
        self.lease = LeaseGate(lease_ttl_s, log)
        self.commander = ""  # the lease's holder as State shows it ("": nobody)
        self.setpoint_delay = SetpointDelay(late_setpoint_s)
        self._late_log_at = -math.inf
        self.rejected_setpoints = 0  # setpoints refused by validation or the envelope
        self._last_reject_log = -math.inf
        self.refusals = RefusalThrottle()  # what is published to the refused commanders
        self.setpoint_commander = ""  # who sent the last setpoint flown (told of a breach)
        self.caller = ""  # the commander of the request whose operation is starting

    def _at(self, now: float, stamp: float) -> None:
        self.now, self.stamp = now, stamp

    def take(self) -> Any:
        """The effects queued since the last call (the node executes them)."""
        out, self.out = self.out, self._outbox()
        return out

    def publish(self, topic: Topic, msg: Any) -> None:
        """Queue a sample for ``topic``."""
        self.out.samples.append((topic, msg))

    @property
    def command_busy(self) -> bool:
        """True while an operation exchanges a command with the aircraft (one at a time)."""
        return self._command_busy

    def take_command_slot(self) -> None:
        """An operation starts its command exchange (only when :attr:`command_busy` is False)."""
        assert not self._command_busy, "the command slot is taken"
        self._command_busy = True

    def release_command_slot(self) -> None:
        """The exchange has ended (answered, unanswered or abandoned)."""
        self._command_busy = False

    def publish_state(self, *, force: bool = False) -> None:
        """Publish State (the core's own; called when the lease's holder changed)."""
        raise NotImplementedError

    def on_started(self, now: float, stamp: float) -> None:
        """The bridge has started: State published at once, stamped ``stamp``."""
        self._at(now, stamp)
        self.publish_state(force=True)

    # ---- the commander lease

    def on_setpoint(
        self,
        target: Any,
        commander: str,
        now: float,
        stamp: float,
        sent: float | None = None,
    ) -> None:
        """A PositionTarget from ``commander`` sent at ``sent`` (its clock, Unix s), flown
        (:meth:`fly_setpoint`) unless refused: when it arrives late or the lease refuses it
        (:meth:`admit_setpoint`), when :meth:`check_setpoint` (the bridge's own validation)
        raises SetpointError, or when :meth:`refuse_envelope` says so. Every refusal but the
        lease's is counted in ``rejected_setpoints``; a validation refusal is logged at most
        every 2 s. Each refusal is published to ``commander`` (:meth:`refuse`)."""
        self._at(now, stamp)
        if not self.admit_setpoint(commander, sent):
            return
        try:
            kind = self.check_setpoint(target)
        except SetpointError as exc:
            self.rejected_setpoints += 1
            self.refuse(VALIDATION, commander, exc.limit, str(exc))
            if self.now - self._last_reject_log >= 2.0:
                self._last_reject_log = self.now
                self._log.warning("setpoint refused (%d so far): %s", self.rejected_setpoints, exc)
            return
        refused = self.refuse_envelope(target, kind)
        if refused:
            self.rejected_setpoints += 1
            limit = getattr(refused, "limit", "")
            self.refuse(ENVELOPE, commander, limit, str(refused))
            return
        self.setpoint_commander = commander
        self.fly_setpoint(target, kind)

    def check_setpoint(self, target: Any) -> Any:
        """The control ``target`` asks for, or SetpointError saying why it may not fly."""
        raise NotImplementedError

    def refuse_envelope(self, target: Any, kind: Any) -> Any:
        """Why the envelope refuses ``target`` (an ``EnvelopeError``: ``limit`` named), or None."""
        raise NotImplementedError

    def fly_setpoint(self, target: Any, kind: Any) -> None:
        """Fly a setpoint every check admitted (now: :attr:`now`)."""
        raise NotImplementedError

    def admit_setpoint(self, commander: str, sent: float | None = None) -> bool:
        """True if a setpoint from ``commander``, sent at ``sent`` (its clock, Unix s; None:
        not known), may be flown now: it did not arrive late (counted in
        ``setpoint_delay.refused`` and logged) and the lease admits it."""
        verdict = self.setpoint_delay.judge(commander, sent, self.now)
        if verdict.late:
            threshold = self.setpoint_delay.threshold_s
            message = (
                f"arrived {verdict.excess:.2f} s later than its usual lag, beyond the bridge's "
                f"{threshold:g} s (held on the way: a stalled link)"
                if verdict.excess > threshold
                else f"sent within {threshold:g} s of a late one (queued behind it)"
            )
            self.refuse(LATE, commander, "late_setpoint_s", message)
            if self.now - self._late_log_at >= 2.0:
                self._late_log_at = self.now
                self._log.warning(
                    "late setpoint from %r refused (%d so far): %.2f s later than its usual lag",
                    commander,
                    self.setpoint_delay.refused,
                    verdict.excess,
                )
            return False
        admitted = self.lease.admit_setpoint(commander, self.now)
        self.show_commander()
        if not admitted:
            reason = LeaseDecision(False, self.lease.holder(self.now)).reason(commander)
            self.refuse(LEASE, commander, "command_lease", reason)
        return admitted

    def refuse(
        self,
        kind: str,
        commander: str,
        limit: str,
        message: str,
        *,
        what: str = "setpoint",
        action: str = "",
    ) -> None:
        """Tell ``commander`` that its ``what`` was refused (or overridden: a breach) by rule
        ``kind`` (:data:`dronewrapper.msgs.refusal.KINDS`), ``limit`` named: published now
        unless an identical refusal was published less than a second ago (then counted into
        the next one, :class:`~.refusals.RefusalThrottle`)."""
        count = self.refusals.admit(self.now, commander, kind, what, limit, message)
        if count:
            refusal = Refusal(
                header=Header(stamp=self.stamp),
                commander=commander,
                kind=kind,
                what=what,
                limit=limit,
                message=message,
                action=action,
                count=count,
            )
            self.publish(registry.REFUSAL, refusal)

    def report_breach(self, limit: str, reason: str, action: str) -> None:
        """Tell whoever commands (the lease's holder, else the sender of the last setpoint
        flown) that a breach of ``limit`` overrides it with the envelope's ``action``."""
        commander = self.lease.holder(self.now) or self.setpoint_commander
        message = f"envelope breach: {reason}"
        self.refuse(BREACH, commander, limit, message, what="command", action=action)

    def request(self, steps: Steps, commander: str, what: str, now: float, stamp: float):
        """A service call from ``commander``: ``what`` names the command the lease guards
        (``""``: a read, never refused). A refused one fails at once (ServiceError, code
        ``lease``) and its steps never run."""
        self._at(now, stamp)
        refusal = self.lease.command_refusal(commander, what, now) if what else None
        self.show_commander()
        if refusal is not None:
            steps.close()
            steps = _refused(refusal)
        self.caller = commander  # read by the operation's first step
        return self.operations.start(steps)

    def on_lease_request(
        self, request: LeaseRequest, commander: str, now: float, stamp: float
    ) -> LeaseReply:
        """The ``{ns}/dronewrapper/lease`` service: take, take over or release."""
        self._at(now, stamp)
        reply = self.lease.handle(request, commander, now)
        self.show_commander()
        return reply

    def show_commander(self) -> None:
        """State follows the lease's holder now (a taken, released or lapsed lease)."""
        holder = self.lease.holder(self.now)
        if holder != self.commander:
            self.commander = holder
            self.publish_state(force=True)

    # ---- operations

    def start(self, steps: Steps, now: float, stamp: float, *, background=False) -> Operation:
        """Begin an operation (its first step runs now; a bad request fails it at once);
        ``background``: the bridge's own, nobody waits for it (its failure is logged)."""
        self._at(now, stamp)
        return self.operations.start(steps, background=background)

    def advance(self, now: float, stamp: float) -> None:
        """Move every pending operation on to ``now``."""
        self._at(now, stamp)
        self.operations.advance()

    def cancel(self, op: Operation) -> None:
        """Abandon ``op`` (the node is stopping): its cleanup runs (a command slot is freed)."""
        self.operations.cancel(op)

    # ---- a commander's cancel

    def cancel_flight(self, request: CancelRequest) -> FlightResult:
        """End the running take-off, landing, go-to or return (:data:`CANCELLABLE`) at once, each
        answered ``cancelled``, and hold where the aircraft is (:meth:`hold_here`)."""
        running = [
            op for op in self.operations.pending if not op.background and op.name in CANCELLABLE
        ]
        if not running:
            return FlightResult(
                message="nothing to cancel: no take-off, landing, go-to or return runs"
            )
        names = ", ".join(CANCELLABLE[op.name] for op in running)
        why = f": {request.reason}" if request.reason else ""
        for op in running:
            message = f"{CANCELLABLE[op.name]} cancelled{why}; holding here"
            self.operations.interrupt(op, FlightResult(failure=CANCELLED, message=message))
        self._log.warning("%s cancelled%s; holding here", names, why)
        self.hold_here()
        return FlightResult(success=True, message=f"{names} cancelled; holding here")

    def hold_here(self) -> None:
        """Hold where the aircraft is now (the core's own way: a position hold, a hover)."""
        raise NotImplementedError


CANCELLABLE = {
    "takeoff_to": "take-off",
    "land_here": "landing",
    "goto_point": "go-to",
    "return_home": "return",
}
"""The waiting operations a cancel ends (their steps' names: both bridges' ``flight``
module), and how its reply names them."""


def cancel_steps(core: PureCore, request: CancelRequest) -> Steps:
    """The ``{ns}/dronewrapper/cancel`` service's operation: done at once."""
    return core.cancel_flight(request)
    yield 0.0


def _refused(error: ServiceError) -> Steps:
    """An operation that fails at once with ``error`` (a refused command)."""
    raise error
    yield 0.0


C = TypeVar("C", bound=PureCore)


class CoreDriver(Generic[C]):
    """Feeds ``core`` under one lock and hands its outboxes to ``execute`` outside the lock.

    Args:
        core: the pure core.
        execute: carries out one outbox (sends, publications); runs on the feeding thread.
        stop: set when the node stops; a waiting service call then cancels its operation.
        clock: the node's clock (``node.clock``): ``monotonic()`` is the core's ``now``,
            ``time()`` its ``stamp`` (s), and a waiting call waits through it.
    """

    def __init__(
        self,
        core: C,
        execute: Callable[[Any], None],
        stop: threading.Event,
        *,
        clock: Clock = REAL,
    ) -> None:
        self.core = core
        self.cond = threading.Condition()  # guards the core; notified when an operation ends
        self._executing = threading.RLock()  # outboxes run one at a time, in the core's order
        self._execute = execute
        self._stop = stop
        self.clock = clock

    def feed(self, call: Callable[..., Any], *args: Any, **kwargs: Any) -> Any:
        """Run ``call(*args, now, stamp, **kwargs)`` on the core under the lock, then execute
        its outbox (outboxes are executed one at a time, in the order the core made them);
        service calls waiting on their operations are woken when one has finished."""
        with self._executing:
            with self.cond:
                finished = self.core.operations.finished
                result = call(*args, self.clock.monotonic(), self.clock.time(), **kwargs)
                out = self.core.take()
                if self.core.operations.finished != finished:
                    self.cond.notify_all()
            self._execute(out)
        return result

    def call(self, steps: Steps, commander: str = "", what: str = "") -> Any:
        """Start the operation of ``commander``'s request and wait (bounded by its own
        timeouts) for its reply; raises its error (a command ``what`` the lease refuses fails
        at once). If the node stops meanwhile the operation is cancelled."""
        op = self.feed(self.core.request, steps, commander, what)
        while not op.done:
            if self._stop.is_set():
                with self.cond:
                    self.core.cancel(op)
                break
            with self.cond:
                if op.done:  # ended by another thread's input (checked under the lock)
                    break
                wait = op.wake_at - self.clock.monotonic()
                finished = self.core.operations.finished  # woken when an operation ends

                def woken(ended: int = finished) -> bool:
                    return self.core.operations.finished != ended or self._stop.is_set()

                self.clock.wait_for(self.cond, woken, min(max(wait, 0.001), MAX_WAIT_S))
            self.feed(self.core.advance)
        with self._executing:  # the reply never overtakes what ended it (a State, a sample)
            pass
        return op.result()
