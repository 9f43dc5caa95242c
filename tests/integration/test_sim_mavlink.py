"""The simulator process as a MAVLink client sees it: real UDP on free loopback ports, real
MAVLink 2 bytes (pymavlink), the offboard-loss failsafe, the parameter protocol, message
intervals, bad input and a clean exit. The full PX4 offboard sequence (modes, arming, body and
local velocities, yaw rate, position, landing) is held in simulated time by
tests/service/test_sim_offboard_virtual.py.

Size: one MAVLink client rig (its timed receive log and waits) shared by every test of the file.
"""

from __future__ import annotations

import itertools
import math
import socket
import threading
import time

import pytest
from mavlink_log import MessageLog
from mavlink_setpoints import FRAME_BODY_NED, setpoint, velocity_target
from pymavlink.dialects.v20 import common as mavlink

from dronewrapper.msgs.mavros import MASK_VELOCITY
from dronewrapper_sim.px4 import params
from dronewrapper_sim.px4.modes import Mode
from support import python_module, start_daemons, stop_daemons, wait_for

pytestmark = pytest.mark.integration


class MavClient(MessageLog):
    """A MAVLink endpoint on a free UDP port (like a bridge's ``udpin``), with a background
    reader that keeps every message and a setpoint streamer that can be started and stopped."""

    def __init__(self, mav_type: int, sysid: int = 245) -> None:
        super().__init__()
        self.sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self.sock.bind(("127.0.0.1", 0))
        self.sock.settimeout(0.1)
        self.port = self.sock.getsockname()[1]
        self.mav_type = mav_type
        self.out = mavlink.MAVLink(None, srcSystem=sysid, srcComponent=191)
        self.parser = mavlink.MAVLink(None)
        self.parser.robust_parsing = True
        self.peer: tuple[str, int] | None = None
        self._send_lock = threading.Lock()
        self._stream_lock = threading.Lock()
        self._stop = threading.Event()
        self.setpoint: object | None = None
        self.setpoint_period = 0.05
        self.last_setpoint_sent = 0.0
        self.heartbeats_sent = 0
        self._threads = start_daemons(self._read, self._stream)

    def _read(self) -> None:
        last_hb = 0.0
        while not self._stop.is_set():
            if self.peer and time.monotonic() - last_hb > 0.5:
                last_hb = time.monotonic()
                self.send(mavlink.MAVLink_heartbeat_message(self.mav_type, 8, 0, 0, 4, 3))
                self.heartbeats_sent += 1
            try:
                data, addr = self.sock.recvfrom(65535)
            except (TimeoutError, OSError):
                continue
            self.peer = addr
            now = time.monotonic()
            for msg in self.parser.parse_buffer(data) or []:
                with self.lock:
                    self.log.append((now, msg))

    def _stream(self) -> None:
        while not self._stop.wait(self.setpoint_period):
            with self._stream_lock:
                sp = self.setpoint
                if sp is not None and self.peer:
                    self.send(sp)
                    self.last_setpoint_sent = time.monotonic()

    def stop_stream(self, last=None) -> float:
        """Stop the setpoint stream (no streamed setpoint is sent after this returns), then
        send ``last`` (if given) as the very last setpoint; returns when that was sent."""
        with self._stream_lock:
            self.setpoint = None
            if last is not None:
                self.send(last)
                self.last_setpoint_sent = time.monotonic()
            return self.last_setpoint_sent

    def send(self, msg) -> None:
        assert self.peer, "no datagram from the vehicle yet"
        with self._send_lock:
            buf = msg.pack(self.out)
            self.out.seq = (self.out.seq + 1) % 256
            self.sock.sendto(buf, self.peer)

    def send_raw(self, data: bytes) -> None:
        self.sock.sendto(data, self.peer)

    def close(self) -> None:
        stop_daemons(self._stop, self._threads)
        self.sock.close()

    # ---- reading: MessageLog ----

    def wait_until(self, found, timeout: float, what: str):
        return wait_for(found, timeout, what=what)

    # ---- commands ----

    def command(
        self, command: int, *p: float, target: int = 1, timeout: float = 10.0, expect: int = 1
    ) -> list:
        """COMMAND_LONG; returns every ACK for it: waits for ``expect`` of them, then 0.3 s
        more for any surplus one."""
        t0 = time.monotonic()
        p7 = [*p, *[0.0] * (7 - len(p))]
        self.send(mavlink.MAVLink_command_long_message(target, 1, command, 0, *p7))

        def replies() -> list:
            return [m for m in self.since(t0, "COMMAND_ACK") if m.command == command]

        wait_for(lambda: len(replies()) >= expect, timeout, what=f"{expect} ACK(s) of {command}")
        time.sleep(0.3)
        return replies()

    def set_mode(self, mode: Mode) -> list:
        return self.command(176, 1, mode.main, mode.sub, expect=2)  # PX4 acks a mode twice

    def sync(self, timeout: float = 10.0) -> None:
        """A barrier: the vehicle handles a link's datagrams in order and answers a parameter
        read at once, so when this read is answered every datagram sent before it was handled
        (and its immediate replies, like COMMAND_ACK, were received)."""
        t0 = time.monotonic()
        self.send(mavlink.MAVLink_param_request_read_message(1, 1, b"COM_OF_LOSS_T", -1))
        self.wait_msg("PARAM_VALUE", lambda m: m.param_id == "COM_OF_LOSS_T", timeout, t0)

    def sync_heartbeat(self, timeout: float = 10.0) -> None:
        """Return once the vehicle has handled one of this client's heartbeats (a GCS peer
        gets STATUSTEXT only after that)."""
        wait_for(lambda: self.heartbeats_sent > 0, timeout, what="our first heartbeat sent")
        self.sync(timeout)

    def mode(self) -> Mode | None:
        hb = self.latest("HEARTBEAT")
        return None if hb is None else Mode(divmod_mode(hb.custom_mode))

    def armed(self) -> bool:
        hb = self.latest("HEARTBEAT")
        return bool(hb and hb.base_mode & 128)

    def wait_heartbeat(self, pred, timeout: float, t0: float | None = None):
        t0 = time.monotonic() if t0 is None else t0
        return self.wait_msg("HEARTBEAT", pred, timeout, t0)

    def stream(self, vx=0.0, vy=0.0, vz=0.0, yaw_rate=0.0, frame=FRAME_BODY_NED, **pos) -> None:
        self.setpoint = setpoint(vx, vy, vz, yaw_rate, frame, **pos)


def divmod_mode(custom_mode: int) -> tuple[int, int]:
    main, sub = (custom_mode >> 16) & 0xFF, (custom_mode >> 24) & 0xFF
    return (main, sub if main == 4 else 0)


@pytest.fixture
def clients():
    made: list[MavClient] = []

    def make(mav_type: int) -> MavClient:
        client = MavClient(mav_type)
        made.append(client)
        return client

    yield make
    for client in made:
        client.close()


def start_sim(spawn, router, onboard: MavClient, gcs: MavClient | None = None, *extra: str):
    gcs_spec = f"{gcs.port}:0" if gcs else "off"
    argv = python_module(
        "dronewrapper_sim", "--scenario", "empty", "--no-cameras", "--connect", router,
        "--udp-onboard", f"{onboard.port}:0", "--udp-gcs", gcs_spec, *extra,
    )  # fmt: skip
    proc = spawn(argv, "sim")
    wait_for(lambda: onboard.latest("HEARTBEAT"), 30, what="first HEARTBEAT from the sim")
    if gcs:
        wait_for(lambda: gcs.latest("HEARTBEAT"), 10, what="HEARTBEAT on the GCS link")
    return proc


def acks(replies: list) -> list[int]:
    return [m.result for m in replies]


def boot_s(msg) -> float:
    """The vehicle's simulated time (s since boot) stamped on ``msg``."""
    return msg.time_boot_ms / 1000.0


def test_offboard_loss_failsafe_and_unlatched_return(spawn, router, clients):
    onboard = clients(mavlink.MAV_TYPE_ONBOARD_CONTROLLER)
    gcs = clients(mavlink.MAV_TYPE_GCS)
    start_sim(spawn, router, onboard, gcs)
    hb = onboard.latest("HEARTBEAT")  # the process's links send as system 1, component 1
    assert (hb.type, hb.autopilot, hb.base_mode) == (2, 12, 29)
    assert hb.get_srcSystem() == 1 and hb.get_srcComponent() == 1
    gcs.sync_heartbeat()  # the sim knows the GCS now: it gets STATUSTEXT
    t_stream = time.monotonic()
    onboard.stream(vz=-1.5)
    wait_for(lambda: onboard.last_setpoint_sent > t_stream, 10, what="the setpoint stream")
    time.sleep(1.2)
    assert acks(onboard.set_mode(Mode.OFFBOARD)) == [mavlink.MAV_RESULT_ACCEPTED] * 2
    assert acks(onboard.command(mavlink.MAV_CMD_COMPONENT_ARM_DISARM, 1)) == [
        mavlink.MAV_RESULT_ACCEPTED
    ]
    wait_for(lambda: onboard.latest("LOCAL_POSITION_NED").z < -2.5, 20, what="climb")
    onboard.stream()
    time.sleep(0.5)

    # stop the stream with a last setpoint that differs (a slow yaw rate), so the simulated
    # time it took effect shows in POSITION_TARGET_LOCAL_NED (50 Hz on the GCS link)
    marker = 0.02  # rad/s
    last = onboard.stop_stream(velocity_target(yaw_rate=marker))
    text = gcs.wait_msg("STATUSTEXT", lambda m: "Failsafe activated" in m.text, 10, last)
    gcs_log = gcs.timed(last)
    at = next(i for i, (_, m) in enumerate(gcs_log) if m is text)
    t_text = gcs_log[at][0]
    taken = next(
        m
        for _, m in gcs_log[:at]
        if m.get_type() == "POSITION_TARGET_LOCAL_NED" and abs(m.yaw_rate - marker) < 1e-4
    )
    stamped = wait_for(
        lambda: next((m for _, m in gcs.timed(t_text)[1:] if hasattr(m, "time_boot_ms")), None),
        5,
        what="telemetry after the failsafe text",
    )
    # COM_OF_LOSS_T = 1 s of simulated time (PX4: 1.04-1.12 s); the margins are the report
    # periods and the simulator's bounded catch-up after a stall (at most 0.2 s)
    lost_after = boot_s(stamped) - boot_s(taken)
    print(f"failsafe {lost_after:.3f} s (simulated), {t_text - last:.3f} s (wall) after the last")
    assert 0.8 < lost_after < 1.35, f"failsafe {lost_after:.3f} s after the last setpoint"
    assert t_text - last > 0.6  # and not before that in real time either
    rtl = onboard.wait_heartbeat(lambda m: divmod_mode(m.custom_mode) == Mode.RTL.value, 6, last)
    assert rtl.system_status == mavlink.MAV_STATE_CRITICAL

    # resume: back in OFFBOARD with no mode command (not latched)
    t_resume = time.monotonic()
    onboard.stream()
    back = onboard.wait_heartbeat(
        lambda m: divmod_mode(m.custom_mode) == Mode.OFFBOARD.value, 6, t_resume
    )
    assert back.base_mode & 128
    assert not [m for m in onboard.since(t_resume, "COMMAND_ACK")]


def median_interval_ms(client: MavClient, kind: str, count: int = 40) -> float:
    """The median interval (ms of simulated time, from time_boot_ms) between the next
    ``count`` ``kind`` messages: the stream's period as the vehicle schedules it, whatever the
    delays between the vehicle and this test."""
    t0 = time.monotonic()
    wait_for(lambda: len(client.since(t0, kind)) >= count, 15, what=f"{count} {kind}")
    stamps = [m.time_boot_ms for m in client.since(t0, kind)]
    gaps = sorted(b - a for a, b in itertools.pairwise(stamps))
    return gaps[len(gaps) // 2]


def test_params_intervals_and_bad_input(spawn, router, clients):
    onboard = clients(mavlink.MAV_TYPE_GCS)  # a GCS-type peer: it gets STATUSTEXT
    proc = start_sim(spawn, router, onboard)
    onboard.sync_heartbeat()

    # parameters: read by name and index, int32 bits, set with echo, list
    t0 = time.monotonic()
    onboard.send(mavlink.MAVLink_param_request_read_message(1, 1, b"COM_OF_LOSS_T", -1))
    value = onboard.wait_msg("PARAM_VALUE", lambda m: m.param_id == "COM_OF_LOSS_T", 10, t0)
    assert value.param_value == 1.0 and value.param_type == mavlink.MAV_PARAM_TYPE_REAL32
    onboard.send(mavlink.MAVLink_param_request_read_message(1, 1, b"COM_RC_IN_MODE", -1))
    raw = onboard.wait_msg("PARAM_VALUE", lambda m: m.param_id == "COM_RC_IN_MODE", 10, t0)
    assert raw.param_type == mavlink.MAV_PARAM_TYPE_INT32
    assert params.float_bits_to_int32(raw.param_value) == 1 and raw.param_value != 1.0
    bits = params.int32_to_float_bits(1)
    onboard.send(mavlink.MAVLink_param_set_message(1, 1, b"NAV_RCL_ACT", bits, 6))
    echo = onboard.wait_msg("PARAM_VALUE", lambda m: m.param_id == "NAV_RCL_ACT", 10, t0)
    assert params.float_bits_to_int32(echo.param_value) == 1
    t_list = time.monotonic()
    onboard.send(mavlink.MAVLink_param_request_list_message(1, 1))
    wait_for(
        lambda: len({m.param_id for m in onboard.since(t_list, "PARAM_VALUE")}) == raw.param_count,
        15,
        what="the whole parameter list",
    )

    # SET_MESSAGE_INTERVAL: LOCAL_POSITION_NED 30 -> 50 Hz; refused for HEARTBEAT. Periods in
    # simulated time, in whole 4 ms physics steps: 30 Hz = 32/36 ms, 50 Hz = 20 ms (a starved
    # simulator that steps in bursts moves them by a step or two, never from one to the other)
    assert 28 <= median_interval_ms(onboard, "LOCAL_POSITION_NED") <= 44
    lpn_id = mavlink.MAVLINK_MSG_ID_LOCAL_POSITION_NED
    assert acks(onboard.command(mavlink.MAV_CMD_SET_MESSAGE_INTERVAL, lpn_id, 20_000)) == [
        mavlink.MAV_RESULT_ACCEPTED
    ]
    assert 16 <= median_interval_ms(onboard, "LOCAL_POSITION_NED") <= 26
    assert acks(onboard.command(mavlink.MAV_CMD_SET_MESSAGE_INTERVAL, 0, 100_000)) == [
        mavlink.MAV_RESULT_FAILED
    ]
    t = time.monotonic()
    onboard.command(mavlink.MAV_CMD_GET_MESSAGE_INTERVAL, lpn_id)
    assert onboard.wait_msg("MESSAGE_INTERVAL", timeout=10, t0=t).interval_us == 20_000

    # bad MAVLink: unknown command, wrong target, frame 9, NaN fields, garbage bytes
    assert acks(onboard.command(4242)) == [mavlink.MAV_RESULT_UNSUPPORTED]
    t = time.monotonic()
    onboard.send(
        mavlink.MAVLink_command_long_message(
            9, 1, mavlink.MAV_CMD_COMPONENT_ARM_DISARM, 0, 1, 0, 0, 0, 0, 0, 0
        )
    )
    onboard.sync()  # handled (and any ACK for it received) before the read is answered
    assert onboard.since(t, "COMMAND_ACK") == []
    assert not onboard.armed()
    t = time.monotonic()
    onboard.send(
        mavlink.MAVLink_set_position_target_local_ned_message(
            0,
            1,
            1,
            mavlink.MAV_FRAME_BODY_OFFSET_NED,
            MASK_VELOCITY,
            0,
            0,
            0,
            1,
            0,
            0,
            0,
            0,
            0,
            0,
            0,
        )
    )
    onboard.wait_msg("STATUSTEXT", lambda m: "coordinate frame 9" in m.text, 10, t)
    nan = math.nan
    for _ in range(5):
        onboard.send(
            mavlink.MAVLink_set_position_target_local_ned_message(
                0, 1, 1, 1, 0, nan, nan, nan, nan, nan, nan, nan, nan, nan, nan, nan
            )
        )
    onboard.send_raw(b"\xfd\x09garbage that is not MAVLink" * 3)
    onboard.send_raw(b"")
    t = time.monotonic()
    onboard.send(mavlink.MAVLink_param_request_read_message(1, 1, b"MIS_TAKEOFF_ALT", -1))
    alive = onboard.wait_msg("PARAM_VALUE", lambda m: m.param_id == "MIS_TAKEOFF_ALT", 10, t)
    assert alive.param_value == 2.5
    assert proc.alive()
    t = time.monotonic()
    lpn = onboard.wait_msg("LOCAL_POSITION_NED", timeout=10, t0=t)  # still streaming
    assert all(math.isfinite(v) for v in (lpn.x, lpn.y, lpn.z))
    assert proc.stop() == 0
