"""The controller process: detections in, body-velocity commands out through the SDK.

Subscribes ``{ns}/perception/detections``; commands the aircraft with the DroneWrapper SDK
embedded on this process's Zenoh session (so setpoints go out on
``{ns}/mavros/setpoint_raw/local``, re-published at >= 20 Hz by the SDK, each carrying the
source camera frame's stamp); publishes ``{ns}/controller/status`` at ``status_rate_hz``.

Lifecycle: wait for the bridge -> announce ready -> take off to ``takeoff.height`` (if
``takeoff.on_start``) -> servo until SIGINT/SIGTERM -> land (``on_exit: land``) or send one
zero command and stop commanding (``on_exit: stop``). With ``dry_run`` no aircraft is involved:
announce ready -> servo until stopped, the commands only in the status.
"""

from __future__ import annotations

import contextlib
import logging
import math
import threading
import time

from dronewrapper.msgs import registry
from dronewrapper.msgs.control import (
    CONTROLLER_IDLE,
    CONTROLLER_LANDING,
    CONTROLLER_TAKEOFF,
)
from dronewrapper.msgs.vision import Detections
from dronewrapper.runtime import Latest, Node, Ratekeeper
from dronewrapper_controller.config import Config
from dronewrapper_controller.inputs import DetectionsGate
from dronewrapper_controller.loop import ControlLoop

log = logging.getLogger("controller")


class StatusPublisher:
    """Publishes the loop's status at a fixed rate on its own thread (also during take-off)."""

    def __init__(self, node: Node, loop: ControlLoop, rate_hz: float) -> None:
        self.phase: str | None = CONTROLLER_IDLE  # None: the servo's own state
        self._node = node
        self._loop = loop
        self._pub = node.publisher(registry.CONTROLLER_STATUS)
        self._stop = threading.Event()
        self._rate_hz = rate_hz
        self._thread = threading.Thread(target=self._run, name="controller-status", daemon=True)

    def start(self) -> None:
        self._thread.start()

    def publish_now(self) -> None:
        self._pub.put(self._loop.status(time.time(), state=self.phase, seq=self._pub.count))

    def _run(self) -> None:
        rate = Ratekeeper(self._rate_hz, stop=self._stop)
        while rate.sleep():
            try:
                self.publish_now()
            except Exception as exc:  # closing session at exit
                log.debug("status publish failed: %s", exc)

    def close(self) -> None:
        self._stop.set()
        self._thread.join(2.0)


def _open_drone(node: Node):
    from dronewrapper import DroneWrapper  # the SDK, embedded on this node's session

    # no cameras (the controller reads detections), no connection wait here (done below, so
    # a stop request can interrupt it), no idle deadman: hover/search commands stay valid.
    return DroneWrapper(name=node.ns, session=node.session, cameras=(), wait=False)


def _run_with_stop(node: Node, what: str, func, timeout: float) -> bool:
    """Run a blocking SDK call on a worker thread; False if it failed or a stop came first."""
    result: dict[str, BaseException | None] = {}

    def target() -> None:
        try:
            func()
            result["error"] = None
        except BaseException as exc:
            result["error"] = exc

    worker = threading.Thread(target=target, name=f"controller-{what}", daemon=True)
    worker.start()
    deadline = time.monotonic() + timeout
    while worker.is_alive() and time.monotonic() < deadline:
        if node.stop_event.wait(0.1):
            return False
    if worker.is_alive():
        log.error("%s did not finish within %.0f s", what, timeout)
        return False
    if result.get("error") is not None:
        log.error("%s failed: %s", what, result["error"])
        return False
    return True


def subscribe_detections(node: Node) -> Latest[Detections]:
    """The newest usable Detections: non-finite or out-of-range messages are counted in
    ``node.callback_errors`` under ``detections refused`` and dropped (logged at most every 2 s)."""
    holder: Latest[Detections] = Latest(name=registry.DETECTIONS.key(node.ns))
    last_log = [-math.inf]

    def on_drop(count: int, problem: str) -> None:
        node.callback_errors["detections refused"] += 1
        now = time.monotonic()
        if now - last_log[0] >= 2.0:
            last_log[0] = now
            log.warning("detections refused (%d so far): %s", count, problem)

    node.subscribe(registry.DETECTIONS, DetectionsGate(holder.update, on_drop))
    return holder


class Takeoff:
    """The SDK's blocking take-off on a worker thread, so the loop can watch meanwhile."""

    def __init__(self, drone, height: float, timeout: float) -> None:
        self.error: BaseException | None = None
        self._thread = threading.Thread(
            target=self._run, args=(drone, height, timeout), name="controller-takeoff", daemon=True
        )
        self._thread.start()

    def _run(self, drone, height: float, timeout: float) -> None:
        try:
            drone.takeoff(h=height, timeout=timeout)
        except BaseException as exc:
            self.error = exc

    @property
    def running(self) -> bool:
        return self._thread.is_alive()


def servo_until_stopped(
    node: Node,
    config: Config,
    loop: ControlLoop,
    drone,
    detections: Latest[Detections],
    takeoff: Takeoff | None,
    status: StatusPublisher,
) -> bool:
    """Wake on each new detections message (or every control period) and command the drone.

    While ``takeoff`` runs the loop only watches (where the target was last seen); False if
    the take-off failed.
    """
    period = 1.0 / config.rate_hz
    seen = detections.count
    logged_state = ""
    while not node.stopping:
        with contextlib.suppress(TimeoutError):
            detections.wait(period, newer_than=seen)
        seen = detections.count
        now = time.monotonic()
        if takeoff is not None:
            if takeoff.running:
                loop.servo.observe(now, detections.value, detections.age())
                continue
            if takeoff.error is not None:
                log.error("takeoff failed: %s", takeoff.error)
                return False
            log.info("take-off done")
            takeoff = None
            status.phase = None
        try:
            cmd = loop.tick(now, detections.value, detections.age())
        except ValueError as exc:  # never die on input: hover on the last command instead
            node.callback_errors["controller tick"] += 1
            log.error("control step failed, command unchanged: %s", exc)
            continue
        if cmd is None or drone is None:  # no drone: a dry run, the status shows the command
            continue
        stamp = cmd.source_stamp if cmd.source_stamp > 0 else None
        drone.set_cmd_vel(cmd.vx, 0.0, cmd.vz, cmd.yaw_rate, stamp=stamp)
        if cmd.state != logged_state:
            log.info("state %s", cmd.state)
            logged_state = cmd.state
    return True


def shutdown(config: Config, drone, status: StatusPublisher) -> None:
    """Land and wait, or send a zero command and stop commanding (the bridge then hovers)."""
    if config.on_exit == "land":
        status.phase = CONTROLLER_LANDING
        log.info("landing")
        try:
            drone.land(timeout=config.land_timeout)
        except Exception as exc:
            log.error("land failed: %s", exc)
    else:
        log.info("stopping commands (the bridge holds, then lands after its timeout)")
        try:
            drone.set_cmd_vel(0.0, 0.0, 0.0, 0.0)
            time.sleep(0.2)  # a few zero setpoints go out before the stream stops
            drone.stop_commanding()
        except Exception as exc:
            log.error("stop failed: %s", exc)


def run_dry(node: Node, config: Config, loop: ControlLoop, status: StatusPublisher) -> int:
    """``dry_run``: servo on the detections with no aircraft; commands go only in the status."""
    log.info("%s dry run: commands are shown in the status, not sent", config.mode)
    node.announce()
    status.phase = None
    detections = node.latest(registry.DETECTIONS)
    servo_until_stopped(node, config, loop, None, detections, None, status)
    return 0


def run(node: Node, config: Config) -> int:
    """The controller service (see the module doc)."""
    loop = ControlLoop(config)
    status = StatusPublisher(node, loop, config.status_rate_hz)
    status.start()
    if config.dry_run:
        try:
            return run_dry(node, config, loop, status)
        finally:
            status.close()
    drone = _open_drone(node)
    try:
        log.info("%s on %s: waiting for the bridge", config.mode, config.aircraft)
        if not _run_with_stop(
            node,
            "wait for the bridge",
            lambda: drone.wait_for_connection(config.ready_timeout),
            config.ready_timeout + 1,
        ):
            return 0 if node.stopping else 1
        node.announce()
        detections = subscribe_detections(node)
        takeoff = None
        if config.takeoff.on_start:
            status.phase = CONTROLLER_TAKEOFF
            log.info("taking off to %.1f m", config.takeoff.height)
            takeoff = Takeoff(drone, config.takeoff.height, config.takeoff.timeout)
        else:
            status.phase = None
        ok = servo_until_stopped(node, config, loop, drone, detections, takeoff, status)
        shutdown(config, drone, status)
        return 0 if ok else 1
    finally:
        status.close()
        drone.close()
