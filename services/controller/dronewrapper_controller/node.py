"""The controller process: detections in, body-velocity commands out, on one loop that never
blocks.

Subscribes ``{ns}/perception/detections``; commands the aircraft through a
:class:`~dronewrapper.client.DroneClient` on this process's node (setpoints on
``{ns}/mavros/setpoint_raw/local``, re-published at 30 Hz by the loop, each carrying the source
camera frame's stamp; take-off and landing as non-blocking sequences, see
:mod:`dronewrapper.client.flight`); publishes ``{ns}/controller/status`` at
``status_rate_hz``.

:class:`Controller` is the life cycle as steps in injected time: wait for the bridge ->
announce ready -> take off to ``takeoff.height`` (if ``takeoff.on_start``; the servo only
watches meanwhile) -> servo until stopped -> land (``on_exit: land``) or send a zero command for
0.2 s and stop commanding (``on_exit: stop``). A landing another commander orders while the
controller servos (:mod:`~dronewrapper_controller.yielding`) ends its commanding at once: it
yields, reports ``idle`` and, when stopped, neither lands nor commands. With ``dry_run`` no
aircraft is involved: announce ready -> servo until stopped, the commands only in the status.
:func:`run` drives it on its node: it wakes on each new detections message and otherwise at the
next control period, setpoint or status due, so a stop request is seen within one control
period. All time is the node's clock.
"""

from __future__ import annotations

import contextlib
import logging
import math
import os

from dronewrapper.client.drone_client import CLIENT_PORTS, DroneClient, default_commander
from dronewrapper.client.flight import FlightError, Landing, NotReady, StepRefused, Takeoff
from dronewrapper.msgs import registry
from dronewrapper.msgs.control import CONTROLLER_IDLE, CONTROLLER_LANDING, CONTROLLER_TAKEOFF
from dronewrapper.msgs.vision import Detections
from dronewrapper.runtime import Latest
from dronewrapper.runtime.contract import NodeApi
from dronewrapper.runtime.ports import Ports
from dronewrapper_controller.config import Config
from dronewrapper_controller.inputs import DetectionsGate
from dronewrapper_controller.loop import ControlLoop
from dronewrapper_controller.yielding import ForeignLanding

log = logging.getLogger("controller")

STOP_ZERO_S = 0.2
TAKEOFF_RETRY_S = 2.0  # a take-off refused while the autopilot gets ready is tried again after
"""``on_exit: stop``: how long the zero command is streamed before commanding stops (s)."""

WAIT, TAKEOFF, SERVO, LANDING, STOPPING, YIELDED, DONE = (
    "wait",
    "takeoff",
    "servo",
    "landing",
    "stopping",
    "yielded",
    "done",
)
STATUS_PHASE = {
    WAIT: CONTROLLER_IDLE,
    TAKEOFF: CONTROLLER_TAKEOFF,
    LANDING: CONTROLLER_LANDING,
    YIELDED: CONTROLLER_IDLE,
}
"""The state the status reports in each phase (others: the servo's own state)."""


def subscribe_detections(node: NodeApi) -> Latest[Detections]:
    """The newest usable Detections, aged on the node's clock: non-finite or out-of-range
    messages are counted in ``node.callback_errors`` under ``detections refused`` and dropped
    (logged at most every 2 s)."""
    holder: Latest[Detections] = Latest(name=registry.DETECTIONS.key(node.ns), clock=node.clock)
    last_log = [-math.inf]

    def on_drop(count: int, problem: str) -> None:
        node.callback_errors["detections refused"] += 1
        now = node.clock.monotonic()
        if now - last_log[0] >= 2.0:
            last_log[0] = now
            log.warning("detections refused (%d so far): %s", count, problem)

    node.subscribe(registry.DETECTIONS, DetectionsGate(holder.update, on_drop))
    return holder


class Controller:
    """The controller's life cycle as non-blocking steps (see the module doc).

    Args:
        node: the process's node: its ``stopping`` starts the shutdown, its clock is the
            loop's time (``monotonic`` for the steps and ages, ``time`` for the status stamp).
        config: the controller config.
        commander: commands the aircraft; None for ``dry_run``.
    """

    def __init__(self, node: NodeApi, config: Config, commander: DroneClient | None) -> None:
        if (commander is None) != config.dry_run:
            raise ValueError("a commander is needed unless dry_run, and none with it")
        now = node.clock.monotonic()
        self.node = node
        self.config = config
        self.commander = commander
        self.loop = ControlLoop(config)
        self.detections = subscribe_detections(node)
        self.exit_code = 0
        self.phase = WAIT
        self._status = node.publisher(registry.CONTROLLER_STATUS)
        self._period = 1.0 / config.rate_hz
        self._status_period = 1.0 / config.status_rate_hz
        self._next_control = now
        self._next_status = now
        self._seen = 0
        self._status_shown: str | None = ""
        self._logged_state = ""
        self._ready_deadline = now + config.ready_timeout
        self._takeoff: Takeoff | None = None
        self._takeoff_retry_at = math.inf
        self._takeoff_wait_until = math.inf
        self._landing: Landing | None = None
        self._stop_commanding_at = math.inf
        self._foreign_landing = ForeignLanding()
        if config.dry_run:
            log.info("%s dry run: commands are shown in the status, not sent", config.mode)
            node.announce()
            self.phase = SERVO
        else:
            log.info("%s on %s: waiting for the bridge", config.mode, config.aircraft)

    @property
    def finished(self) -> bool:
        return self.phase == DONE

    def step(self, now: float) -> None:
        """Do what is due at ``now`` (loop clock, s); never waits."""
        if self.node.stopping and self.phase in (WAIT, TAKEOFF, SERVO):
            self._shut_down(now)
        elif self.node.stopping and self.phase == YIELDED:
            self.phase = DONE  # another commander landed it: nothing of ours to undo
        if self.phase == WAIT:
            self._wait_for_bridge(now)
        elif self.phase == TAKEOFF:
            self._take_off(now)
        elif self.phase == SERVO:
            self._servo(now)
        elif self.phase == LANDING:
            self._land(now)
        elif self.phase == STOPPING and now >= self._stop_commanding_at:
            assert self.commander is not None
            self.commander.stop()
            self.phase = DONE
        if self.phase not in (TAKEOFF, SERVO):  # detections not read now: not waited for
            self._seen = self.detections.count
        if self.commander is not None:
            self.commander.poll(now)
        if self.phase == DONE:
            return
        phase = self._status_phase()
        if now >= self._next_status:
            self._publish_status(phase)
            self._next_status = max(self._next_status + self._status_period, now)
        elif phase != self._status_shown:  # a new phase: say so at once
            self._publish_status(phase)

    def next_wake(self, now: float) -> float:
        """When :meth:`step` must run next at the latest (loop clock, s); new detections wake
        it earlier."""
        wake = self._next_status
        if self.phase in (TAKEOFF, SERVO):
            wake = min(wake, self._next_control)
        else:  # waiting for the bridge or landing: look again every control period
            wake = min(wake, now + self._period)
        if self.commander is not None:
            wake = min(wake, self.commander.next_due())
        if self.phase == STOPPING:
            wake = min(wake, self._stop_commanding_at)
        return wake

    def wait(self, timeout: float) -> None:
        """Block up to ``timeout`` s (node clock) for a new detections message."""
        with contextlib.suppress(TimeoutError):
            self.detections.wait(max(0.0, timeout), newer_than=self._seen)

    # ---- phases ----

    def _wait_for_bridge(self, now: float) -> None:
        assert self.commander is not None
        if self.commander.ready():
            self.node.announce()
            if self.config.takeoff.on_start:
                log.info("taking off to %.1f m", self.config.takeoff.height)
                self._takeoff_wait_until = now + self.config.takeoff.wait_ready
                self._start_takeoff(now)
                self.phase = TAKEOFF
                self._take_off(now)
            else:
                self.phase = SERVO
                self._servo(now)
        elif now >= self._ready_deadline:
            log.error(
                "no bridge ready within %g s: %s",
                self.config.ready_timeout,
                self.commander.not_ready_reason(),
            )
            self.exit_code = 1
            self.phase = DONE

    def _start_takeoff(self, now: float) -> None:
        assert self.commander is not None
        self._takeoff = Takeoff(
            self.commander, self.config.takeoff.height, self.config.takeoff.timeout, now
        )
        self._takeoff_retry_at = math.inf

    def _retry_takeoff(self, now: float, exc: FlightError) -> bool:
        """A take-off the autopilot refused, or that found it not connected, is tried again
        after TAKEOFF_RETRY_S while ``takeoff.wait_ready`` lasts (the autopilot getting
        ready: PX4's estimator, ArduCopter's GPS fix); True when a retry is scheduled."""
        if not isinstance(exc, (StepRefused, NotReady)):
            return False
        if now + TAKEOFF_RETRY_S > self._takeoff_wait_until:
            return False
        log.warning("takeoff refused (%s): trying again in %g s", exc, TAKEOFF_RETRY_S)
        self._takeoff = None
        self._takeoff_retry_at = now + TAKEOFF_RETRY_S
        return True

    def _take_off(self, now: float) -> None:
        if self._new_input(now):  # taking off, the servo only watches where the target is
            self.loop.servo.observe(now, self.detections.value, self.detections.age())
        if self._takeoff is None:
            if now < self._takeoff_retry_at:
                return
            self._start_takeoff(now)
        assert self._takeoff is not None
        try:
            done = self._takeoff.step(now)
        except FlightError as exc:
            if self._retry_takeoff(now, exc):
                return
            log.error("takeoff failed: %s", exc)
            self.exit_code = 1
            self._shut_down(now)
            return
        if done:
            log.info("take-off done")
            self.phase = SERVO
            self._next_control = now  # servo at once
            self._servo(now)

    def _servo(self, now: float) -> None:
        if self.commander is not None and self._yield_to_a_foreign_landing():
            return
        if not self._new_input(now):
            return
        try:
            cmd = self.loop.tick(now, self.detections.value, self.detections.age())
            if cmd is None or self.commander is None:  # dry run: the status shows it
                return
            stamp = cmd.source_stamp if cmd.source_stamp > 0 else None
            self.commander.set_velocity(cmd.vx, 0.0, cmd.vz, cmd.yaw_rate, now, stamp=stamp)
        except ValueError as exc:  # never die on input: the last command holds instead
            self.node.callback_errors["controller tick"] += 1
            log.error("control step failed, command unchanged: %s", exc)
            return
        if cmd.state != self._logged_state:
            log.info("state %s", cmd.state)
            self._logged_state = cmd.state

    def _yield_to_a_foreign_landing(self) -> bool:
        """Stop commanding for good when another commander lands the aircraft."""
        assert self.commander is not None
        state, extended = self.commander.state.value, self.commander.extended.value
        reason = self._foreign_landing.reason(
            None if state is None else state.mode,
            None if extended is None else extended.landed_state,
        )
        if reason is None:
            return False
        log.warning("%s: the controller stops commanding until it is started again", reason)
        self.commander.stop()
        self.phase = YIELDED
        return True

    def _shut_down(self, now: float) -> None:
        """Land (``on_exit: land``) or stream a zero command briefly and stop commanding."""
        if self.commander is None or self.phase == WAIT:  # dry run, or nothing commanded yet
            self.phase = DONE
        elif self.config.on_exit == "land":
            log.info("landing")
            self.phase = LANDING
            self._landing = Landing(self.commander, self.config.land_timeout, now)
        else:
            log.info("stopping commands (the bridge holds, then lands after its timeout)")
            self.phase = STOPPING
            self.commander.set_velocity(0.0, 0.0, 0.0, 0.0, now)
            self._stop_commanding_at = now + STOP_ZERO_S

    def _land(self, now: float) -> None:
        assert self._landing is not None
        try:
            if self._landing.step(now):
                self.phase = DONE
        except FlightError as exc:
            log.error("land failed: %s", exc)
            self.phase = DONE

    def _new_input(self, now: float) -> bool:
        """True (once) when new detections arrived or a control period passed."""
        count = self.detections.count
        if count == self._seen and now < self._next_control:
            return False
        self._seen = count
        self._next_control = now + self._period
        return True

    def _status_phase(self) -> str | None:
        """The state the status reports: the phase's, or None for the servo's own (also while
        its zero command goes out on the way to a stop)."""
        return STATUS_PHASE.get(self.phase)

    def _publish_status(self, phase: str | None) -> None:
        self._status_shown = phase
        status = self.loop.status(self.node.clock.time(), state=phase, seq=self._status.count)
        self._status.put(status)


PORTS = (
    Ports(
        "controller",
        publishes=(registry.CONTROLLER_STATUS,),
        subscribes=(registry.DETECTIONS,),
    )
    | CLIENT_PORTS
)
"""What the controller publishes, subscribes to and calls, its DroneClient's included
(:mod:`dronewrapper.runtime.ports`)."""


def commander_name() -> str:
    """Our name on the command lease, as the SDK names it (``$DRONEWRAPPER_COMMANDER``, the
    identity's name, or ``user@host``)."""
    return default_commander(os.environ.get("DRONEWRAPPER_IDENTITY", ""))


def run(node: NodeApi, config: Config) -> int:
    """The controller service on the node's clock (see the module doc); the exit status."""
    clock = node.clock
    commander = None if config.dry_run else DroneClient(node, name=commander_name())
    try:
        controller = Controller(node, config, commander)
        while True:
            now = clock.monotonic()
            controller.step(now)
            if controller.finished:
                return controller.exit_code
            controller.wait(controller.next_wake(now) - clock.monotonic())
    finally:
        if commander is not None:
            commander.close()
