"""Fly a follow graph in the simulator and record it from ground truth (helper for the tests).

Each flight runs a compose graph (any aircraft: the intended distance comes from the controller
config the graph starts) through the launcher's Python API on a free loopback router
with free UDP ports, records vehicle, objects and controller status with FollowMonitor, then
stops everything. The controller uses ``on_exit: stop`` so a flight ends quickly. A flight
lasts a fixed time of servoing, counted from the end of the take-off, so a slow start on a
loaded machine (imports, model loading, take-off) does not eat into what is judged.
"""

from __future__ import annotations

import itertools
import math
import time
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Protocol

import msgspec
import zenoh

from dronewrapper.rotations import wrap_pi
from dronewrapper.runtime.config import load_config
from dronewrapper.runtime.node import open_session
from dronewrapper.runtime.options import ZenohOptions
from dronewrapper_compose.graph import Graph, load_graph
from dronewrapper_compose.launcher import Launcher, build_argv
from dronewrapper_compose.ports import private_links
from dronewrapper_controller.config import Config as ControllerConfig
from dronewrapper_sim.evaluation.metrics import (
    TRACKING_STATES,
    FollowSample,
    FollowSummary,
    bearing_error,
    colour_intended_distance,
    person_intended_distance,
    summarize,
)
from dronewrapper_sim.evaluation.monitor import FollowMonitor
from dronewrapper_sim.world.scenario import load_scenario
from support import REPO, free_port

CONTROLLER_CONFIG = (
    REPO / "services/controller/dronewrapper_controller" / "config" / "iris_sim.yaml"
)
CENTRED_TOLERANCE = math.radians(10.0)
DISTANCE_TOLERANCE = 1.5  # m
# A person's box, as a multiple of their height (tall, wide). YOLOX: the box fits the person
# (rendered sprites with arms: about 0.5 x as wide as tall). HOG (OpenCV's people detector):
# a 64x128 window in which a person is about 96 px tall, so the box is 128/96 x their height
# and half as wide as tall.
PERSON_BOX = {"yolox": (1.0, 0.5), "hog": (128 / 96, 64 / 96)}


@dataclass
class Flight:
    scenario: str
    samples: list[FollowSample]
    summary: FollowSummary
    exit_code: int
    log: str
    failures: list[str] = field(default_factory=list)

    def describe(self) -> str:
        s = self.summary
        return (
            f"{self.scenario}: acquire {s.time_to_acquire:.1f} s, centred {s.centred_share:.0%}, "
            f"seen {s.visible_share:.0%}, distance err mean {s.distance_mean:.2f} m "
            f"p95 {s.distance_p95:.2f} m (intended {s.intended_distance:.2f} m), within "
            f"{DISTANCE_TOLERANCE} m {s.distance_share:.0%}, bearing p95 "
            f"{math.degrees(s.bearing_p95):.1f} deg, {s.samples} samples"
        )

    def timeline(self, step_s: float = 1.0) -> str:
        """One line per ``step_s`` of the recording (for failure messages): time, controller
        state, target seen, bearing and elevation errors (deg), distance (m), and the object
        nearest the optical axis."""
        lines, next_t = [], -math.inf
        for x in self.samples:
            if x.t >= next_t:
                next_t = x.t + step_s
                lines.append(
                    f"{x.t:5.1f} s {x.state or '-':9s} seen {int(x.target_visible)} "
                    f"bearing {math.degrees(x.bearing):6.1f} elev {math.degrees(x.elevation):6.1f} "
                    f"d {x.distance:4.1f} m nearest {x.closest_to_axis()}"
                )
        return "\n".join(lines)


def controller_config(launcher: Launcher) -> ControllerConfig:
    """The controller's config exactly as the graph starts it (its --config and --set)."""
    spec = next(p for p in launcher.graph.processes if p.module == "dronewrapper_controller")
    argv, _ = build_argv(spec, launcher.values, launcher.graph_path, launcher.ns, launcher.router)
    path = argv[argv.index("--config") + 1] if "--config" in argv else None
    sets = [value for flag, value in itertools.pairwise(argv) if flag == "--set"]
    return load_config(ControllerConfig, path, sets)


def intended_distance(
    scenario_name: str, detector: str = "yolox", cfg: ControllerConfig | None = None
) -> tuple[float, float]:
    """(intended distance m, aim height m) of a controller config (default: the simulated
    Iris's) in this scenario, from the scenario's camera and target."""
    scenario = load_scenario(scenario_name)
    target = next(o for o in scenario.objects if o.name == "target")
    cfg = cfg or load_config(ControllerConfig, CONTROLLER_CONFIG)
    cam = scenario.camera
    hfov = math.radians(cam.hfov_deg)
    if target.kind == "beacon":
        d = colour_intended_distance(
            cfg.follow_color.target_radius, cfg.ref_width, cam.width, hfov, target.radius_m
        )
        return d, 0.0
    height = target.height_m or 1.75
    d = person_intended_distance(
        cfg.follow_person.area_ratio,
        cam.width,
        cam.height,
        hfov,
        PERSON_BOX[detector][0] * height,
        PERSON_BOX[detector][1] * height,
    )
    return d, height / 2.0


RESULTS_ENV = "DRONEWRAPPER_CAPABILITIES"  # a JSON-lines file: each app flight's result


def record_result(flight: Flight, app: str, backend: str, firmware: str, passed: bool) -> None:
    """Append ``flight``'s result to ``$DRONEWRAPPER_CAPABILITIES`` when it is set (for
    docs/capabilities.md, ``python -m bench.capabilities render``)."""
    import datetime
    import json
    import os

    path = os.environ.get(RESULTS_ENV, "").strip()
    if not path:
        return
    s = flight.summary
    entry = {
        "kind": "app",
        "app": app,
        "scenario": flight.scenario,
        "backend": backend,
        "firmware": firmware,
        "date": datetime.date.today().isoformat(),
        "passed": passed,
        "acquire_s": s.time_to_acquire if math.isfinite(s.time_to_acquire) else None,
        "centred": s.centred_share,
        "within_distance": s.distance_share,
    }
    with open(path, "a") as out:
        out.write(json.dumps(entry) + "\n")


START_TIMEOUT_S = 60.0  # from the graph being up to the controller servoing (after take-off)
MIN_TRACKED_S = 8.0  # a flight goes on at least this long after the target was acquired


def _acquired(samples: list[FollowSample]) -> bool:
    """The controller sees the target and it is centred (as ``summarize`` defines acquisition)."""
    return any(
        s.state in TRACKING_STATES and s.target_visible and s.centred(CENTRED_TOLERANCE)
        for s in samples
    )


class Watcher(Protocol):
    """Something that watches the graph's bus during a flight (opened with the session and the
    graph's namespace) and is closed after it."""

    def close(self) -> None: ...


def with_settings(graph: Graph, settings: Mapping[str, Mapping[str, str]]) -> Graph:
    """``graph`` with more ``set`` entries for some processes (process name -> key -> value),
    as ``--set`` on their command lines: a bridge put on another link, say."""
    unknown = set(settings) - {spec.name for spec in graph.processes}
    if unknown:
        raise ValueError(f"no process {sorted(unknown)} in the graph")
    processes = [
        msgspec.structs.replace(spec, set={**spec.set, **settings.get(spec.name, {})})
        for spec in graph.processes
    ]
    return msgspec.structs.replace(graph, processes=processes)


def fly(
    graph: str,
    scenario: str,
    seconds: float,
    tmp_path: Path,
    variables: dict[str, str] | None = None,
    start_timeout: float = START_TIMEOUT_S,
    router: str = "",
    settings: Mapping[str, Mapping[str, str]] | None = None,
    watch: Callable[[zenoh.Session, str], Watcher] | None = None,
) -> Flight:
    """Run ``compose/<graph>.yaml`` on ``scenario`` and record until the controller has been
    servoing (after its take-off) for ``seconds`` and, when it acquired the target late, for
    MIN_TRACKED_S after that; or until ``start_timeout`` s passed without servoing. ``router``:
    the graph's router endpoint ("": a free loopback port); ``settings``: more ``set`` entries
    by process (:func:`with_settings`); ``watch``: opened on the recording's session and the
    graph's namespace once the graph is up, closed at the end."""
    router = router or f"tcp/127.0.0.1:{free_port()}"
    values = {
        "scenario": scenario,
        **private_links(),
        "on_exit": "stop",
        **(variables or {}),
    }
    log_path = tmp_path / f"{graph}-{scenario}.log"
    with open(log_path, "w") as log_file:
        path = REPO / "compose" / f"{graph}.yaml"
        spec = with_settings(load_graph(path), settings or {})
        launcher = Launcher(spec, path, router=router, variables=values, out=log_file)
        goal, aim = intended_distance(
            scenario, values.get("detector", "yolox"), controller_config(launcher)
        )
        monitor = session = watcher = None
        try:
            launcher.start()
            session = open_session(ZenohOptions(mode="client", connect=[router]))
            monitor = FollowMonitor(session, launcher.ns, aim_height=aim).start()
            watcher = watch(session, launcher.ns) if watch is not None else None
            deadline = time.monotonic() + start_timeout  # until servoing starts
            servoing = acquired = False
            while time.monotonic() < deadline:
                dead = [c.name for c in launcher.children if c.poll() is not None]
                assert not dead, f"{dead} died; log {log_path}:\n{log_path.read_text()[-4000:]}"
                status = monitor.status.value
                if not servoing and status is not None and status.state in TRACKING_STATES:
                    servoing = True
                    deadline = time.monotonic() + seconds
                if servoing and not acquired and _acquired(monitor.samples[-3:]):
                    acquired = True  # judge at least MIN_TRACKED_S after a late acquisition
                    deadline = max(deadline, time.monotonic() + MIN_TRACKED_S)
                time.sleep(0.2)
        finally:
            if watcher is not None:
                watcher.close()
            if monitor is not None:
                monitor.close()
            if session is not None:
                session.close()
            code = launcher.stop()
    samples = list(monitor.samples) if monitor is not None else []
    summary = summarize(
        samples,
        intended_distance=goal,
        centred_tolerance=CENTRED_TOLERANCE,
        distance_tolerance=DISTANCE_TOLERANCE,
    )
    return Flight(scenario, samples, summary, code, log_path.read_text(), list(launcher.failures))


def passes(flight: Flight, max_acquire: float, min_centred: float, min_distance: float) -> bool:
    """Whether ``flight`` meets its bounds (acquired within ``max_acquire`` s, centred and at
    the intended distance at least these shares of the time), as the capability matrix
    records it."""
    s = flight.summary
    return (
        flight.exit_code == 0
        and s.samples > 50
        and s.time_to_acquire <= max_acquire
        and s.centred_share >= min_centred
        and s.distance_share >= min_distance
    )


def check_flight(flight: Flight, max_acquire: float, min_centred: float, min_distance: float):
    """Assert each bound of :func:`passes`, the flight's description, timeline and log tail
    in the failure."""
    s = flight.summary
    print(flight.describe())
    detail = f"{flight.describe()}\n{flight.timeline()}\n{flight.log[-3000:]}"
    assert flight.exit_code == 0, f"graph failures: {flight.failures}\n{detail}"
    assert s.samples > 50, f"too few samples: {detail}"
    assert s.time_to_acquire <= max_acquire, detail
    assert s.centred_share >= min_centred, detail
    assert s.distance_share >= min_distance, detail


def crossed(sample: FollowSample) -> bool:
    """A passer-by is within 5 deg of the target's bearing (in front of or behind it)."""
    return any(
        abs(wrap_pi(bearing_error(sample.vehicle, sample.yaw, pos) - sample.bearing))
        < math.radians(5)
        for pos in sample.others.values()
    )
