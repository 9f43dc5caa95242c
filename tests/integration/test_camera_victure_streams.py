"""The camera_victure process on real network streams that stop and come back.

A local HTTP MJPEG server (multipart/x-mixed-replace, with garbage frames mixed in) and an
RTP/UDP H.264 stream (MPEG-TS over RTP, encoded with PyAV) are served by the test, stopped and
restarted; the service reconnects with backoff and says so in its CameraStatus. Each served
frame is the test pattern carrying a counter (10000 + n after the restart), so the test knows
which run of the server a received frame came from. Also: a URL nobody serves, and a missing
device (exit 2).
"""

from __future__ import annotations

import socket
import threading
import time
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer

import cv2
import pytest

from dronewrapper.images import image_to_bgr
from dronewrapper.msgs import registry
from dronewrapper_camera_victure.pattern import read_counter, render_pattern
from support import client_node, free_port, python_module, wait_for

pytestmark = pytest.mark.integration

WIDTH, HEIGHT = 320, 240
RESTART_BASE = 10_000
GARBAGE_EVERY = 15  # every 15th served MJPEG part is not a JPEG


class MjpegServer:
    """An HTTP MJPEG camera on 127.0.0.1:``port`` at about 30 fps, until :meth:`stop`."""

    def __init__(self, port: int, first: int) -> None:
        self.stopping = threading.Event()
        self.served = 0
        outer = self

        class Handler(BaseHTTPRequestHandler):
            def do_GET(self) -> None:
                self.send_response(200)
                self.send_header("Content-Type", "multipart/x-mixed-replace; boundary=frame")
                self.end_headers()
                n = first
                try:
                    while not outer.stopping.is_set():
                        frame = render_pattern(WIDTH, HEIGHT, n, time.time())
                        data = cv2.imencode(".jpg", frame)[1].tobytes()
                        if n % GARBAGE_EVERY == GARBAGE_EVERY - 1:
                            data = b"not a jpeg " * 40
                        head = f"--frame\r\nContent-Type: image/jpeg\r\nContent-Length: {len(data)}"
                        self.wfile.write(head.encode() + b"\r\n\r\n" + data + b"\r\n")
                        outer.served += 1
                        n += 1
                        outer.stopping.wait(1 / 30)
                except (BrokenPipeError, ConnectionResetError):
                    pass

            def log_message(self, *args) -> None:
                pass

        self.server = ThreadingHTTPServer(("127.0.0.1", port), Handler)
        self.server.daemon_threads = True
        self.thread = threading.Thread(target=self.server.serve_forever, daemon=True)
        self.thread.start()

    def stop(self) -> None:
        self.stopping.set()
        self.server.shutdown()
        self.server.server_close()
        self.thread.join(5)


class RtpH264Sender:
    """H.264 in MPEG-TS over RTP to 127.0.0.1:``port``, encoded with PyAV, until :meth:`stop`."""

    def __init__(self, port: int, first: int) -> None:
        self.stopping = threading.Event()
        self.sent = 0
        self.port, self.first = port, first
        self.thread = threading.Thread(target=self._run, daemon=True)
        self.thread.start()

    def _run(self) -> None:
        import av

        out = av.open(f"rtp://127.0.0.1:{self.port}", "w", format="rtp_mpegts")
        try:
            stream = out.add_stream("libx264", rate=30)
            stream.width, stream.height, stream.pix_fmt = WIDTH, HEIGHT, "yuv420p"
            stream.options = {"tune": "zerolatency", "preset": "ultrafast", "g": "10"}
            n = self.first
            while not self.stopping.is_set():
                frame = render_pattern(WIDTH, HEIGHT, n, time.time())
                for packet in stream.encode(av.VideoFrame.from_ndarray(frame, format="bgr24")):
                    out.mux(packet)
                self.sent += 1
                n += 1
                self.stopping.wait(1 / 30)
        finally:
            out.close()

    def stop(self) -> None:
        self.stopping.set()
        self.thread.join(5)


def _camera(spawn, router: str, source: str, *extra: str):
    sets = [
        f"source={source}",
        "open_timeout=2",
        "read_timeout=1",
        "retry_initial=0.2",
        "retry_max=1",
        "status_period=0.25",
        *extra,
    ]
    argv = ["--connect", router, *[a for s in sets for a in ("--set", s)]]
    return spawn(python_module("dronewrapper_camera_victure", *argv), "camera_victure")


class Watcher:
    """The test's view: received frames' counters and the newest CameraStatus."""

    def __init__(self, router: str) -> None:
        self.node = client_node(router, name="watcher")
        self.counters: list[int] = []
        self.node.subscribe(registry.IMAGE_RAW, self._frame, camera="cam_frontal")
        self.status = self.node.latest(registry.CAMERA_STATUS, camera="cam_frontal")

    def _frame(self, msg) -> None:
        self.counters.append(read_counter(image_to_bgr(msg)))

    def wait_status(self, predicate, timeout: float, what: str, proc):
        def check():
            assert proc.alive(), proc.output()
            return self.status.value is not None and predicate(self.status.value)

        wait_for(check, timeout, what=what)
        return self.status.value

    def close(self) -> None:
        self.node.close()


def _stop_and_restart(proc, watch: Watcher, start, stop_source, *, lost_within: float) -> None:
    """Frames flow from the first run, stop when it stops, and flow again from the second."""
    first = start(0)
    try:
        wait_for(lambda: len(watch.counters) >= 10, 20, what="frames from the first run")
    finally:
        stop_source(first)
    watch.wait_status(lambda s: s.state == "reconnecting", lost_within, "the loss noticed", proc)
    second = start(RESTART_BASE)
    try:
        status = watch.wait_status(
            lambda s: s.reconnects >= 1 and s.state == "streaming", 20, "a reconnection", proc
        )
        wait_for(
            lambda: sum(c >= RESTART_BASE for c in watch.counters) >= 10,
            10,
            what="frames from the second run",
        )
    finally:
        stop_source(second)
    assert status.open_failures >= 1 or status.reconnects >= 1
    before = [c for c in watch.counters if c < RESTART_BASE]
    after = [c for c in watch.counters if c >= RESTART_BASE]
    assert before == sorted(before) and after == sorted(after)  # never older after newer
    assert watch.counters.index(after[0]) == len(before)  # and nothing old after the restart


def test_http_mjpeg_stream_stopped_and_restarted(router, spawn):
    port = free_port()
    url = f"http://127.0.0.1:{port}/stream.mjpg"
    watch = Watcher(router)
    try:
        proc = _camera(spawn, router, url)
        _stop_and_restart(
            proc,
            watch,
            lambda first: MjpegServer(port, first),
            MjpegServer.stop,
            lost_within=5,
        )
        status = watch.status.value
        assert status.corrupt_frames >= 1  # the garbage parts, counted and survived
        assert "lost" in status.last_error or "cannot open" in status.last_error
        assert proc.stop() == 0
    finally:
        watch.close()
    assert "open again" in proc.output()


def test_rtp_h264_stream_stopped_and_restarted(router, spawn):
    port = free_port(socket.SOCK_DGRAM)
    watch = Watcher(router)
    try:
        proc = _camera(spawn, router, f"rtp://127.0.0.1:{port}")
        _stop_and_restart(
            proc,
            watch,
            lambda first: RtpH264Sender(port, first),
            RtpH264Sender.stop,
            lost_within=8,
        )
        assert proc.stop() == 0
    finally:
        watch.close()


def test_a_url_nobody_serves_is_retried_not_fatal(router, spawn):
    watch = Watcher(router)
    try:
        proc = _camera(spawn, router, f"http://127.0.0.1:{free_port()}/nothing.mjpg")
        status = watch.wait_status(lambda s: s.open_failures >= 3, 20, "retries", proc)
        assert status.state == "connecting" and status.frames_published == 0
        assert "cannot open stream" in status.last_error
        assert proc.stop() == 0
    finally:
        watch.close()


def test_help_and_list(spawn):
    helped = spawn(python_module("dronewrapper_camera_victure", "--help"), "help")
    listed = spawn(python_module("dronewrapper_camera_victure", "--list"), "list")
    assert helped.proc.wait(30) == 0 and "--list" in helped.output()
    assert "--connect" in helped.output() and "--config" in helped.output()
    code = listed.proc.wait(30)
    if code == 1:  # a CI machine has no camera, and says so
        assert "no V4L2 devices" in listed.output()
    else:  # a machine with one lists it
        assert code == 0 and "/dev/video" in listed.output()


def test_stops_promptly_while_a_stream_hangs_opening(router, spawn):
    """A server that accepts and never answers: OpenCV blocks opening it (up to
    open_timeout, 60 s here); SIGINT still stops the service at once, exit 0."""
    server = socket.socket()
    server.bind(("127.0.0.1", 0))
    server.listen()
    held: list[socket.socket] = []
    accepting = threading.Thread(target=lambda: held.append(server.accept()[0]), daemon=True)
    accepting.start()
    port = server.getsockname()[1]
    try:
        proc = spawn(
            python_module(
                "dronewrapper_camera_victure", "--connect", router,
                "--set", f"source=http://127.0.0.1:{port}/hang.mjpg", "--set", "open_timeout=60",
            ),
            "camera_victure",
        )  # fmt: skip
        wait_for(lambda: held, 20, what="the service connecting")
        started = time.monotonic()
        assert proc.stop(timeout=15) == 0, proc.output()
        assert time.monotonic() - started < 10  # not the 60 s open timeout
    finally:
        for conn in held:
            conn.close()
        server.close()


def test_a_missing_device_exits_2_naming_it(router, spawn):
    proc = spawn(
        python_module("dronewrapper_camera_victure", "--connect", router, "--set", "source=7"),
        "camera_victure",
    )
    proc.proc.wait(30)
    assert proc.proc.returncode == 2
    assert "no camera device /dev/video7" in proc.output()


def test_webcam_follow_color_graph_dry_run(spawn):
    """The desk graph with the test pattern as the 'webcam': its red bar is followed, the
    controller's commands show up in its status, and no aircraft is needed."""
    from support import free_endpoint

    endpoint = free_endpoint()
    proc = spawn(
        python_module(
            "dronewrapper", "up", "compose/webcam_follow_color.yaml", "--router", endpoint,
            "--var", "camera=pattern", "--var", "fps=15", "--var", "debug_image=false",
        ),
        "up",
    )  # fmt: skip
    node = client_node(endpoint, name="watcher")
    try:
        status = node.latest(registry.CONTROLLER_STATUS)

        def tracking():
            assert proc.alive(), proc.output()
            s = status.value
            return s is not None and s.state == "tracking" and s.target_visible and s.cmd_yaw_rate

        wait_for(tracking, 45, what="the dry-run controller tracking the red bar")
        assert status.value.mode == "follow_color" and status.value.source_stamp > 1e9
    finally:
        node.close()
    assert proc.stop(30) == 0
    assert "dry run" in proc.output()
