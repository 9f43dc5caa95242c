"""The simulated Tello as a process, over real UDP on loopback, flown by a minimal client of
ours: every read, the state string parsed back, a take-off, a move and an rc stick checked in
ENU against the ground truth on Zenoh, emergency, bad input and floods, a second client, the
video decoded by PyAV and by OpenCV, the ``port`` command, a clean exit. The protocol itself
(every move, turn, curve, flip and stick, and auto-landing on a configured timeout, in
simulated time) is held by tests/unit/test_sim_tello_protocol.py; the auto-land timeout set on
a running simulator, by tests/integration/test_tello_bridge_sim.py."""

from __future__ import annotations

import contextlib
import random
import re
import socket
import time

import av
import cv2
import pytest

from dronewrapper.msgs import registry
from dronewrapper_sim.tello.state_string import FIELD_ORDER, parse_state
from support import client_node, python_module, wait_for

pytestmark = pytest.mark.integration


def free_loopback_pair() -> tuple[str, str]:
    """Two loopback addresses 127.a.b.c, 127.a.b.c+1 whose Tello ports are free (the drone
    binds 8889 on the first, our client 8890 and 11111 on the second)."""
    for _ in range(50):
        a, b, c = random.randrange(100, 250), random.randrange(0, 256), random.randrange(2, 250, 2)
        drone, client = f"127.{a}.{b}.{c}", f"127.{a}.{b}.{c + 1}"
        try:
            for host, port in ((drone, 8889), (client, 8890), (client, 11111)):
                with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as probe:
                    probe.bind((host, port))
        except OSError:
            continue
        return drone, client
    raise RuntimeError("no free loopback address pair")


class TelloClient:
    """A minimal Tello SDK client: commands from an ephemeral port, state on 8890, video on
    11111 (all on ``host``)."""

    def __init__(self, drone: str, host: str, video_port: int = 11111) -> None:
        self.drone = (drone, 8889)
        self.cmd = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self.cmd.bind((host, 0))
        self.state = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self.state.bind((host, 8890))
        self.video = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self.video.bind((host, video_port))

    def send(self, text: str | bytes) -> None:
        self.cmd.sendto(text.encode() if isinstance(text, str) else text, self.drone)

    def reply(self, timeout: float = 10.0) -> str:
        self.cmd.settimeout(timeout)
        data, sender = self.cmd.recvfrom(2048)
        assert sender == self.drone  # replies come from the drone's 8889
        return data.decode()

    def ask(self, text: str, timeout: float = 20.0) -> str:
        self.send(text)
        return self.reply(timeout)

    def drain(self) -> None:
        for sock in (self.cmd, self.state, self.video):
            sock.setblocking(False)
            with contextlib.suppress(BlockingIOError):
                while True:
                    sock.recv(65535)
            sock.setblocking(True)

    def states(self, count: int, timeout: float = 10.0) -> list[tuple[float, dict]]:
        """The next ``count`` state datagrams: (arrival time, fields)."""
        self.state.setblocking(False)
        with contextlib.suppress(BlockingIOError):
            while True:
                self.state.recv(4096)  # older ones
        self.state.setblocking(True)
        self.state.settimeout(timeout)
        out = []
        for _ in range(count):
            data, sender = self.state.recvfrom(4096)
            assert sender[0] == self.drone[0]
            text = data.decode("ascii")
            assert text.endswith(";\r\n")
            out.append((time.monotonic(), parse_state(text)))
        return out

    def video_bytes(self, seconds: float) -> bytes:
        self.video.settimeout(5.0)
        chunks = []
        end = time.monotonic() + seconds
        while time.monotonic() < end:
            data = self.video.recv(65535)
            assert len(data) <= 1460
            chunks.append(data)
        return b"".join(chunks)

    def close(self) -> None:
        for sock in (self.cmd, self.state, self.video):
            sock.close()


def decode_pyav(stream: bytes) -> list:
    decoder = av.CodecContext.create("h264", "r")
    frames = []
    for packet in decoder.parse(stream):
        with contextlib.suppress(av.error.InvalidDataError):  # the stream joined mid-GOP
            frames += decoder.decode(packet)
    return frames


def wait_answering(client: TelloClient, proc) -> None:
    """Wait until the simulated Tello (``proc``, alive throughout) answers ``command`` ok."""

    def up() -> bool:
        assert proc.alive(), proc.output()
        client.send("command")
        try:
            return client.reply(timeout=0.5) == "ok"
        except TimeoutError:
            return False

    wait_for(up, 30, interval=0.1, what="the simulated Tello answering 'command'")


@pytest.fixture
def tello(spawn, router, tmp_path):
    """A simulated Tello on a free loopback address with a Zenoh router; our client."""
    drone, host = free_loopback_pair()
    proc = spawn(
        python_module(
            "dronewrapper_sim", "--aircraft", "tello", "--address", drone,
            "--connect", router, "--namespace", "tello", "--scenario", "beacon_static",
        ),
        "tello",
    )  # fmt: skip
    client = TelloClient(drone, host)
    wait_answering(client, proc)
    yield client, proc, router
    client.close()


def test_tello_over_udp(tello, tmp_path):
    client, proc, router = tello
    with client_node(router, namespace="tello") as node:
        truth = node.latest(registry.SIM_GROUND_TRUTH)
        truth.wait(15)

        def pose():
            return truth.wait(5).pose

        # reads
        reads = {
            "battery?": r"100",
            "speed?": r"100\.0",
            "time?": r"0s",
            "height?": r"0dm",
            "temp?": r"\d+~\d+C",
            "attitude?": r"pitch:-?\d+;roll:-?\d+;yaw:-?\d+;",
            "baro?": r"-?\d+\.\d+",
            "tof?": r"\d+mm",
            "acceleration?": r"agx:-?[\d.]+;agy:-?[\d.]+;agz:-?[\d.]+;",
            "wifi?": r"\d+",
            "sdk?": r"20",
            "sn?": r"\w+",
        }
        client.drain()
        for command, pattern in reads.items():
            assert re.fullmatch(pattern, client.ask(command)), command

        # the state string: 10 Hz, the real field order, parsed back
        states = client.states(11)
        period = (states[-1][0] - states[0][0]) / 10
        assert 0.05 < period < 0.3  # 10 Hz (bounds for a loaded machine)
        assert tuple(states[-1][1]) == FIELD_ORDER
        assert states[-1][1]["bat"] == 100 and states[-1][1]["h"] == 0

        # bad input: answered, never crashes, changes nothing
        assert client.ask("forward 50") == "error Motor stop"
        assert client.ask(b"\xff\xfe takeoff") == "error"
        assert client.ask("takeoff please") == "error"
        assert client.ask("jump") == "unknown command: jump"
        for i in range(500):  # a flood
            client.send(bytes([i % 256]) * 30)
        time.sleep(0.5)
        client.drain()
        assert client.ask("battery?") == "100"
        assert pose().position.z == pytest.approx(0.0, abs=0.01)

        # take-off and a move, answered when finished
        started = time.monotonic()
        assert client.ask("takeoff") == "ok"
        assert time.monotonic() - started > 1.5
        assert 0.8 <= pose().position.z <= 1.2
        p0 = pose().position
        assert client.ask("forward 50") == "ok"  # heading east in beacon_static: +x
        p1 = pose().position
        assert (p1.x - p0.x, p1.y - p0.y) == pytest.approx((0.5, 0.0), abs=0.1)
        # rc: b forward, no reply; ENU from ground truth (the other sticks, moves, turns, the
        # curve and the flip: tests/unit/test_sim_tello_protocol.py, in simulated time)
        a = pose()
        t0 = truth.wait(5).header.stamp
        client.send("rc 0 80 0 0")  # forward = east
        time.sleep(1.5)
        b = truth.wait(5)
        dt = b.header.stamp - t0
        client.send("rc 0 0 0 0")
        vx, vy = (b.pose.position.x - a.position.x) / dt, (b.pose.position.y - a.position.y) / dt
        assert vx > 0.3 and abs(vy) < 0.2
        with pytest.raises(TimeoutError):
            client.reply(timeout=0.5)  # rc is never answered
        time.sleep(0.5)

        # a second client is obeyed, and answered itself
        _, other_host = free_loopback_pair()
        other = TelloClient(client.drone[0], other_host)
        try:
            z0 = pose().position.z
            assert other.ask("down 20") == "ok"
            assert pose().position.z - z0 == pytest.approx(-0.2, abs=0.08)
        finally:
            other.close()

        # video: after streamon, H.264 that PyAV and OpenCV decode; the port command moves it
        assert client.ask("streamon") == "ok"
        stream = client.video_bytes(2.0)
        frames = decode_pyav(stream)
        assert len(frames) >= 15
        assert (frames[-1].width, frames[-1].height) == (960, 720)
        assert frames[-1].to_ndarray(format="bgr24").std() > 5  # a rendered scene
        path = tmp_path / "tello.h264"
        path.write_bytes(stream)
        capture = cv2.VideoCapture(str(path))
        ok, image = capture.read()
        capture.release()
        assert ok and image.shape == (720, 960, 3)
        other = TelloClient(client.drone[0], other_host, video_port=11200)
        try:
            assert client.ask("port 8890 11200") == "ok"  # the video moves to 11200
            assert other.ask("command") == "ok"  # and state and video to the last 'command'
            other.video.settimeout(5.0)
            assert len(other.video.recv(65535)) > 0
            assert other.states(1)[0][1]["bat"] > 0
        finally:
            other.close()
        assert client.ask("command") == "ok"
        assert client.ask("port 8890 11111") == "ok"
        assert client.ask("streamoff") == "ok"

        # emergency: motors off at once, it falls
        assert client.ask("emergency") == "ok"
        wait_for(lambda: pose().position.z < 0.01, 5, what="the fall")
        assert client.ask("forward 50") == "error Motor stop"
        assert client.states(1)[0][1]["h"] == 0
    assert proc.stop() == 0
    assert "Traceback" not in proc.output()
