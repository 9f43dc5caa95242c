"""Fuzz the real processes over a real router (a bounded number of examples).

The bridge, perception (colour) and controller run as their own processes, as a graph would run
them; the autopilot is an AutopilotPeer in this process on real UDP. Every service of the bridge,
its setpoint key, the controller's detections key and perception's image key are fed broken
payloads. Then: every process is still running and still does its job (the bridge answers a
valid read, perception turns a valid frame into detections, the controller keeps publishing its
status), no detections with a non-finite stamp were published, and nothing that could actuate
reached the autopilot (the controller, on the ground and never told to take off, may stream
hover setpoints: no command, mode change, parameter write or arming is allowed).
"""

from __future__ import annotations

import math
import socket
import time

import msgspec
import pytest
from autopilot_peer import AutopilotPeer
from bridge_rig import Collected
from fuzz_inputs import REQUESTS, Bad, bad_image, bad_request, bad_setpoint, detections
from hypothesis import HealthCheck, given, settings

from dronewrapper.msgs import codec, registry
from dronewrapper.msgs.mavros import ParamGet
from dronewrapper.msgs.sensor import Image
from dronewrapper.msgs.std import ErrorReply, Header
from dronewrapper.msgs.vision import BoundingBox2D, Detection2D, Detections
from support import client_node, free_port, python_module, wait_for, zenoh_router

pytestmark = [pytest.mark.fuzz, pytest.mark.integration]

BOUNDED = settings(
    max_examples=8,
    deadline=None,
    derandomize=True,
    database=None,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large],
)
SERVICES = ("bridge_mavlink", "perception", "controller")


def service_argv(module: str, name: str, router: str, *extra: str) -> list[str]:
    return python_module(
        module, *extra, "--connect", router, "--namespace", "drone", "--name", name,
        "--mode", "peer",
    )  # fmt: skip


def alive_services(user) -> set[str]:
    replies = user.session.liveliness().get("drone/alive/*", timeout=2)
    return {str(r.ok.key_expr).rsplit("/", 1)[1] for r in replies if r.ok is not None}


def test_the_running_graph_survives_bad_input_and_actuates_nothing(spawn):
    port = free_port(socket.SOCK_DGRAM)
    with zenoh_router() as router:
        peer = AutopilotPeer(port)
        user = client_node(router, name="fuzzer")
        procs: dict = {}
        try:
            procs = {
                "bridge_mavlink": spawn(
                    service_argv(
                        "dronewrapper_bridge_mavlink", "bridge_mavlink", router,
                        "--connection", f"udpin:127.0.0.1:{port}",
                    ),
                    "bridge",
                ),
                "perception": spawn(
                    service_argv(
                        "dronewrapper_perception", "perception", router, "--set", "detector=color"
                    ),
                    "perception",
                ),
                "controller": spawn(
                    service_argv(
                        "dronewrapper_controller", "controller", router,
                        "--set", "mode=follow_color", "--set", "takeoff.on_start=false",
                        "--set", "on_exit=stop",
                    ),
                    "controller",
                ),
            }  # fmt: skip
            fuzz_graph(user, peer, procs)
        finally:
            user.close()
            peer.close()
            for proc in procs.values():
                proc.stop()
    for name, proc in procs.items():
        assert proc.proc.returncode == 0, (
            f"{name} exited with {proc.proc.returncode}:\n" + (proc.output()[-3000:])
        )


def fuzz_graph(user, peer: AutopilotPeer, procs: dict) -> None:
    wait_for(
        lambda: alive_services(user) >= set(SERVICES),
        120,
        interval=0.5,
        what=f"{', '.join(SERVICES)} ready (alive: {alive_services(user)})",
    )
    published = Collected()
    status = Collected()
    user.subscribe(registry.DETECTIONS, published)
    user.subscribe(registry.CONTROLLER_STATUS, status)
    since = time.monotonic()

    for name in sorted(REQUESTS):
        refusals(user, REQUESTS[name])()

    @settings(BOUNDED, max_examples=15)
    @given(bad=bad_setpoint(), frames=detections(), image=bad_image())
    def published_garbage(bad: Bad, frames, image: bytes) -> None:
        user.session.put(registry.SETPOINT_RAW_LOCAL.key("drone"), bad.payload)
        frames = msgspec.structs.replace(frames, detector="fuzz")  # not perception's
        user.session.put(registry.DETECTIONS.key("drone"), codec.encode(frames))
        user.session.put(registry.IMAGE_RAW.key("drone", camera="cam_frontal"), image)

    published_garbage()
    # issue 12 item 4, exactly: a target in view with header.stamp = inf killed the controller
    for stamp in (math.inf, math.nan, -math.inf):
        user.session.put(registry.DETECTIONS.key("drone"), codec.encode(target_in_view(stamp)))

    for name, proc in procs.items():
        assert proc.alive(), f"{name} died:\n{proc.output()[-3000:]}"
    # still doing their jobs
    got = user.call(registry.PARAM_GET, ParamGet(param_id="MPC_XY_VEL_MAX"), timeout=15)
    assert got.success and got.value.real == 12.0
    frame = Image(
        header=Header(stamp=time.time(), frame_id="cam_frontal"),
        height=2,
        width=4,
        encoding="bgr8",
        data=bytes(24),
    )
    camera = user.publisher(registry.IMAGE_RAW, camera="cam_frontal")
    after = time.monotonic()
    wait_for(
        lambda: camera.put(frame) or [m for m in published.values(after) if m.detector == "color"],
        30,
        interval=0.3,
        what="perception to process a valid frame after the fuzz",
    )
    wait_for(lambda: len(status.values(after)) >= 3, 15, what="the controller's status")
    for msg in published.values(since):
        if msg.detector != "fuzz":
            assert math.isfinite(msg.header.stamp), msg.header
    actuating = [m for m in peer.actuating(since) if "POSITION_TARGET" not in m.get_type()]
    assert actuating == []


def refusals(user, shape):
    """A hypothesis test: broken requests to ``shape``'s service each get an error naming it."""

    @BOUNDED
    @given(bad=bad_request(shape))
    def refused(bad: Bad) -> None:
        key = shape.service.key("drone")
        replies = list(user.session.get(key, payload=bad.payload, timeout=15))
        assert len(replies) == 1 and replies[0].err is not None, bad
        message = codec.decode(ErrorReply, replies[0].err.payload.to_bytes()).message
        assert bad.named in message, message

    return refused


def target_in_view(stamp: float) -> Detections:
    """A red blob in the middle of the frame: the controller would steer on it."""
    blob = Detection2D(
        id="1",
        bbox=BoundingBox2D.at(160.0, 120.0, 30, 30),
        circle_radius=15.0,
    )
    return Detections(
        header=Header(stamp=stamp, frame_id="cam_frontal"),
        detections=[blob],
        image_width=320,
        image_height=240,
        detector="fuzz",
        target_id="1",
    )
