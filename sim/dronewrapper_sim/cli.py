"""``dronewrapper sim``: the simulated PX4-like aircraft and its world.

A PX4-like autopilot speaking MAVLink 2 on UDP like PX4 SITL (onboard link to 14540+N from
14580+N, GCS link to 14550 from 18570+N, system id 1+N), over quadrotor physics, with the
scenario's world and the frontal and ventral cameras published on Zenoh.

    dronewrapper sim --scenario beacon_static
    dronewrapper sim --instance 1 --no-cameras          # a second drone: drone1, sysid 2
    dronewrapper sim --udp-onboard 15000:0 --udp-gcs off  # test ports (LOCAL 0 = ephemeral)
    dronewrapper sim --aircraft tello                   # a DJI Tello on 127.0.0.1:8889
    sudo dronewrapper sim --aircraft tello --netns      # ... at 192.168.10.1, as a real one
    dronewrapper sim --autopilot px4-sih                # the world around real PX4 SIH
    dronewrapper sim --autopilot ardupilot              # ... around real ArduCopter SITL
"""

from __future__ import annotations

import argparse
import json
import logging
import os
from collections.abc import Sequence

from dronewrapper.msgs import registry
from dronewrapper.msgs.registry import DEFAULT_NAMESPACE
from dronewrapper.runtime.config import ConfigError
from dronewrapper.runtime.contract import NodeApi
from dronewrapper.runtime.options import ENV_PREFIX
from dronewrapper.runtime.ports import Ports
from dronewrapper.runtime.service import run_service
from dronewrapper_sim.config import SimConfig
from dronewrapper_sim.world.scenario import SCENARIO_NAMES
from dronewrapper_sim.world_process import run_world

log = logging.getLogger("sim")


def add_args(parser: argparse.ArgumentParser) -> None:
    """The simulator's own flags (each one sets a SimConfig field)."""
    group = parser.add_argument_group("simulator")
    group.add_argument(
        "--scenario",
        help=f"{' | '.join(SCENARIO_NAMES)}, or a YAML file (default beacon_static)",
    )
    group.add_argument("--instance", type=int, help="vehicle instance N (ports, sysid, ns)")
    group.add_argument("--seed", type=int, help="random seed (default: the scenario's)")
    group.add_argument("--no-cameras", action="store_true", help="do not render cameras")
    group.add_argument("--camera-rate", type=float, metavar="HZ", help="camera rate")
    group.add_argument("--width", type=int, help="image width, px")
    group.add_argument("--height", type=int, help="image height, px")
    group.add_argument("--sprites", metavar="DIR", help="person sprite folder (billboards)")
    group.add_argument(
        "--udp-onboard", metavar="[HOST:]PORT[:LOCAL]", help="onboard link, or 'off'"
    )
    group.add_argument("--udp-gcs", metavar="[HOST:]PORT[:LOCAL]", help="GCS link, or 'off'")
    group.add_argument("--realtime-factor", type=float, help="sim seconds per wall second")
    group.add_argument("--compressed", action="store_true", help="always publish JPEG too")
    group.add_argument("--aircraft", choices=("iris", "tello"), help="vehicle (default iris)")
    group.add_argument("--address", help="tello: address of UDP 8889 (default 127.0.0.1+N)")
    group.add_argument(
        "--netns", action="store_true", help="tello: own network namespace at 192.168.10.1 (root)"
    )
    group.add_argument("--signing-key", metavar="FILE", help="MAVLink 2 signing key at boot")
    group.add_argument(
        "--autopilot",
        choices=("px4-sih", "ardupilot"),
        help="no autopilot of ours: the vehicle pose comes from this external autopilot's truth",
    )
    group.add_argument(
        "--autopilot-link", metavar="udp|tcp:HOST:PORT", help="where the external truth arrives"
    )


def configure(args: argparse.Namespace, overrides: list[str]) -> None:
    """Turn the simulator flags into config overrides; set the namespace of an instance."""
    flags = {
        "scenario": args.scenario,
        "instance": args.instance,
        "seed": args.seed,
        "camera_rate_hz": args.camera_rate,
        "width": args.width,
        "height": args.height,
        "sprites": args.sprites,
        "udp_onboard": args.udp_onboard,
        "udp_gcs": args.udp_gcs,
        "realtime_factor": args.realtime_factor,
        "aircraft": args.aircraft,
        "address": args.address,
        "signing_key_file": args.signing_key,
        "autopilot": args.autopilot,
        "autopilot_link": args.autopilot_link,
    }
    for key, value in flags.items():
        if value is not None:
            overrides.append(f"{key}={json.dumps(value)}")  # JSON is valid YAML: no surprises
    if args.no_cameras:
        overrides.append("cameras=false")
    if args.compressed:
        overrides.append("compressed=true")
    if args.netns:
        overrides.append("netns=true")
    explicit_ns = args.namespace or os.environ.get(f"{ENV_PREFIX}NAMESPACE")
    if args.instance and not explicit_ns:
        args.namespace = f"{DEFAULT_NAMESPACE}{args.instance}"


PORTS = Ports(
    "sim",
    publishes=(
        registry.IMAGE_RAW,  # camera_stream.py
        registry.IMAGE_COMPRESSED,
        registry.SIM_GROUND_TRUTH,  # world_topics.py
        registry.SIM_OBJECT_POSE,
        registry.SIM_POSE_SOURCE,  # external/world_runner.py
    ),
    subscribes=(registry.SIM_OBJECT_CMD_VEL,),
    serves=(registry.SIM_WORLD, registry.SIM_WORLD_LOAD, registry.SIM_RESET),
)
"""What the simulator's process publishes, subscribes to and serves
(:mod:`dronewrapper.runtime.ports`)."""


def run(node: NodeApi, config: SimConfig) -> int:
    """Run the simulator on ``node`` until SIGINT/SIGTERM."""
    from dronewrapper_sim.runner import SimRunner
    from dronewrapper_sim.world.scenario import load_scenario

    try:
        scenario = load_scenario(config.scenario)
    except ConfigError as exc:
        log.error("%s", exc)
        return 2
    if config.aircraft == "tello":
        from dronewrapper_sim.tello.main import run_tello

        return run_tello(node, config, scenario)
    if config.autopilot:
        from dronewrapper_sim.external.main import run_external

        return run_external(node, config, scenario)
    runner = run_world(node, lambda: SimRunner(config, scenario, node), log)
    if runner is None:
        return 1
    log.info(
        "stopped after %.1f s simulated (%.1f s of wall time slipped after stalls)",
        runner.autopilot.time_s,
        runner.slipped_s,
    )
    return 0


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of ``dronewrapper sim`` and ``python -m dronewrapper_sim``."""
    return run_service(
        "sim", __doc__, SimConfig, run, argv, add_args=add_args, configure=configure, ports=PORTS
    )
