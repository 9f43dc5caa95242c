"""The bridge's logic in-process, over real UDP MAVLink and a real Zenoh router.

The autopilot is a small pymavlink peer in this file (a scripted PX4: DO_SET_MODE acked twice,
ACCEPTED then the commander's real result, refusals of modes that need RC with STATUSTEXT,
int32 params as raw bits; or a scripted ArduCopter: one ack, position targets in
GUIDED override its take-off, disarm 10 s after arming on the ground), so each rule of the
contract can be checked exactly on the wire. Each rule is tested at the core in given time
(tests/unit/test_bridge_core*.py); the tests here prove the wiring: threads, sockets, Zenoh
keys, stream rates. Flights against the simulator are in tests/integration; against real
ArduCopter SITL in tests/sitl.

Size: the scripted PX4 and ArduCopter peers and the five wiring tests that drive them are read
together.
"""

from __future__ import annotations

import itertools
import math
import os
import threading
import time
from collections.abc import Iterator

import pytest

os.environ.setdefault("MAVLINK20", "1")

from bridge_rig import reaches_bridge
from pymavlink import mavutil
from targets import velocity

from dronewrapper.msgs import registry
from dronewrapper.msgs.geometry import Point, Vector3
from dronewrapper.msgs.mavros import (
    FRAME_BODY_NED,
    MASK_POSITION,
    MASK_VELOCITY,
    CommandBool,
    CommandTOL,
    ParamGet,
    ParamSet,
    ParamValue,
    PositionTarget,
    SetMode,
)
from dronewrapper.runtime import ServiceError
from dronewrapper_bridge_mavlink.link import MavLink
from dronewrapper_bridge_mavlink.node import Bridge, Config
from dronewrapper_bridge_mavlink.outgoing import CommandLong, Send, SetPositionTargetLocalNed
from support import client_node, free_port, start_daemons, stop_daemons, wait_for

OFFBOARD = 6 << 16
POSCTL = 3 << 16
ALTCTL = 2 << 16
AUTO_LAND = (4 << 16) | (6 << 24)
AUTO_LOITER = (4 << 16) | (3 << 24)
ARMED = 128


class FakePX4:
    """A scripted PX4 (or, with ``autopilot=3``, ArduCopter) on a real UDP socket: sends
    telemetry, answers commands, logs traffic.

    ArduCopter as measured against its SITL (issue 21): NAV_TAKEOFF in GUIDED, armed, climbs
    (``climb_rate`` m/s to the requested height) unless a position target arrives after it
    (ArduCopter obeys the target instead: a ground-level hold keeps the motors idle), and it
    disarms itself ``disarm_delay`` s (10) after arming if it never left the ground.
    """

    def __init__(self, bridge_port: int, autopilot: int = 12, disarm_delay: float = 10.0) -> None:
        self.autopilot = autopilot  # MAV_AUTOPILOT: 12 PX4, 3 ArduPilot
        self.disarm_delay = disarm_delay
        self.climb_rate = 2.0
        self.climb_to: float | None = None  # ArduCopter: take-off height above the start, m
        self.takeoff_overridden = False
        self.armed_at = math.inf
        self.refuse_modes: dict[int, str] = {}  # PX4 custom_mode -> the commander's reason
        self.heartbeat_every = 10  # ticks of 20 ms (5 Hz keeps tests short; PX4 sends 1 Hz)
        self.conn = mavutil.mavlink_connection(
            f"udpout:127.0.0.1:{bridge_port}", source_system=1, source_component=1
        )
        self.custom_mode = AUTO_LOITER
        self.armed = False
        self.landed_state = 1
        self.position_ned = (0.0, 0.0, 0.0)
        self.yaw_ned = math.pi / 2  # facing east
        self.heartbeats = True
        self.setpoints: list[tuple[float, object]] = []
        self.commands: list[tuple[float, object]] = []
        self.gcs_heartbeats = 0
        self.params = {"COM_OF_LOSS_T": (1.0, 9), "COM_RC_IN_MODE": (1, 6)}
        self._stop = threading.Event()
        self._lock = threading.Lock()
        self._threads = start_daemons(self._send_loop, self._recv_loop)

    def close(self) -> None:
        stop_daemons(self._stop, self._threads)
        self.conn.close()

    def send(self, name: str, *args, **kw) -> None:
        with self._lock:
            getattr(self.conn.mav, f"{name}_send")(*args, **kw)

    def _send_loop(self) -> None:
        tick = 0
        while not self._stop.wait(0.02):  # 50 Hz
            tick += 1
            if self.autopilot == 3:
                self._arducopter_step(0.02)
            n, e, d = self.position_ned
            self.send("local_position_ned", tick * 20, n, e, d, 0.0, 0.0, 0.0)
            self.send("attitude", tick * 20, 0.0, 0.0, self.yaw_ned, 0.0, 0.0, 0.0)
            if tick % 10 == 0:
                self.send("extended_sys_state", 0, self.landed_state)
                self.send("sys_status", 0, 0, 0, 0, 12100, 500, 80, 0, 0, 0, 0, 0, 0)
            if tick % self.heartbeat_every == 0 and self.heartbeats:
                base = 29 | (ARMED if self.armed else 0)
                self.send("heartbeat", 2, self.autopilot, base, self.custom_mode, 4)

    def _arducopter_step(self, dt: float) -> None:
        n, e, d = self.position_ned
        if self.armed and self.climb_to is not None:
            d = max(-self.climb_to, d - self.climb_rate * dt)
            self.position_ned = (n, e, d)
            self.landed_state = 2 if d < -0.2 else self.landed_state
        if self.armed and self.custom_mode == 9:  # LAND: 1 m/s down, disarm on the ground
            self.climb_to = None
            d = min(0.0, d + 1.0 * dt)
            self.position_ned = (n, e, d)
            if d >= 0.0:
                self.armed, self.landed_state = False, 1
                self.send("statustext", 6, b"Disarming motors")
            return
        if self.armed and d > -0.2 and time.monotonic() - self.armed_at >= self.disarm_delay:
            self.armed, self.climb_to = False, None
            self.send("statustext", 6, b"Disarming motors")

    def _on_setpoint_arducopter(self, msg) -> None:
        position_ignored = msg.type_mask & 0b111 == 0b111
        if self.custom_mode == 4 and not position_ignored and self.climb_to is not None:
            self.climb_to = None  # GUIDED obeys the position target, not the take-off
            self.takeoff_overridden = True

    def _recv_loop(self) -> None:
        while not self._stop.is_set():
            msg = self.conn.recv_match(blocking=True, timeout=0.1)
            if msg is None:
                continue
            now = time.monotonic()
            kind = msg.get_type()
            if kind == "HEARTBEAT" and msg.type == 6:
                self.gcs_heartbeats += 1
            elif kind == "SET_POSITION_TARGET_LOCAL_NED":
                self.setpoints.append((now, msg))
                if self.autopilot == 3:
                    self._on_setpoint_arducopter(msg)
            elif kind == "COMMAND_LONG":
                self.commands.append((now, msg))
                self._on_command(msg)
            elif kind == "PARAM_REQUEST_READ":
                self._param_value(msg.param_id)
            elif kind == "PARAM_SET":
                _value, ptype = self.params[msg.param_id]
                self.params[msg.param_id] = (
                    _bits_to_int(msg.param_value)
                    if ptype == 6 and self.autopilot != 3
                    else msg.param_value,
                    ptype,
                )
                self._param_value(msg.param_id)

    def _param_value(self, name: str) -> None:
        value, ptype = self.params[name]
        # PX4 carries int32 bits in the float; ArduPilot casts the value to float
        bits = ptype == 6 and self.autopilot != 3
        wire = _int_to_bits(int(value)) if bits else float(value)
        self.send("param_value", name.encode(), wire, ptype, len(self.params), 0)

    def _on_command(self, msg) -> None:
        if msg.command == 176 and self.autopilot == 3:  # ArduCopter: mode number, one ack
            self.custom_mode = int(msg.param2)
            self.send("command_ack", 176, 0)
        elif msg.command == 176:  # PX4: the receiver's ACCEPTED, then the commander's result
            wanted = (int(msg.param2) << 16) | (int(msg.param3) << 24)
            self.send("command_ack", 176, 0)
            refusal = self.refuse_modes.get(wanted)
            if refusal is None and self.armed and wanted in (POSCTL, ALTCTL):  # no RC here
                name = "Position" if wanted == POSCTL else "Altitude"
                refusal = f"Switching to {name} is currently not available"
            if refusal is not None:
                self.send("command_ack", 176, 1)
                self.send("statustext", 2, f"{refusal}\t".encode())
                return
            self.custom_mode = wanted
            self.send("command_ack", 176, 0)  # the commander's (second) ack
        elif msg.command == 400:
            self.armed = msg.param1 == 1
            self.armed_at = time.monotonic()
            self.send("command_ack", 400, 0)
        elif msg.command == 21:
            self.custom_mode = 9 if self.autopilot == 3 else AUTO_LAND
            self.send("command_ack", 21, 0)
        elif msg.command == 22 and self.autopilot == 3:
            ok = self.armed and self.custom_mode == 4  # ArduCopter: armed, in GUIDED
            if ok:
                self.climb_to = msg.param7
            self.send("command_ack", 22, 0 if ok else 4)
        elif msg.command in (22, 511):
            self.send("command_ack", msg.command, 0)
        else:
            self.send("command_ack", msg.command, 3)

    def commands_named(self, command: int) -> list:
        return [m for _, m in list(self.commands) if m.command == command]


def _int_to_bits(value: int) -> float:
    import struct

    return struct.unpack("<f", struct.pack("<i", value))[0]


def _bits_to_int(value: float) -> int:
    import struct

    return struct.unpack("<i", struct.pack("<f", value))[0]


class TappedLink(MavLink):
    """The bridge's real link, also noting when (monotonic s) each message left and its fields.

    Timing checks use these send times: the fake autopilot's receive times include however long
    its Python thread waited for the GIL on a busy machine.
    """

    def __init__(self, *args, **kwargs) -> None:
        super().__init__(*args, **kwargs)
        self.log: list[tuple[float, Send]] = []

    def send(self, message: Send) -> bool:
        self.log.append((time.monotonic(), message))
        return super().send(message)

    def setpoints(self, type_mask: int) -> list[float]:
        """Send times of the SET_POSITION_TARGET_LOCAL_NED with this type_mask."""
        return [
            t
            for t, message in list(self.log)
            if isinstance(message, SetPositionTargetLocalNed)
            and message.target.type_mask == type_mask
        ]

    def command_times(self, command: int) -> list[float]:
        """Send times of the COMMAND_LONGs of this MAV_CMD (retries included)."""
        return [
            t
            for t, message in list(self.log)
            if isinstance(message, CommandLong) and message.command == command
        ]


@pytest.fixture
def rig(router) -> Iterator[tuple[Bridge, FakePX4, object]]:
    yield from make_rig(router, autopilot=12)


@pytest.fixture
def ardu_rig(router) -> Iterator[tuple[Bridge, FakePX4, object]]:
    yield from make_rig(router, autopilot=3)


def make_rig(router, autopilot: int) -> Iterator[tuple[Bridge, FakePX4, object]]:
    port = free_port(2)
    # Generous ack and reason waits: the fake always answers at once, but its thread may wait
    # for the GIL on a busy machine, and a retry would look like a second command on the wire.
    config = Config(
        connection=f"udpin:127.0.0.1:{port}",
        commander_lost_timeout=2.0,
        command_ack_timeout=1.5,
        reason_wait=2.0,
    )
    bridge_node = client_node(router, name="bridge_mavlink")
    link = TappedLink(
        config.connection,
        source_system=config.source_system,
        source_component=config.source_component,
    )
    bridge = Bridge(bridge_node, config, link=link)
    threads = bridge.start()
    fake = FakePX4(port, autopilot)
    if autopilot == 3:
        fake.custom_mode = 5  # LOITER
    user = client_node(router, name="user")
    try:
        wait_for(lambda: bridge.core.connected, 20, what="bridge connected to the fake PX4")
        wait_for(lambda: reaches_bridge(user), 20, what="the user's session to reach the bridge")
        yield bridge, fake, user
    finally:
        user.close()
        bridge_node.stop()
        for t in threads:
            t.join(3)
        bridge.link.close()
        bridge_node.close()
        fake.close()


def median_gap(times: list[float]) -> float:
    """The median interval between successive times (s): a rate check that a busy machine's
    occasional stall of the whole process (a lost tick or two) does not fail, while a stream
    slower than the bound shifts every interval."""
    gaps = sorted(b - a for a, b in itertools.pairwise(times))
    return gaps[len(gaps) // 2] if gaps else math.inf


def stream(pub, target, seconds: float, hz: float = 30.0) -> float:
    """Publish ``target`` at ``hz`` (the SDK's stream rate) for ``seconds``; returns the time
    just before the last put. The bridge forwards each setpoint once, so its rate is the
    commander's: a sleep-paced "20 Hz" loop runs just under 20 Hz."""
    end = time.monotonic() + seconds
    last = time.monotonic()
    while time.monotonic() < end:
        last = time.monotonic()
        pub.put(target)
        time.sleep(1.0 / hz)
    return last


def test_telemetry_in_enu_and_state(rig):
    _bridge, fake, user = rig
    fake.position_ned = (5.0, 2.0, -3.0)
    pose = user.latest(registry.LOCAL_POSE)
    state = user.latest(registry.STATE)
    battery = user.latest(registry.BATTERY)
    texts = user.latest(registry.STATUSTEXT)
    p = wait_for(lambda: pose.value if pose.value and pose.value.pose.position.z > 2 else None, 15)
    assert (p.pose.position.x, p.pose.position.y, p.pose.position.z) == (2.0, 5.0, 3.0)
    s = state.wait(10)
    assert s.connected and s.autopilot == "px4" and s.mode == "AUTO.LOITER"
    assert math.isclose(battery.wait(10).percentage, 0.8)
    fake.send("statustext", 6, b"Takeoff detected\t")
    assert wait_for(lambda: texts.value and texts.value.text == "Takeoff detected", 10)
    assert wait_for(lambda: fake.gcs_heartbeats >= 1, 10)  # so PX4 sends STATUSTEXT at all
    rates = wait_for(lambda: fake.commands_named(511), 10, what="SET_MESSAGE_INTERVAL")
    assert {int(m.param1) for m in rates} >= {32, 31}  # LOCAL_POSITION_NED, ATTITUDE_QUATERNION


def test_setpoints_forwarded_rotated_then_hold_then_land(rig):
    bridge, fake, user = rig
    fake.custom_mode, fake.armed, fake.landed_state = OFFBOARD, True, 2
    fake.position_ned = (1.0, 1.0, -5.0)
    wait_for(lambda: bridge.core.failsafe.mode == "OFFBOARD" and bridge.core.failsafe.airborne, 10)
    failsafe_states: list[str] = []  # State.failsafe as published, in order
    user.subscribe(registry.STATE, lambda s: failsafe_states.append(s.failsafe))
    pub = user.publisher(registry.SETPOINT_RAW_LOCAL)
    last_put = stream(pub, velocity(vx=1.0), 1.5)
    # >= 20 Hz forwarded during the last second of commanding (when the bridge sent them)
    fwd = [t for t in bridge.link.setpoints(MASK_VELOCITY) if last_put - 1.0 < t <= last_put]
    assert len(fwd) >= 10 and median_gap(fwd) <= 1.0 / 20.0, f"{len(fwd)} in the last second"
    # velocity commands expire after setpoint_timeout (0.5 s): then it holds where it is
    held = wait_for(
        lambda: [t for t in bridge.link.setpoints(MASK_POSITION) if t > last_put], 10, what="hold"
    )
    assert 0.4 < held[0] - last_put < 1.5, f"hold {held[0] - last_put:.2f} s after the last"
    wait_for(lambda: "hold" in failsafe_states, 10, what="failsafe hold published")
    wait_for(lambda: any(m.type_mask == MASK_POSITION for _, m in fake.setpoints), 10)
    last = [m for _, m in fake.setpoints if m.type_mask == MASK_VELOCITY][-1]
    assert last.coordinate_frame == 1
    assert math.isclose(last.vy, 1.0, abs_tol=1e-3) and abs(last.vx) < 1e-3  # east = forward
    m = next(m for _, m in fake.setpoints if m.type_mask == MASK_POSITION)
    assert (m.x, m.y, m.z) == (1.0, 1.0, -5.0)
    # commander lost (2 s in this config) while airborne -> NAV_LAND, requested exactly once
    # (a re-send of the same request would carry confirmation > 0)
    wait_for(lambda: fake.commands_named(21), 10, what="NAV_LAND")
    assert bridge.core.failsafe.state == "land"
    wait_for(lambda: "land" in failsafe_states, 10, what="failsafe land published")
    assert failsafe_states.index("hold") < failsafe_states.index("land")
    time.sleep(1.0)
    assert sum(m.confirmation == 0 for m in fake.commands_named(21)) == 1
    assert not fake.commands_named(176)  # never re-requested OFFBOARD


def test_bad_setpoints_and_bytes_change_nothing(rig):
    bridge, fake, user = rig
    pub = user.publisher(registry.SETPOINT_RAW_LOCAL)
    before = len(fake.setpoints)
    for bad in (velocity(vx=math.nan), velocity(vz=math.inf), velocity(vx=99.0)):
        pub.put(bad)
    user.session.put(registry.SETPOINT_RAW_LOCAL.key("drone"), b"\x00garbage")
    wait_for(lambda: bridge.core.rejected_setpoints == 3, 10)
    wait_for(lambda: sum(bridge.node.decode_errors.values()) >= 1, 10)
    time.sleep(0.3)
    assert len(fake.setpoints) == before  # not in OFFBOARD, nothing fresh: nothing sent
    with pytest.raises(ServiceError, match="altitude"):
        user.call(registry.TAKEOFF, CommandTOL.takeoff(2000.0), timeout=10)
    replies = list(user.session.get(registry.ARMING.key("drone"), payload=b"\xc1", timeout=10))
    assert len(replies) == 1 and replies[0].err is not None
    assert b"bad CommandBool request" in replies[0].err.payload.to_bytes()
    assert not fake.commands_named(400)  # nothing was sent to the autopilot


def test_params_int32_bits_and_real(rig):
    _bridge, fake, user = rig
    got = user.call(registry.PARAM_GET, ParamGet(param_id="COM_RC_IN_MODE"), timeout=10)
    assert got.success and got.value.integer == 1
    got = user.call(registry.PARAM_GET, ParamGet(param_id="COM_OF_LOSS_T"), timeout=10)
    assert got.success and math.isclose(got.value.real, 1.0)
    put = user.call(
        registry.PARAM_SET,
        ParamSet(param_id="COM_RC_IN_MODE", value=ParamValue(integer=4)),
        timeout=10,
    )
    assert put.success and put.value.integer == 4 and fake.params["COM_RC_IN_MODE"][0] == 4
    with pytest.raises(ServiceError, match="param_id"):
        user.call(registry.PARAM_GET, ParamGet(param_id="X" * 17), timeout=10)


def test_ardupilot_guided_modes_frames_takeoff_params(ardu_rig):
    """ArduCopter: GUIDED by number, no priming (before or after the ack), frame 1 (never 9),
    relative take-off altitude, mixed control emulated with vz, integer params cast (not
    bit-reinterpreted)."""
    _bridge, fake, user = ardu_rig
    state = user.latest(registry.STATE)
    assert wait_for(lambda: state.value and state.value.mode == "LOITER", 10)
    assert state.value.autopilot == "ardupilotmega"
    with pytest.raises(ServiceError, match="GUIDED"):
        user.call(registry.SET_MODE, SetMode(custom_mode="OFFBOARD"), timeout=5)
    before = len(fake.setpoints)
    assert user.call(registry.SET_MODE, SetMode(custom_mode="GUIDED"), timeout=10).mode_sent
    (mode_cmd,) = fake.commands_named(176)
    # No priming stream, before the mode change or after it (it would override a take-off).
    time.sleep(0.5)
    assert len(fake.setpoints) == before
    assert (mode_cmd.param1, mode_cmd.param2) == (1.0, 4.0)
    wait_for(lambda: state.value.mode == "GUIDED" and state.value.guided, 10)
    assert user.call(registry.ARMING, CommandBool(value=True), timeout=10).success
    assert user.call(registry.TAKEOFF, CommandTOL.takeoff(4.0), timeout=10).success
    (takeoff,) = fake.commands_named(22)
    assert takeoff.param7 == 4.0  # ArduPilot: metres above home, not AMSL
    fake.climb_to = None  # stop the scripted climb at 3 m
    fake.landed_state, fake.position_ned = 2, (0.0, 0.0, -3.0)
    pub = user.publisher(registry.SETPOINT_RAW_LOCAL)
    mixed = PositionTarget(
        coordinate_frame=FRAME_BODY_NED,
        type_mask=1987,
        velocity=Vector3(x=1.0),
        position=Point(z=4.0),
    )
    stream(pub, mixed, 0.5)
    # the mixed commands (not the holds before them or 0.5 s after them)
    moving = wait_for(
        lambda: [m for _, m in list(fake.setpoints) if m.type_mask != MASK_POSITION],
        10,
        what="the mixed setpoints",
    )
    frames = {m.coordinate_frame for _, m in fake.setpoints}
    assert frames == {1}  # never BODY_OFFSET_NED (9) nor BODY_NED (8)
    last = moving[-1]
    assert last.type_mask == MASK_VELOCITY and math.isclose(last.vz, -1.0, abs_tol=1e-3)
    assert math.isclose(last.vy, 1.0, abs_tol=1e-3)  # facing east: forward = NED y
    got = user.call(registry.PARAM_GET, ParamGet(param_id="COM_RC_IN_MODE"), timeout=10)
    assert got.success and got.value.integer == 1
