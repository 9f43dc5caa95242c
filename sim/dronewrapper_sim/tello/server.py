"""The simulated Tello process: the SDK on UDP, the flight in real time, the world on Zenoh.

One main loop (this thread) steps the flight at ``physics_rate_hz`` (simulated time = wall
time), answers each datagram on ``A:8889`` as soon as it arrives (``select``), sends the state
datagram at 10 Hz to the host of the last ``command`` sender on the state port, steps the world
and publishes ``{ns}/sim/ground_truth`` and ``sim/objects/{name}/pose`` like the Iris sim. After
``streamon`` the video thread renders the forward camera from the true pose, encodes H.264 and
sends it to the same host on the video port.
"""

from __future__ import annotations

import contextlib
import logging
import select
import socket
import threading
from dataclasses import replace
from typing import Any

from dronewrapper.rotations import quat_from_rpy
from dronewrapper.runtime.clock import REAL, Clock
from dronewrapper.runtime.contract import NodeApi
from dronewrapper_sim.dynamics import WindModel
from dronewrapper_sim.pose_snapshot import PoseSnapshot
from dronewrapper_sim.tello.config import TelloConfig
from dronewrapper_sim.tello.flight import TelloFlight
from dronewrapper_sim.tello.params import TELLO
from dronewrapper_sim.tello.protocol import Reply, TelloProtocol
from dronewrapper_sim.tello.state_string import format_state
from dronewrapper_sim.world.scenario import Scenario
from dronewrapper_sim.world_topics import WorldTopics

log = logging.getLogger("sim.tello")

COMMAND_PORT = 8889
MAX_DATAGRAMS_PER_WAKE = 64  # a flood cannot starve the physics: at most this many per tick
MAX_CATCH_UP_STEPS = 20
GROUND_TRUTH_RATE_HZ = 50.0
OBJECT_POSE_RATE_HZ = 20.0


class TelloServer:
    """One simulated Tello and its world, run in real time (see module doc).

    Args:
        config: the Tello's settings.
        scenario: the world (and the start pose).
        node: the Zenoh node for ground truth, object poses and teleop (None: UDP only).
        command_socket: the bound ``A:8889`` socket (made by the caller: it may live in
            another network namespace).
        seed: the world's random seed.
    """

    def __init__(
        self,
        config: TelloConfig,
        scenario: Scenario,
        node: NodeApi | None,
        command_socket: socket.socket,
        seed: int | None = None,
    ) -> None:
        from dronewrapper_sim.world.world import World

        self.config = config
        self.scenario = scenario
        self.node = node
        self.time: Clock = REAL if node is None else node.clock  # its pacing and stamps
        seed_override = seed  # None: each scenario loaded later uses its own seed
        seed = scenario.seed if seed is None else seed
        self.world = World(scenario, seed=seed)
        self.world_lock = threading.Lock()
        wind = scenario.wind
        self.flight = TelloFlight(
            start=(scenario.vehicle.x, scenario.vehicle.y, scenario.vehicle.yaw),
            wind=WindModel(wind.east_m_s, wind.north_m_s, wind.gust_m_s, seed=seed),
            envelope=replace(TELLO, auto_land_s=config.auto_land_s),
            battery_percent=config.battery_percent,
        )
        self.protocol = TelloProtocol(self.flight, baro_origin_m=scenario.home.altitude_m)
        self.sock = command_socket
        self.lock = threading.Lock()  # flight + protocol, shared with the video thread
        self.video: Any = None
        self.datagrams = 0
        self.replies = 0
        self.states = 0
        self.send_errors = 0
        self._snapshot = self._make_snapshot()
        self.world_topics = (
            WorldTopics(
                node, self.world, self.world_lock, seed=seed_override, reset_vehicle=self.reset
            )
            if node is not None
            else None
        )

    @property
    def address(self) -> tuple[str, int]:
        """The command socket's address."""
        return self.sock.getsockname()

    def snapshot(self) -> PoseSnapshot:
        """The latest true pose (ENU, FLU->ENU quaternion)."""
        return self._snapshot

    def describe(self) -> str:
        host, port = self.address
        return (
            f"Tello SDK on udp {host}:{port}, scenario {self.scenario.name}, "
            f"video {'on streamon' if self.video is not None else 'off'}, "
            f"namespace {self.node.ns if self.node else '-'}"
        )

    # ---- the loop ----

    def run(self, stop: threading.Event, duration_s: float | None = None) -> None:
        """Run until ``stop`` is set (or ``duration_s`` of its clock passed)."""
        if self.video is not None:
            self.video.start()
        dt = 1.0 / self.config.physics_rate_hz
        start = self.time.monotonic()
        t0 = start
        steps = 0
        state_period = 1.0 / self.config.state_rate_hz
        next_state = start
        next_gt = next_obj = start
        while not stop.is_set():
            now = self.time.monotonic()
            if duration_s is not None and now - start >= duration_s:
                break
            next_tick = t0 + (steps + 1) * dt
            wait = min(max(next_tick - now, 0.0), 0.05)
            readable, _, _ = select.select([self.sock], [], [], wait)
            if readable:
                self._receive()
            now = self.time.monotonic()
            if now < next_tick:
                continue
            owed = int((now - t0) / dt) - steps
            if owed > MAX_CATCH_UP_STEPS:  # a long stall: slip the clock, do not burst
                t0 += (owed - MAX_CATCH_UP_STEPS) * dt
                owed = MAX_CATCH_UP_STEPS
            replies: list[Reply] = []
            with self.lock:
                for _ in range(owed):
                    replies += self.protocol.tick(dt, now)
                self._snapshot = self._make_snapshot()
            steps += owed
            with self.world_lock:
                self.world.step(owed * dt)
            self._send(replies)
            if now >= next_state:
                next_state = max(next_state + state_period, now)
                self._send_state()
            if now >= next_gt:
                next_gt = max(next_gt + 1.0 / GROUND_TRUTH_RATE_HZ, now)
                if self.world_topics is not None:
                    self.world_topics.publish_ground_truth(self._snapshot)
            if now >= next_obj:
                next_obj = max(next_obj + 1.0 / OBJECT_POSE_RATE_HZ, now)
                if self.world_topics is not None:
                    self.world_topics.publish_objects()

    def reset(self) -> str:
        """Put the Tello back at its start pose, landed, motors off."""
        with self.lock:
            self.flight.reset_to_start()
            self._snapshot = self._make_snapshot()
        x, y, _ = self.flight.start
        return f"Tello back at its start ({x:g}, {y:g}) m, landed, motors off"

    def _receive(self) -> None:
        for _ in range(MAX_DATAGRAMS_PER_WAKE):
            try:
                data, sender = self.sock.recvfrom(65535)
            except (BlockingIOError, InterruptedError):
                return
            except OSError:  # e.g. ICMP port unreachable reported on the socket
                continue
            self.datagrams += 1
            with self.lock:
                replies = self.protocol.handle(data, sender, self.time.monotonic())
            self._send(replies)

    def _send(self, replies: list[Reply]) -> None:
        for reply in replies:
            try:
                self.sock.sendto(reply.text.encode("utf-8"), reply.address)
                self.replies += 1
            except OSError:
                self.send_errors += 1

    def _send_state(self) -> None:
        session = self.protocol.session
        if not self.protocol.sdk_mode or session.client is None:
            return
        with self.lock:
            text = format_state(self.protocol)
        try:
            self.sock.sendto(text.encode("ascii"), (session.client[0], session.state_port))
            self.states += 1
        except OSError:
            self.send_errors += 1

    def _make_snapshot(self) -> PoseSnapshot:
        s = self.flight.state
        return PoseSnapshot(
            (s.x, s.y, s.z), quat_from_rpy(s.roll, s.pitch, s.yaw), self.time.time()
        )

    def close(self) -> None:
        """Stop the video thread and close the socket."""
        if self.video is not None:
            self.video.close()
        with contextlib.suppress(OSError):
            self.sock.close()
