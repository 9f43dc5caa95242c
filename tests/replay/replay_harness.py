"""The replay tier's engine: recorded inputs through perception and the controller, in recorded
time on the runtime's fake bus, and the comparison of their outputs with stored references.

Perception: every recorded frontal-camera frame is delivered on a :class:`FakeBus` at its
recorded time and the real :class:`PerceptionService` (subscriber, newest-frame slot, pipeline,
publisher) processes it. Controller: the recorded detections are delivered the same way to the
real :class:`Controller` (dry run: no aircraft), stepped at each of its wakes and each delivery,
with the bus clock as its time; every command its control loop gives is recorded.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from dronewrapper.msgs import Detections, registry
from dronewrapper.record.reader import read_bus
from dronewrapper.runtime.config import load_config
from dronewrapper.runtime.fake import FakeBus, FakeNode
from dronewrapper_controller.config import Config as ControllerConfig
from dronewrapper_controller.node import PORTS as CONTROLLER_PORTS
from dronewrapper_controller.node import Controller
from dronewrapper_perception.config import Config as PerceptionConfig
from dronewrapper_perception.node import PORTS as PERCEPTION_PORTS
from dronewrapper_perception.node import PerceptionService

REPO = Path(__file__).resolve().parents[2]
DATA = Path(__file__).resolve().parent / "data"
CAMERA = "cam_frontal"
RECORDINGS = {
    # name: (perception config, controller config overrides); the graph's settings
    "beacon_smooth": ({"detector": "color"}, {"mode": "follow_color"}),
    "holdout_teleop": ({"detector": "color"}, {"mode": "follow_color"}),
    "people_crossing_front": (
        {
            "detector": "yolox",
            "model_path": str(REPO / "assets" / "models" / "yolox_nano.onnx"),
            "tracker": "kalman",
            "threads": 1,  # same results on any machine: no thread-count-dependent sums
        },
        {"mode": "follow_person"},
    ),
}
HOLDOUT = "holdout_teleop"
"""Flown on a path of its own (see record_sim.py): never used to tune anything."""

BBOX_TOL_PX = 1.0
SCORE_TOL = 0.02
CMD_TOL = 1e-3  # m/s, rad/s (plus 1 % of the value)


def recording(name: str) -> Path:
    return DATA / f"{name}.mcap"


def reference_path(name: str) -> Path:
    return DATA / f"{name}.reference.json"


def detection_rows(msg: Detections) -> dict[str, Any]:
    """The comparable content of a Detections message (no processing time)."""
    return {
        "stamp": msg.header.stamp,
        "target_id": msg.target_id,
        "detections": [
            {
                "id": d.id,
                "class": d.results[0].hypothesis.class_id if d.results else "",
                "score": round(d.results[0].hypothesis.score, 6) if d.results else 0.0,
                "cx": round(d.bbox.center.position.x, 3),
                "cy": round(d.bbox.center.position.y, 3),
                "w": round(d.bbox.size_x, 3),
                "h": round(d.bbox.size_y, 3),
            }
            for d in msg.detections
        ],
    }


def replay_perception(name: str) -> list[Detections]:
    """Perception's outputs for the recording's camera frames, in recorded time."""
    perception, _ = RECORDINGS[name]
    frames = list(read_bus(recording(name), [registry.IMAGE_RAW.key(camera=CAMERA)]))
    bus = FakeBus(start=frames[0].log_time_ns / 1e9)
    node = FakeNode("perception", bus, ports=PERCEPTION_PORTS)
    service = PerceptionService(node, load_config(PerceptionConfig, data=perception))
    for frame in frames:
        bus.schedule(frame.log_time_ns / 1e9, frame.key, frame.payload)
    while bus.step():
        service.spin_once(0.0)
    return [d.msg for d in bus.published[registry.DETECTIONS.key()]]


def replay_controller(name: str) -> list[dict[str, Any]]:
    """The controller's commands for the recording's detections, in recorded time."""
    _, overrides = RECORDINGS[name]
    config = load_config(
        ControllerConfig,
        REPO / "services/controller/dronewrapper_controller" / "config" / "iris_sim.yaml",
        data={**overrides, "dry_run": True},
    )
    recorded = list(read_bus(recording(name), [registry.DETECTIONS.key()]))
    t0 = recorded[0].log_time_ns / 1e9
    bus = FakeBus(start=t0)
    controller = Controller(FakeNode("controller", bus, ports=CONTROLLER_PORTS), config, None)
    out: list[dict[str, Any]] = []
    tick = controller.loop.tick

    def recorded_tick(now: float, detections: Detections | None, age: float) -> Any:
        cmd = tick(now, detections, age)
        if cmd is not None:
            out.append(
                {
                    "t": round(now - t0, 6),
                    "state": cmd.state,
                    "vx": cmd.vx,
                    "vz": cmd.vz,
                    "yaw_rate": cmd.yaw_rate,
                    "source_stamp": cmd.source_stamp,
                }
            )
        return cmd

    controller.loop.tick = recorded_tick  # type: ignore[method-assign]
    for msg in recorded:
        bus.schedule(msg.log_time_ns / 1e9, msg.key, msg.payload)
    while bus.pending:
        now = bus.clock()
        bus.run_until(now)  # what arrives now wakes the controller before its step
        controller.step(now)
        wake = max(controller.next_wake(now), now + 1e-6)
        queued = bus.next_time()
        bus.clock.advance_to(wake if queued is None else min(wake, queued))
    return out


def outputs(name: str) -> dict[str, Any]:
    """Everything the tier compares for one recording."""
    return {
        "perception": [detection_rows(d) for d in replay_perception(name)],
        "controller": replay_controller(name),
    }


@dataclass
class Diff:
    """How replayed outputs differ from the reference; ``problems`` empty when within tolerance."""

    problems: list[str]
    max_bbox_px: float = 0.0
    max_cmd: float = 0.0

    def report(self, name: str) -> str:
        head = (
            f"{name}: max bbox change {self.max_bbox_px:.3f} px (tol {BBOX_TOL_PX}), "
            f"max command change {self.max_cmd:.2e} (tol {CMD_TOL:g} + 1 %)"
        )
        if not self.problems:
            return head + ": same within tolerance"
        shown = self.problems[:20]
        more = len(self.problems) - len(shown)
        return "\n  ".join([head, *shown] + ([f"... {more} more"] if more > 0 else []))


def compare(got: dict[str, Any], ref: dict[str, Any]) -> Diff:
    """Compare outputs with a reference, with the tolerances above."""
    diff = Diff([])
    gp, rp = got["perception"], ref["perception"]
    if len(gp) != len(rp):
        diff.problems.append(f"perception: {len(gp)} outputs, reference {len(rp)}")
    for i, (g, r) in enumerate(zip(gp, rp, strict=False)):
        where = f"perception[{i}] stamp {r['stamp']:.3f}"
        if g["stamp"] != r["stamp"]:
            diff.problems.append(f"{where}: stamp {g['stamp']:.3f}")
        if g["target_id"] != r["target_id"]:
            diff.problems.append(f"{where}: target {g['target_id']!r} was {r['target_id']!r}")
        if len(g["detections"]) != len(r["detections"]):
            n, m = len(g["detections"]), len(r["detections"])
            diff.problems.append(f"{where}: {n} detections, reference {m}")
        for gd, rd in zip(g["detections"], r["detections"], strict=False):
            px = max(abs(gd[k] - rd[k]) for k in ("cx", "cy", "w", "h"))
            diff.max_bbox_px = max(diff.max_bbox_px, px)
            if px > BBOX_TOL_PX or (gd["id"], gd["class"]) != (rd["id"], rd["class"]):
                diff.problems.append(f"{where}: detection {gd} was {rd}")
            elif abs(gd["score"] - rd["score"]) > SCORE_TOL:
                diff.problems.append(f"{where}: score {gd['score']} was {rd['score']}")
    gc, rc = got["controller"], ref["controller"]
    if len(gc) != len(rc):
        diff.problems.append(f"controller: {len(gc)} commands, reference {len(rc)}")
    for i, (g, r) in enumerate(zip(gc, rc, strict=False)):
        where = f"controller[{i}] t={r['t']:.3f}"
        if g["state"] != r["state"] or g["source_stamp"] != r["source_stamp"]:
            diff.problems.append(f"{where}: {g['state']} for {g['source_stamp']} was {r}")
        for k in ("vx", "vz", "yaw_rate"):
            d = abs(g[k] - r[k])
            diff.max_cmd = max(diff.max_cmd, d)
            if not math.isclose(g[k], r[k], rel_tol=0.01, abs_tol=CMD_TOL):
                diff.problems.append(f"{where}: {k} {g[k]:.4f} was {r[k]:.4f}")
    return diff
