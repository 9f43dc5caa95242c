"""``dronewrapper up GRAPH``: the command line of the launcher (:mod:`.launcher`).

Exit status: 0 when every process started and stopped cleanly, 1 when a process died or
failed to become ready, 2 for a bad graph file or bad flags. ``--check`` validates the graph
and prints each process's command line without starting anything.
"""

from __future__ import annotations

import logging
import os
import signal
import sys
import threading
from collections.abc import Sequence

from dronewrapper.router import InsecureEndpoint
from dronewrapper.runtime.arguments import CommandParser
from dronewrapper.runtime.options import DEFAULT_ROUTER
from dronewrapper.runtime.service import setup_logging
from dronewrapper_compose import fleet
from dronewrapper_compose.graph import (
    GraphError,
    check_variables,
    load_graph,
    parse_vars,
    resolve_graph_path,
)
from dronewrapper_compose.launcher import Launcher, LaunchError


def simulated_drones(launcher: Launcher) -> int:
    """How many simulated aircraft the graph runs (its ``dronewrapper_sim`` processes)."""
    return sum(inst.spec.module == fleet.SIM_MODULE for group in launcher.groups for inst in group)


def usable_cores() -> int:
    """The cores this process may run on."""
    return len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count() or 1


def main(argv: Sequence[str] | None = None) -> int:
    """``dronewrapper up GRAPH [--router EP] [--scenario NAME] [--duration S] [--var K=V]``."""
    parser = CommandParser(prog="dronewrapper up", description="run a process graph")
    parser.add_argument("graph", help="compose/NAME.yaml, or a bare graph name")
    parser.add_argument("--router", default=DEFAULT_ROUTER, help="router endpoint to start")
    parser.add_argument(
        "--use-router", action="store_true", help="connect to a running router instead"
    )
    parser.add_argument("--scenario", help="sets the graph variable 'scenario'")
    parser.add_argument("--duration", type=float, default=0.0, help="stop after S seconds")
    parser.add_argument("--namespace", "--ns", help="vehicle namespace (default: the graph's)")
    parser.add_argument("--var", action="append", default=[], metavar="KEY=VALUE")
    parser.add_argument("--check", action="store_true", help="validate the graph and print argv")
    parser.add_argument(
        "--listen",
        action="append",
        default=[],
        metavar="ENDPOINT",
        help="also listen here for other machines, e.g. tls/0.0.0.0:7448 (needs --identity)",
    )
    parser.add_argument(
        "--connect",
        action="append",
        default=[],
        metavar="ENDPOINT",
        help="also join this router, e.g. a relay's tls/RELAY:7448 (needs --identity)",
    )
    parser.add_argument("--identity", default="", help="the drone's certificate (keys)")
    parser.add_argument("--keys", default="", metavar="DIR", help="key store folder")
    parser.add_argument(
        "--insecure", action="store_true", help="allow plain tcp/ off loopback (trusted networks)"
    )
    args = parser.parse_args(argv)
    try:
        variables = parse_vars(args.var)
        if args.scenario:
            variables["scenario"] = args.scenario
        path = resolve_graph_path(args.graph)
        check_variables(load_graph(path), path, variables)  # the command line's: names too
        launcher = Launcher.from_file(
            args.graph,
            router=args.router,
            start_router=not args.use_router,
            variables=variables,
            namespace=args.namespace,
            listen=args.listen,
            connect=args.connect,
            identity=args.identity,
            keys_dir=args.keys,
            insecure=args.insecure,
        )
        if warning := fleet.load_warning(simulated_drones(launcher), usable_cores()):
            print(f"dronewrapper up: warning: {warning}", file=sys.stderr)
        if args.check:
            for group in launcher.groups:
                for inst in group:
                    print(f"{inst.label}: {' '.join(launcher.argv_of(inst)[0])}")
            return 0
    except GraphError as exc:
        print(f"dronewrapper up: {exc}", file=sys.stderr)
        return 2

    setup_logging()  # the graph runs: log lines from here on (a bad graph only printed above)
    if args.identity and not args.use_router:  # what a rejected TLS handshake means
        from dronewrapper.zenoh_log import relay_zenoh_log

        relay_zenoh_log(logging.getLogger("router"))
        launcher.out = sys.stdout  # where fd 1 went before Zenoh's log took it
    stop = threading.Event()

    def on_signal(signum: int, _frame: object) -> None:
        if stop.is_set():
            return
        launcher._say(f"{signal.Signals(signum).name} received, stopping")
        stop.set()

    signal.signal(signal.SIGINT, on_signal)
    signal.signal(signal.SIGTERM, on_signal)
    try:
        launcher.start()
    except (LaunchError, GraphError, ConnectionError, InsecureEndpoint, FileNotFoundError) as exc:
        launcher.failures.append(str(exc))
        launcher._say(f"start failed: {exc}")
        launcher.stop()
        return 1
    launcher._say(
        "all processes ready"
        + (f"; running for {args.duration:g} s" if args.duration else "; Ctrl-C to stop")
    )
    return launcher.wait(duration=args.duration or None, stop=stop)


if __name__ == "__main__":
    raise SystemExit(main())
