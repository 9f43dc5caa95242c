"""The latency budget of the follow graphs, stage by stage, with the middleware's share.

For each app (follow-color on ``beacon_static``, follow-person with YOLOX on ``person_static``)
the real graph runs, every process separate, on a loopback router. This process stands beside
it and times each camera frame on its way (see :mod:`bench.budget` for the stages):

* perception's Detections carry the frame's stamp, its processing time and
  when the frame reached perception, its queue wait and its decode time;
* a subscriber takes the first velocity setpoint carrying the frame's stamp, with its send
  time (the ``sent`` attachment, on the controller's clock);
* a UDP relay between the simulator (the autopilot) and the bridge times the
  SET_POSITION_TARGET_LOCAL_NED datagram that setpoint became (MAVLink out), never before the
  setpoint was sent.

Render and publish are inside the simulator: they are the same scene rendered and encoded here
(in-process p50). The middleware's share is the total minus render and compute.
``--minutes M`` runs each graph M minutes and compares the first minute with the last.

Run: ``python -m bench.latency_budget [--app color|person|both] [--seconds 30 | --minutes 10]``;
writes results/latency_budget.json.
"""

from __future__ import annotations

import math
import select
import socket
import struct
import sys
import tempfile
import threading
import time
from dataclasses import asdict
from pathlib import Path

import numpy as np

from bench.budget import FrameTimes, budget_rows, first_datagram, growth, split_all, summarise
from bench.common import percentiles, print_table, probed_graph, write_results
from dronewrapper.msgs import codec, registry
from dronewrapper.msgs.mavros import MASK_VELOCITY, PositionTarget
from dronewrapper.msgs.sensor import Image
from dronewrapper.msgs.std import Header
from dronewrapper.msgs.vision import Detections
from dronewrapper.runtime.arguments import CommandParser, first_line
from dronewrapper.runtime.caller import origin_of
from dronewrapper.runtime.shm_put import ShmWriter
from dronewrapper_compose.ports import free_port

REPO = Path(__file__).resolve().parents[1]
ASSETS = REPO / "assets"

APPS = {
    # name: (graph, scenario, detector)
    "color": ("sim_follow_color", "beacon_static", "color"),
    "person": ("sim_follow_person", "person_static", "yolox"),
}
PREVIOUS = {
    # the reference measurement on the same VM kind, idle (glass -> setpoint at the bridge, ms):
    # p50, p99 (docs/performance.md)
    "color": (10.7, 45.0),
    "person": (33.0, 88.0),
}
SETPOINT_MSG_ID = 84  # SET_POSITION_TARGET_LOCAL_NED
WAIT_FOR_COMMANDS_S = 120.0


# ---- in-process: what happens inside the simulator ----


def render_and_publish(scenario_name: str, frames: int) -> dict[str, dict[str, float]]:
    """Per-frame render and publish of the scenario's frontal camera, in this process, the way
    the simulator does them (the frame written into Zenoh shared memory by the runtime's
    ShmWriter, without the put itself) (s in, ms out)."""
    from dronewrapper_sim.render.camera import FRONTAL, PinholeCamera
    from dronewrapper_sim.render.renderer import Renderer
    from dronewrapper_sim.world.scenario import load_scenario
    from dronewrapper_sim.world.world import World

    scenario = load_scenario(scenario_name)
    world = World(scenario)
    cam = scenario.camera
    renderer = Renderer(world, PinholeCamera(cam.width, cam.height, math.radians(cam.hfov_deg)),
                        ASSETS / "sprites")  # fmt: skip
    quat = np.array([0.0, 0.0, 0.0, 1.0])
    writer = ShmWriter()
    render_s, publish_s = [], []
    for k in range(frames):
        world.step(1.0 / cam.rate_hz)
        # a hovering drone never holds exactly still: a new pose each frame, as in flight (the
        # renderer caches the background of an unchanged pose, which would time 10x too fast)
        position = np.array([0.0, 0.0, 2.0 + 0.002 * math.sin(k)])
        t0 = time.perf_counter()
        image = renderer.render(FRONTAL, position, quat)
        t1 = time.perf_counter()
        h, w = image.shape[:2]
        view = memoryview(np.ascontiguousarray(image)).cast("B")
        writer.payload(Image(header=Header.now("cam_frontal"), height=h, width=w,
                             encoding="bgr8", step=w * 3, data=view))  # fmt: skip
        t2 = time.perf_counter()
        render_s.append(t1 - t0)
        publish_s.append(t2 - t1)
    return {"render": percentiles(render_s), "publish": percentiles(publish_s)}


# ---- MAVLink out: a relay between the simulator and the bridge ----


def parse_setpoint(datagram: bytes) -> tuple[float, float, float] | None:
    """Horizontal speed, |vz|, |yaw_rate| of a SET_POSITION_TARGET_LOCAL_NED datagram, else
    None (the bridge turns body velocities into local NED: only these survive unchanged).

    MAVLink 2 trims trailing zero bytes of the payload; they are put back.
    """
    if len(datagram) >= 10 and datagram[0] == 0xFD:
        length = datagram[1]
        msg_id = datagram[7] | datagram[8] << 8 | datagram[9] << 16
        payload = datagram[10 : 10 + length]
    elif len(datagram) >= 6 and datagram[0] == 0xFE:
        length, msg_id = datagram[1], datagram[5]
        payload = datagram[6 : 6 + length]
    else:
        return None
    if msg_id != SETPOINT_MSG_ID:
        return None
    fields = struct.unpack_from("<I11f", payload.ljust(53, b"\0"))
    vx, vy, vz, yaw_rate = fields[4], fields[5], fields[6], fields[11]
    return (math.hypot(vx, vy), abs(vz), abs(yaw_rate))


def setpoint_key(vx: float, vy: float, vz: float, yaw_rate: float) -> tuple[float, float, float]:
    """A body-velocity setpoint's horizontal speed, |vz| and |yaw_rate| (see parse_setpoint)."""
    return (math.hypot(vx, vy), abs(vz), abs(yaw_rate))


class MavlinkTap(threading.Thread):
    """Relays UDP between the simulator (sending to ``listen_port``) and the bridge (listening
    on ``bridge_port``), and notes when each setpoint datagram from the bridge passes."""

    def __init__(self, listen_port: int, bridge_port: int) -> None:
        super().__init__(name="mavlink-tap", daemon=True)
        self.sim_side = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self.sim_side.bind(("127.0.0.1", listen_port))
        self.bridge_side = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self.bridge_side.bind(("127.0.0.1", 0))
        self.bridge = ("127.0.0.1", bridge_port)
        self.sim_address: tuple[str, int] | None = None
        self.setpoints: list[tuple[float, tuple[float, float, float]]] = []
        self.stop = threading.Event()

    def run(self) -> None:
        sockets = [self.sim_side, self.bridge_side]
        while not self.stop.is_set():
            ready, _, _ = select.select(sockets, [], [], 0.2)
            for sock in ready:
                data, address = sock.recvfrom(65536)
                if sock is self.sim_side:
                    self.sim_address = address
                    self.bridge_side.sendto(data, self.bridge)
                    continue
                now = time.time()
                if self.sim_address is not None:
                    self.sim_side.sendto(data, self.sim_address)
                key = parse_setpoint(data)
                if key is not None:
                    self.setpoints.append((now, key))

    def close(self) -> None:
        self.stop.set()
        self.join(5)
        self.sim_side.close()
        self.bridge_side.close()


# ---- the probe: arrivals at a subscriber standing where perception and the bridge are ----


class Probe:
    """Arrival times of Detections and setpoints, by frame stamp (``time.time()``), with each
    setpoint's send time (NaN when it carries none)."""

    def __init__(self, session, ns: str) -> None:
        self.detections: dict[float, tuple[float, float, float, float, float]] = {}
        self.setpoints: dict[float, tuple[float, float, tuple[float, float, float]]] = {}
        self.lock = threading.Lock()
        det_dec, sp_dec = codec.decoder(Detections), codec.decoder(PositionTarget)

        def on_detections(sample) -> None:
            now = time.time()
            det = det_dec.decode(sample.payload.to_bytes())
            if det.receive_time <= 0.0:  # a perception that does not report its timing
                return
            with self.lock:
                self.detections[det.header.stamp] = (now, det.receive_time,
                                                     det.processing_time, det.queue_time,
                                                     det.decode_time)  # fmt: skip

        def on_setpoint(sample) -> None:
            now = time.time()
            sp = sp_dec.decode(sample.payload.to_bytes())
            if sp.type_mask != MASK_VELOCITY:
                return
            key = setpoint_key(sp.velocity.x, sp.velocity.y, sp.velocity.z, sp.yaw_rate)
            sent = origin_of(sample.attachment)[1]
            with self.lock:
                self.setpoints.setdefault(
                    sp.header.stamp, (now, math.nan if sent is None else sent, key)
                )

        self._subs = [
            session.declare_subscriber(registry.DETECTIONS.key(ns), on_detections),
            session.declare_subscriber(registry.SETPOINT_RAW_LOCAL.key(ns), on_setpoint),
        ]

    def clear(self) -> None:
        with self.lock:
            self.detections.clear()
            self.setpoints.clear()

    def close(self) -> None:
        for sub in self._subs:
            sub.undeclare()


def match_frames(probe: Probe, tap_setpoints) -> list[FrameTimes]:
    """Join what was seen of each frame that produced a command; MAVLink out is the first
    setpoint datagram with the same values after the setpoint was sent (bench.budget's
    ``first_datagram``)."""
    mav = sorted(tap_setpoints)
    used: set[int] = set()
    frames = []
    with probe.lock:
        items = sorted(probe.setpoints.items())
        for stamp, (sp_arrival, sent, key) in items:
            if stamp not in probe.detections:
                continue
            det_arrival, received, processing, queue, decode = probe.detections[stamp]
            out = first_datagram(sent, key, mav, used)
            frames.append(
                FrameTimes(stamp=stamp, image_arrival=received,
                           detections_arrival=det_arrival, processing=processing, queue=queue,
                           decode=decode, setpoint_arrival=sp_arrival, setpoint_sent=sent,
                           mavlink_out=out)
            )  # fmt: skip
    return frames


def graph_with_tap(graph: str) -> Path:
    """A copy of the graph whose simulator talks to ``${tap_port}`` instead of the bridge."""
    text = (REPO / "compose" / f"{graph}.yaml").read_text()
    sim_link = '"${onboard_port}:0"'
    if sim_link not in text:
        raise RuntimeError(f"{graph}.yaml: cannot find the simulator's onboard link {sim_link}")
    text = text.replace(sim_link, '"${tap_port}:0"')
    text = text.replace("\nvars:\n", '\nvars:\n  tap_port: "0"\n', 1)
    text = text.replace("config: ../", f"config: {REPO}/")
    out = Path(tempfile.mkdtemp(prefix="latency_budget_")) / f"{graph}_tapped.yaml"
    out.write_text(text)
    return out


def run_graph(app: str, seconds: float) -> tuple[list[FrameTimes], dict[str, object]]:
    """Run one app's graph; the frames seen over ``seconds`` once it commands the drone."""
    from dronewrapper_compose.launcher import Launcher

    graph, scenario, detector = APPS[app]
    router = f"tcp/127.0.0.1:{free_port('tcp')}"
    bridge_port, tap_port = free_port("udp"), free_port("udp")
    variables = {
        "scenario": scenario,
        "onboard_port": str(bridge_port),
        "tap_port": str(tap_port),
        "gcs_port": str(free_port("udp")),
        "on_exit": "stop",
    }
    if graph == "sim_follow_person":
        variables["detector"] = detector
    path = graph_with_tap(graph)
    log_path = REPO / "out" / "bench" / f"latency_budget_{app}.log"
    log_path.parent.mkdir(parents=True, exist_ok=True)
    tap = MavlinkTap(tap_port, bridge_port)
    tap.start()
    facts: dict[str, object] = {"graph": graph, "scenario": scenario, "log": str(log_path)}
    with open(log_path, "w") as log_file:
        launcher = Launcher.from_file(path, router=router, variables=variables, out=log_file)
        try:
            with probed_graph(launcher, router, Probe) as probe:
                deadline = time.monotonic() + WAIT_FOR_COMMANDS_S
                while not probe.setpoints and time.monotonic() < deadline:
                    time.sleep(0.2)
                if not probe.setpoints:
                    raise RuntimeError(f"{graph}: no velocity setpoint in {WAIT_FOR_COMMANDS_S} s")
                time.sleep(2.0)  # past the first commands
                probe.clear()
                tap.setpoints.clear()
                start = time.time()
                time.sleep(seconds)
                facts["measured_s"] = time.time() - start
                frames = match_frames(probe, list(tap.setpoints))
                facts["detections_seen"] = len(probe.detections)
        finally:
            tap.close()
            path.unlink(missing_ok=True)
            path.parent.rmdir()
    return frames, facts


def measure(app: str, seconds: float, frames: int = 120) -> dict[str, object]:
    """The budget of one app: in-process render/publish, then the graph (ms out)."""
    scenario = APPS[app][1]
    local = render_and_publish(scenario, frames)
    seen, facts = run_graph(app, seconds)
    render_s = local["render"]["p50_ms"] / 1e3
    publish_s = local["publish"]["p50_ms"] / 1e3
    per_frame, kept, out_of_order = split_all(seen, render_s, publish_s)
    summary = summarise(per_frame)
    to_setpoint = [f.setpoint_arrival - f.stamp for f in kept]
    result: dict[str, object] = {
        **facts,
        "in_process": local,
        "frames": len(kept),
        "frames_out_of_order": len(out_of_order),
        "out_of_order_examples": out_of_order[:3],
        "stages": summary,
        "glass_to_setpoint": percentiles(to_setpoint),
        "previous_glass_to_setpoint_ms": dict(zip(("p50", "p99"), PREVIOUS[app], strict=True)),
    }
    times = [f.stamp for f in kept]
    for key in ("total", "middleware"):
        result[f"growth_{key}"] = asdict(growth(times, [p[key] for p in per_frame]))
    return result


def print_budget(app: str, result: dict) -> None:
    summary = result["stages"]
    print_table(
        f"latency budget, {app} ({result['graph']} on {result['scenario']}, "
        f"{result['frames']} frames that produced a command; ms)",
        ["stage", "middleware", "p50", "p99"],
        budget_rows(summary),
    )
    sp = result["glass_to_setpoint"]
    prev = PREVIOUS[app]
    p50, p99 = sp.get("p50_ms", math.nan), sp.get("p99_ms", math.nan)
    print(f"  glass -> setpoint at a subscriber: p50 {p50:.1f} / p99 {p99:.1f} ms "
          f"(reference: {prev[0]} / {prev[1]} ms)")  # fmt: skip
    det = summary["detections_to_subscriber"]
    print(f"  reference: Detections published -> at a subscriber beside the controller: "
          f"p50 {det['p50_ms']:.2f} / p99 {det['p99_ms']:.2f} ms")  # fmt: skip
    if result.get("frames_out_of_order"):
        print(f"  left out: {result['frames_out_of_order']} frames whose instants are out of "
              f"order, e.g. {result['out_of_order_examples'][0]}")  # fmt: skip
    mw = summary["middleware"]
    print(f"  middleware share: p50 {mw['p50_ms']:.2f} ms (target <= 3), p99 {mw['p99_ms']:.2f} ms"
          f" (target <= 10)")  # fmt: skip
    g = result["growth_total"]
    if result.get("measured_s", 0) >= 120:
        print(f"  growth, first vs last minute: total p50 {g['first_p50_ms']:.1f} -> "
              f"{g['last_p50_ms']:.1f} ms, p99 {g['first_p99_ms']:.1f} -> {g['last_p99_ms']:.1f}"
              f" ms; middleware p50 {result['growth_middleware']['first_p50_ms']:.2f} -> "
              f"{result['growth_middleware']['last_p50_ms']:.2f} ms")  # fmt: skip


def main(argv: list[str] | None = None) -> int:
    parser = CommandParser(description=first_line(__doc__))
    parser.add_argument("--app", choices=("color", "person", "both"), default="both")
    parser.add_argument("--seconds", type=float, default=30.0, help="measured time per app")
    parser.add_argument("--minutes", type=float, help="measured time per app in minutes "
                        "(>= 2 shows the first against the last minute)")  # fmt: skip
    args = parser.parse_args(argv)
    seconds = args.minutes * 60.0 if args.minutes else args.seconds
    if not (math.isfinite(seconds) and seconds > 0):
        parser.error("--seconds/--minutes must be positive")
    apps = ["color", "person"] if args.app == "both" else [args.app]
    results = {}
    for app in apps:
        results[app] = measure(app, seconds)
        print_budget(app, results[app])
    write_results("latency_budget", {"seconds": seconds, "apps": results})
    return 0


if __name__ == "__main__":
    sys.exit(main())
