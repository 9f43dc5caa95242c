"""The simulator's PX4-like autopilot through the full offboard sequence, in simulated time.

:class:`Vehicle` steps the autopilot (250 Hz physics, its links polled every 16 ms, as the
simulator's loop does) and carries every message both ways as real MAVLink 2 bytes between
it and two clients, a companion (``onboard``) and a ground station (``gcs``), each with its
2 Hz heartbeat and a 20 Hz setpoint stream. Nothing waits: every time here is the
vehicle's own, so rates and delays are exact however loaded the machine. The same autopilot
behind real UDP sockets in a real process (heartbeat ids, the offboard-loss failsafe,
parameters, intervals, bad bytes, a clean exit) is held by tests/integration/test_sim_mavlink.py.
"""

from __future__ import annotations

import math
import os
from collections.abc import Callable

os.environ.setdefault("MAVLINK20", "1")

import pytest
from mavlink_log import MessageLog
from mavlink_setpoints import FRAME_BODY_NED, FRAME_LOCAL_NED, setpoint
from pymavlink.dialects.v20 import common as mavlink

from dronewrapper_sim.px4 import telemetry
from dronewrapper_sim.px4.autopilot import Autopilot, AutopilotConfig
from dronewrapper_sim.px4.modes import Mode

PHYSICS_S = 1.0 / 250.0
"""One physics step (s)."""
POLL_S = 0.016
"""How often the autopilot's links are polled (s)."""


class Client(MessageLog):
    """A MAVLink endpoint of the vehicle's ``link``: keeps every message it is sent with the
    vehicle's time, sends a heartbeat every 0.5 s once it has heard the vehicle, and streams
    ``setpoint`` at 20 Hz while it is set."""

    def __init__(self, vehicle: Vehicle, link: str, mav_type: int, sysid: int = 245) -> None:
        super().__init__()
        self.vehicle, self.link, self.mav_type = vehicle, link, mav_type
        self.out = mavlink.MAVLink(None, srcSystem=sysid, srcComponent=191)
        self.parser = mavlink.MAVLink(None)
        self.heard = False
        self.setpoint: object | None = None
        self.setpoint_period = 0.05
        self.last_setpoint_sent = -math.inf
        self.heartbeats_sent = 0
        self._next_hb = self._next_sp = 0.0
        vehicle.clients[link] = self

    def receive(self, data: bytes) -> None:
        self.heard = True
        for msg in self.parser.parse_buffer(data) or []:
            self.log.append((self.vehicle.now, msg))

    def tick(self, now: float) -> None:
        if self.heard and now >= self._next_hb:
            self._next_hb = now + 0.5
            self.send(mavlink.MAVLink_heartbeat_message(self.mav_type, 8, 0, 0, 4, 3))
            self.heartbeats_sent += 1
        if now >= self._next_sp:
            self._next_sp = now + self.setpoint_period
            if self.setpoint is not None and self.heard:
                self.send(self.setpoint)
                self.last_setpoint_sent = now

    def send(self, msg) -> None:
        assert self.heard, "no datagram from the vehicle yet"
        data = msg.pack(self.out)
        self.out.seq = (self.out.seq + 1) % 256
        self.vehicle.receive(self.link, data)

    def stop_stream(self) -> float:
        self.setpoint = None
        return self.last_setpoint_sent

    # ---- reading: MessageLog ----

    def wait_until(self, found, timeout: float, what: str):
        return self.vehicle.run_until(found, timeout, what)

    # ---- commands ----

    def command(self, command: int, *p: float, expect: int = 1, timeout: float = 10.0) -> list:
        """COMMAND_LONG; every ACK for it: waits for ``expect``, then 0.3 s more."""
        t0 = self.vehicle.now
        p7 = [*p, *[0.0] * (7 - len(p))]
        self.send(mavlink.MAVLink_command_long_message(1, 1, command, 0, *p7))

        def replies() -> list:
            return [m for m in self.since(t0, "COMMAND_ACK") if m.command == command]

        self.vehicle.run_until(lambda: len(replies()) >= expect, timeout, f"ACK of {command}")
        self.vehicle.run(0.3)
        return replies()

    def set_mode(self, mode: Mode) -> list:
        return self.command(176, 1, mode.main, mode.sub, expect=2)  # PX4 acks a mode twice

    def sync_heartbeat(self) -> None:
        """Once the vehicle has handled one of this client's heartbeats (a GCS then gets
        STATUSTEXT)."""
        self.vehicle.run_until(lambda: self.heartbeats_sent > 0, 10, "our first heartbeat")

    def wait_heartbeat(self, pred, timeout: float, t0: float | None = None):
        return self.wait_msg("HEARTBEAT", pred, timeout, self.vehicle.now if t0 is None else t0)

    def stream(self, vx=0.0, vy=0.0, vz=0.0, yaw_rate=0.0, frame=FRAME_BODY_NED, **pos) -> None:
        self.setpoint = setpoint(vx, vy, vz, yaw_rate, frame, **pos)


class Vehicle:
    """The autopilot with an onboard and a GCS link at the simulator's rates; ``now``: its
    time (s since boot)."""

    def __init__(self) -> None:
        rates = {"onboard": telemetry.ONBOARD_RATES, "gcs": telemetry.GCS_RATES}
        self.autopilot = Autopilot(AutopilotConfig(), link_rates=rates)
        self.out = mavlink.MAVLink(None, srcSystem=1, srcComponent=1)
        self.parsers = {link: mavlink.MAVLink(None) for link in rates}
        self.clients: dict[str, Client] = {}
        self._polled = 0.0

    @property
    def now(self) -> float:
        return self.autopilot.time_s

    def receive(self, link: str, data: bytes) -> None:
        """Bytes from a client handled on ``link`` at once; the replies sent back."""
        for msg in self.parsers[link].parse_buffer(data) or []:
            self._send(link, self.autopilot.handle(link, msg))

    def _send(self, link: str, msgs: list) -> None:
        for msg in msgs:
            data = msg.pack(self.out)
            self.out.seq = (self.out.seq + 1) % 256
            if link in self.clients:
                self.clients[link].receive(data)

    def step(self) -> None:
        """One poll period: the clients' heartbeats and setpoints due, then the physics."""
        for client in self.clients.values():
            client.tick(self.now)
        end = self._polled + POLL_S
        while self.autopilot.time_s + PHYSICS_S <= end + 1e-9:
            self.autopilot.step(PHYSICS_S)
        self._polled = self.autopilot.time_s
        for link, msgs in self.autopilot.poll().items():
            self._send(link, msgs)

    def run(self, seconds: float) -> None:
        end = self.now + seconds
        while self.now < end - 1e-9:
            self.step()

    def run_until(self, predicate: Callable[[], object], timeout: float, what: str):
        """Step until ``predicate()`` (checked every poll period), at most ``timeout`` s of
        the vehicle's time; its value."""
        end = self.now + timeout
        while not (value := predicate()):
            assert self.now < end, f"not within {timeout:g} s (simulated): {what}"
            self.step()
        return value


def acks(replies: list) -> list[int]:
    return [m.result for m in replies]


def divmod_mode(custom_mode: int) -> tuple[int, int]:
    main, sub = (custom_mode >> 16) & 0xFF, (custom_mode >> 24) & 0xFF
    return (main, sub if main == 4 else 0)


def yaw_of(client: Client) -> float:
    return client.latest("ATTITUDE").yaw


def turned_from(start_yaw: float, yaw: float) -> float:
    """The signed turn (rad, NED: clockwise > 0) from ``start_yaw`` to ``yaw``."""
    return math.remainder(yaw - start_yaw, math.tau)


def boot_s(msg) -> float:
    """The vehicle's simulated time (s since boot) stamped on ``msg``."""
    return msg.time_boot_ms / 1000.0


def test_full_px4_offboard_sequence():
    vehicle = Vehicle()
    onboard = Client(vehicle, "onboard", mavlink.MAV_TYPE_ONBOARD_CONTROLLER)
    gcs = Client(vehicle, "gcs", mavlink.MAV_TYPE_GCS)
    vehicle.run_until(lambda: onboard.latest("HEARTBEAT"), 30, "first HEARTBEAT")
    vehicle.run_until(lambda: gcs.latest("HEARTBEAT"), 10, "HEARTBEAT on the GCS link")
    hb = onboard.latest("HEARTBEAT")
    assert (hb.type, hb.autopilot, hb.base_mode) == (2, 12, 29)
    gcs.sync_heartbeat()  # the vehicle knows the GCS now: it gets STATUSTEXT

    # OFFBOARD while disarmed with no stream: accepted (acked twice), arming then refused
    mode_acks = onboard.set_mode(Mode.OFFBOARD)
    assert acks(mode_acks) == [mavlink.MAV_RESULT_ACCEPTED] * 2
    assert mode_acks[0].get_seq() != mode_acks[1].get_seq()
    t_deny = vehicle.now
    assert acks(onboard.command(mavlink.MAV_CMD_COMPONENT_ARM_DISARM, 1)) == [
        mavlink.MAV_RESULT_TEMPORARILY_REJECTED
    ]
    gcs.wait_msg("STATUSTEXT", lambda m: "Arming denied" in m.text, 10, t_deny)
    assert onboard.texts() == []  # a companion (non-GCS) link gets no STATUSTEXT

    # stream > 1 s, then OFFBOARD and arm are accepted; climb in body frame (vz up = -1.5)
    t_stream = vehicle.now
    onboard.stream(vz=-1.5)
    vehicle.run_until(lambda: onboard.last_setpoint_sent >= t_stream, 10, "the stream")
    vehicle.run(1.2)
    assert acks(onboard.set_mode(Mode.OFFBOARD)) == [mavlink.MAV_RESULT_ACCEPTED] * 2
    assert acks(onboard.command(mavlink.MAV_CMD_COMPONENT_ARM_DISARM, 1)) == [
        mavlink.MAV_RESULT_ACCEPTED
    ]
    onboard.wait_heartbeat(lambda m: m.base_mode & 128, 6)
    vehicle.run_until(lambda: onboard.latest("LOCAL_POSITION_NED").z < -4.0, 20, "climb to 4 m")
    assert onboard.latest("EXTENDED_SYS_STATE").landed_state == mavlink.MAV_LANDED_STATE_IN_AIR

    # turn with a yaw rate (NED yaw rate > 0 = clockwise) of 0.5 rad/s, as in the PX4 trial
    # (97 degrees in 3.4 s), judged in simulated time (ATTITUDE.time_boot_ms)
    start_yaw = yaw_of(onboard)
    t_turn = vehicle.now
    onboard.stream(yaw_rate=0.5)
    vehicle.run_until(
        lambda: turned_from(start_yaw, yaw_of(onboard)) > math.radians(90), 20, "turn 90 deg"
    )
    t_stop = vehicle.now
    onboard.stream()
    turning = [
        m
        for t, m in onboard.timed(t_turn, "ATTITUDE")
        if t <= t_stop and math.radians(20) < turned_from(start_yaw, m.yaw) < math.radians(85)
    ]
    assert len(turning) > 20, len(turning)
    first, last = turning[0], turning[-1]
    rate = turned_from(first.yaw, last.yaw) / (boot_s(last) - boot_s(first))
    assert 0.42 < rate < 0.58, f"steady yaw rate {rate:.3f} rad/s, commanded 0.5"
    vehicle.run_until(lambda: abs(onboard.latest("ATTITUDE").yawspeed) < 0.05, 10, "turn stopped")
    turned = turned_from(start_yaw, yaw_of(onboard))
    assert math.radians(90) < turned < math.radians(150), math.degrees(turned)
    yaw = yaw_of(onboard)

    # body velocity: forward goes along the heading, right goes 90 degrees clockwise from it
    def moving(speed: float, heading: float):
        def check() -> bool:
            lpn = onboard.latest("LOCAL_POSITION_NED")
            direction = math.atan2(lpn.vy, lpn.vx)  # NED: atan2(east, north) = heading
            along = abs(math.remainder(direction - heading, math.tau)) < math.radians(15)
            return math.hypot(lpn.vx, lpn.vy) > 0.8 * speed and along

        return check

    for body, heading in (((2.0, 0.0), yaw), ((0.0, 1.5), yaw + math.pi / 2)):
        onboard.stream(vx=body[0], vy=body[1])
        vehicle.run_until(moving(math.hypot(*body), heading), 15, f"body velocity {body}")

    # local NED velocity: north whatever the heading
    onboard.stream(vx=1.5, frame=FRAME_LOCAL_NED)
    vehicle.run_until(moving(1.25, 0.0), 15, "north in the local frame")  # > 1 m/s north

    # local position and yaw
    onboard.stream(x=2.0, y=-3.0, z=-3.0, yaw=0.0)

    def at_position():
        p = onboard.latest("LOCAL_POSITION_NED")
        near = math.dist((p.x, p.y, p.z), (2.0, -3.0, -3.0)) < 0.4
        return near and abs(yaw_of(onboard)) < 0.15

    vehicle.run_until(at_position, 30, "reach the position and yaw setpoint")
    t_target = vehicle.now
    target = onboard.wait_msg("POSITION_TARGET_LOCAL_NED", timeout=10, t0=t_target)
    assert (target.x, target.y, target.z) == pytest.approx((2.0, -3.0, -3.0))

    # land: AUTO.LAND, "Landing detected", auto-disarm, then the intended mode (OFFBOARD) again
    t_land = vehicle.now
    assert acks(onboard.command(21, *[math.nan] * 7)) == [mavlink.MAV_RESULT_ACCEPTED]
    onboard.wait_heartbeat(lambda m: divmod_mode(m.custom_mode) == Mode.LAND.value, 6, t_land)
    onboard.stop_stream()
    disarmed = onboard.wait_heartbeat(lambda m: not m.base_mode & 128, 40, t_land)
    assert divmod_mode(disarmed.custom_mode) == Mode.OFFBOARD.value
    for text in ("Landing detected", "Disarmed by landing"):
        gcs.wait_msg("STATUSTEXT", lambda m, text=text: text in m.text, 10, t_land)
    assert onboard.latest("EXTENDED_SYS_STATE").landed_state == mavlink.MAV_LANDED_STATE_ON_GROUND
    assert onboard.latest("LOCAL_POSITION_NED").z == pytest.approx(0.0, abs=0.05)
