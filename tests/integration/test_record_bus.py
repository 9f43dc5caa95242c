"""Record, replay and view on a real loopback router: ``dronewrapper record|replay|foxglove``.

A simulated aircraft and its bridge are recorded and the file is read back with the ``mcap``
reader; a recorder killed with SIGKILL leaves a file that opens; a recording replayed into the
perception process gives back the detections of the live flight; the Foxglove server answers a
real WebSocket client with the advertised channels.
"""

from __future__ import annotations

import asyncio
import itertools
import json
import signal
import struct
import sys
import time
from pathlib import Path

import numpy as np
import pytest
import websockets
from mcap.reader import make_reader

from dronewrapper.msgs import Header, Point, Pose, PoseStamped, registry
from dronewrapper.record.reader import read_bus, summarize
from support import REPO, client_node, free_port, python_module, wait_for

pytestmark = pytest.mark.integration

HOLDOUT = REPO / "tests" / "replay" / "data" / "holdout_teleop.mcap"


def _dronewrapper(*args: str) -> list[str]:
    return [sys.executable, "-m", "dronewrapper", *args]


def _wait_exit(proc, timeout: float) -> int:
    try:
        return proc.proc.wait(timeout)
    except Exception as exc:
        raise AssertionError(
            f"{proc.argv} still running after {timeout} s:\n{proc.output()}"
        ) from exc


def test_record_a_simulated_aircraft_and_read_it_back(router, spawn, tmp_path):
    port = free_port()
    spawn(
        python_module(
            "dronewrapper_sim", "--scenario", "beacon_static", "--connect", router,
            "--udp-onboard", f"{port}:0", "--udp-gcs", "off",
            "--width", "160", "--height", "120", "--camera-rate", "10",
        ),
        "sim",
    )  # fmt: skip
    spawn(
        python_module(
            "dronewrapper_bridge_mavlink", "--connect", router,
            "--set", f"connection=udpin:127.0.0.1:{port}",
        ),
        "bridge",
    )  # fmt: skip
    with client_node(router) as node:
        pose = node.latest(registry.LOCAL_POSE)
        frames = node.latest(registry.IMAGE_RAW, camera="cam_frontal")
        wait_for(lambda: pose.count > 3 and frames.count > 1, 60, what="sim and bridge running")
    out = tmp_path / "flight.mcap"
    rec = spawn(
        _dronewrapper(
            "record", "drone/**", "sim/**", "-o", str(out), "--connect", router,
            "--duration", "3", "--compressed-images",
        ),
        "record",
    )  # fmt: skip
    assert _wait_exit(rec, 60) == 0, rec.output()
    assert "recorded" in rec.output()

    with out.open("rb") as f:
        reader = make_reader(f)
        summary = reader.get_summary()
        assert summary is not None and summary.chunk_indexes  # complete, chunked
        schemas = {sid: s for sid, s in summary.schemas.items()}
        channels = {c.topic: c for c in summary.channels.values()}
        counts = summary.statistics.channel_message_counts

        def schema_of(topic: str) -> str:
            return schemas[channels[topic].schema_id].name

        assert schema_of("/drone/cam_frontal/image_raw") == "foxglove.CompressedImage"
        assert schema_of("/drone/mavros/local_position/pose") == "dronewrapper/v1/PoseStamped"
        assert schema_of("/tf") == "foxglove.FrameTransform"
        assert schema_of("/drone/mavros/global_position/global/fix") == "foxglove.LocationFix"
        assert channels["drone/mavros/state"].message_encoding == "msgpack"
        # 3 s of a 10 Hz camera and >= 30 Hz telemetry, with margins for a loaded machine
        assert counts[channels["/drone/cam_frontal/image_raw"].id] >= 10
        assert counts[channels["drone/mavros/local_position/pose"].id] >= 30
        assert counts[channels["drone/sim/ground_truth"].id] >= 30
        # each frame once: the camera's own JPEG stream is left out once its raw frames arrive
        own_jpeg = channels.get("/drone/cam_frontal/image_raw/compressed")
        duplicates = counts[own_jpeg.id] if own_jpeg is not None else 0
        assert duplicates <= 2, (duplicates, counts[channels["/drone/cam_frontal/image_raw"].id])

        json_schema = json.loads(schemas[channels["/drone/mavros/state"].schema_id].data)
        assert "armed" in json_schema["properties"]
        for _, _, msg in reader.iter_messages(topics=["/drone/mavros/local_position/pose"]):
            decoded = json.loads(msg.data)
            assert decoded["header"]["frame_id"] and "orientation" in decoded["pose"]
            break

    decoded_frames = [m.decode() for m in read_bus(out, ["drone/cam_frontal/image_raw"])]
    first = decoded_frames[0]
    assert (first.width, first.height, first.encoding) == (160, 120, "bgr8")
    pixels = np.frombuffer(first.data, np.uint8).reshape(120, 160, 3)
    assert pixels.std() > 5  # a rendered scene, not a blank frame
    truth = [m.decode() for m in read_bus(out, ["drone/sim/ground_truth"])]
    assert all(isinstance(m, PoseStamped) for m in truth)
    assert all(b.header.stamp >= a.header.stamp for a, b in itertools.pairwise(truth))


def test_a_sigkilled_recorder_leaves_a_file_that_opens(router, spawn, tmp_path):
    out = tmp_path / "killed.mcap"
    rec = spawn(_dronewrapper("record", "drone/**", "-o", str(out), "--connect", router), "rec")
    sent = 0
    with client_node(router) as node:
        pub = node.publisher(registry.LOCAL_POSE)

        def recorded_enough() -> bool:
            nonlocal sent
            assert rec.alive(), rec.output()
            for _ in range(5):
                sent += 1
                pub.put(
                    PoseStamped(header=Header(stamp=1e9 + sent), pose=Pose(position=Point(x=sent)))
                )
            return out.exists() and summarize(out).count >= 100

        wait_for(recorded_enough, 60, interval=0.02, what="100 poses flushed to the file")
        rec.proc.send_signal(signal.SIGKILL)
        rec.proc.wait(10)
    info = summarize(out)
    assert info.truncated  # no summary, no footer: cut
    assert info.count >= 100
    xs = [m.decode().pose.position.x for m in read_bus(out)]
    assert xs == sorted(xs) and len(xs) >= 50
    with out.open("rb") as f:  # the mcap library's own streaming reader reads it too
        from mcap.stream_reader import StreamReader

        records = StreamReader(f).records
        assert next(records).__class__.__name__ == "Header"


def test_an_interrupted_recorder_completes_its_file(router, spawn, tmp_path):
    out = tmp_path / "stopped.mcap"
    rec = spawn(_dronewrapper("record", "drone/**", "-o", str(out), "--connect", router), "rec")
    with client_node(router) as node:
        pub = node.publisher(registry.LOCAL_POSE)
        received = []

        def some_recorded() -> bool:
            assert rec.alive(), rec.output()
            pub.put(PoseStamped(header=Header(stamp=1e9 + len(received))))
            received.append(1)
            return out.exists() and summarize(out).count >= 10

        wait_for(some_recorded, 60, interval=0.05, what="poses flushed to the file")
        assert rec.stop() == 0, rec.output()  # SIGINT
    with out.open("rb") as f:
        summary = make_reader(f).get_summary()
    assert summary is not None and summary.statistics.message_count >= 20  # raw + JSON
    assert not summarize(out).truncated


def test_replay_into_the_perception_process_gives_the_live_detections(router, spawn):
    perception = spawn(
        python_module("dronewrapper_perception", "--connect", router, "--set", "detector=color"),
        "perception",
    )
    live = {
        m.decode().header.stamp: m.decode() for m in read_bus(HOLDOUT, [registry.DETECTIONS.key()])
    }
    with client_node(router) as node:
        got = []
        node.subscribe(registry.DETECTIONS, got.append)
        wait_for(lambda: "perception ready" in perception.output(), 60, what="perception ready")
        replay = spawn(
            _dronewrapper(
                "replay", str(HOLDOUT), "--keys", "drone/cam_frontal/image_raw",
                "--connect", router,
            ),
            "replay",
        )  # fmt: skip
        assert _wait_exit(replay, 60) == 0, replay.output()
        frames = sum(1 for _ in read_bus(HOLDOUT, ["drone/cam_frontal/image_raw"]))
        # a loaded machine may skip frames (perception takes the newest), never invent any
        wait_for(lambda: len(got) >= frames // 2, 30, what="detections for the replayed frames")
        time.sleep(0.5)
    matched = [(d, live[d.header.stamp]) for d in got if d.header.stamp in live]
    assert len(matched) >= frames // 2
    for det, ref in matched:
        assert det.target() is not None and ref.target() is not None
        dx = det.target().bbox.center.position.x - ref.target().bbox.center.position.x
        dy = det.target().bbox.center.position.y - ref.target().bbox.center.position.y
        assert abs(dx) < 4 and abs(dy) < 4


def test_replay_keeps_the_timing_and_publishes_the_clock(router, spawn):
    key = registry.CONTROLLER_STATUS.key()
    recorded = [m.log_time_ns / 1e9 for m in read_bus(HOLDOUT, [key])]
    with client_node(router) as node:
        arrivals, clock = [], []
        node.subscribe(registry.CONTROLLER_STATUS, lambda m: arrivals.append(time.monotonic()))
        node.subscribe(registry.CLOCK, lambda m: clock.append(m.stamp))
        time.sleep(0.5)  # the subscriptions reach the router
        replay = spawn(
            _dronewrapper(
                "replay", str(HOLDOUT), "--keys", key, "--rate", "2", "--clock",
                "--connect", router,
            ),
            "replay",
        )  # fmt: skip
        assert _wait_exit(replay, 60) == 0, replay.output()
        wait_for(lambda: len(arrivals) >= len(recorded), 10, what="every replayed status")
    # at twice the speed, never early: the span is at least half the recorded one
    span = arrivals[-1] - arrivals[0]
    assert span >= (recorded[-1] - recorded[0]) / 2 - 0.05
    assert clock == sorted(clock) and len(clock) > 10
    assert recorded[0] - 0.01 <= clock[0] and clock[-1] <= recorded[-1] + 0.01


def test_foxglove_server_answers_a_websocket_client(router, spawn):
    port = free_port()
    server = spawn(_dronewrapper("foxglove", "--port", str(port), "--connect", router), "foxglove")
    wait_for(lambda: "Foxglove: open" in server.output(), 30, what="the Foxglove server")
    with client_node(router) as node:
        pub = node.publisher(registry.LOCAL_POSE)
        pose = PoseStamped(header=Header(stamp=1e9), pose=Pose(position=Point(x=1.5)))

        async def talk() -> tuple[dict, dict, bytes]:
            uri = f"ws://127.0.0.1:{port}"
            async with websockets.connect(
                uri, subprotocols=["foxglove.sdk.v1", "foxglove.websocket.v1"], open_timeout=10
            ) as ws:
                info = json.loads(await asyncio.wait_for(ws.recv(), 10))
                advertised = None
                channels: dict[str, dict] = {}
                deadline = time.monotonic() + 30
                while advertised is None and time.monotonic() < deadline:
                    pub.put(pose)
                    try:
                        frame = await asyncio.wait_for(ws.recv(), 0.2)
                    except asyncio.TimeoutError:
                        continue
                    if isinstance(frame, str):
                        msg = json.loads(frame)
                        if msg.get("op") == "advertise":
                            for ch in msg["channels"]:
                                channels[ch["topic"]] = ch
                                if ch["topic"] == "/drone/mavros/local_position/pose":
                                    advertised = ch
                assert advertised is not None, "pose channel never advertised"
                # foxglove-sdk may advertise a channel a moment before it accepts subscriptions
                # to it ("Unknown channel ID"): subscribe again (new id) until data flows
                subscriptions = []
                deadline = time.monotonic() + 30
                seen = []
                next_subscribe = 0.0
                data = None
                while time.monotonic() < deadline:
                    if data is not None and "/tf" in channels:
                        return info, channels, data
                    if data is None and time.monotonic() >= next_subscribe:
                        subscriptions.append(7 + len(subscriptions))
                        request = {"id": subscriptions[-1], "channelId": advertised["id"]}
                        await ws.send(json.dumps({"op": "subscribe", "subscriptions": [request]}))
                        next_subscribe = time.monotonic() + 1.0
                    pub.put(pose)
                    try:
                        frame = await asyncio.wait_for(ws.recv(), 0.2)
                    except asyncio.TimeoutError:
                        continue
                    seen.append(frame[:1] if isinstance(frame, bytes) else frame[:80])
                    if isinstance(frame, str) and json.loads(frame).get("op") == "advertise":
                        channels.update({c["topic"]: c for c in json.loads(frame)["channels"]})
                    if isinstance(frame, bytes) and frame[0] == 0x01 and data is None:
                        sub_id, _log_time = struct.unpack_from("<IQ", frame, 1)
                        assert sub_id in subscriptions
                        data = frame[13:]
                raise AssertionError(
                    f"no message on the subscribed channel or no /tf; got {seen[:20]}\n"
                    f"{server.output()}"
                )

        info, channels, payload = asyncio.run(talk())
    advertised = channels["/drone/mavros/local_position/pose"]
    assert info["op"] == "serverInfo"
    assert (
        advertised["encoding"] == "json"
        and advertised["schemaName"] == "dronewrapper/v1/PoseStamped"
    )
    assert "properties" in json.loads(advertised["schema"])
    tf = channels["/tf"]  # the pose as a transform, same as the recorder writes
    assert (tf["encoding"], tf["schemaName"]) == ("protobuf", "foxglove.FrameTransform")
    assert json.loads(payload)["pose"]["position"]["x"] == 1.5
    assert server.stop() == 0, server.output()


def test_record_info_summarises_a_file():
    from dronewrapper.cli import main

    assert main(["record", "--info", str(HOLDOUT)]) == 0
    assert Path(HOLDOUT).exists()


def test_replay_from_a_start_time_loops_until_stopped(router, spawn):
    key = registry.CONTROLLER_STATUS.key()
    times = [m.log_time_ns for m in read_bus(HOLDOUT, [key])]
    start = summarize(HOLDOUT).start_ns  # --start counts from the recording's first message
    after = sum(1 for t in times if t >= start + 2e9)  # the last second of the recording
    with client_node(router) as node:
        stamps = []
        node.subscribe(registry.CONTROLLER_STATUS, lambda m: stamps.append(m.header.stamp))
        time.sleep(0.5)
        replay = spawn(
            _dronewrapper(
                "replay", str(HOLDOUT), "--keys", key, "--start", "2", "--loop", "--rate", "4",
                "--connect", router,
            ),
            "replay",
        )  # fmt: skip
        wait_for(lambda: len(stamps) >= 2 * after + 1, 30, what="a second pass")
        assert replay.stop() == 0, replay.output()
    first_pass = stamps[:after]
    assert stamps[after : 2 * after] == first_pass  # the same messages again
    assert min(first_pass) >= start / 1e9 + 2.0 - 0.5  # stamps lag receive times a little
    assert "pass(es)" in replay.output()
