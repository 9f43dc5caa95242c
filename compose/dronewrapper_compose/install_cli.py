"""``dronewrapper install GRAPH`` / ``dronewrapper uninstall GRAPH``: boot into a graph.

``install`` checks the graph with its variables (as ``dronewrapper up --check`` does), writes
``dronewrapper-NAME.service`` (see :mod:`~dronewrapper_compose.systemd_unit`) into
``/etc/systemd/system`` and enables it (``systemctl enable``), then starts it unless
``--no-start``. ``--root DIR`` writes and enables under ``DIR`` instead (an image being
prepared, or a test), and starts nothing; ``--print`` only prints the unit.

    sudo .venv/bin/dronewrapper install compose/px4_real_follow_person_secure.yaml \\
        --user jetson --var serial=/dev/ttyTHS1 --var baud=921600 \\
        --listen tls/0.0.0.0:7448 --identity drone1
    sudo .venv/bin/dronewrapper uninstall compose/px4_real_follow_person_secure.yaml
"""

from __future__ import annotations

import argparse
import getpass
import os
import pwd
import subprocess
import sys
from collections.abc import Sequence
from pathlib import Path

from dronewrapper.runtime.arguments import CommandParser
from dronewrapper_compose.graph import REPO, GraphError, check_variables, load_graph, parse_vars
from dronewrapper_compose.graph import resolve_graph_path as resolve
from dronewrapper_compose.launcher import Launcher
from dronewrapper_compose.systemd_unit import UnitSpec, render_unit, serial_devices, unit_name

UNIT_DIR = Path("etc/systemd/system")


def _unit_path(args: argparse.Namespace, graph: Path) -> Path:
    if args.unit_dir:
        return Path(args.unit_dir) / unit_name(graph)
    return Path(args.root or "/") / UNIT_DIR / unit_name(graph)


def _systemctl(args: argparse.Namespace, *command: str) -> int:
    argv = ["systemctl", *([f"--root={args.root}"] if args.root else []), *command]
    print("$", " ".join(argv))
    return subprocess.call(argv)


def build_spec(args: argparse.Namespace) -> UnitSpec:
    """The unit for the command line's graph and options (GraphError when they are wrong)."""
    variables = parse_vars(args.var)
    graph = resolve(args.graph).resolve()
    check_variables(load_graph(graph), graph, variables)
    if any(ep.startswith("tls/") for ep in args.listen) and not args.identity:
        raise GraphError("--listen tls/... needs --identity (the router's certificate)")
    launcher = Launcher.from_file(
        graph, variables=variables, listen=args.listen, identity=args.identity, keys_dir=args.keys
    )
    argvs = [launcher.argv_of(inst)[0] for group in launcher.groups for inst in group]
    command = [sys.executable, "-m", "dronewrapper", "up", str(graph)]
    command += [f"--var={pair}" for pair in args.var]
    command += [f"--listen={ep}" for ep in args.listen]
    command += [f"--identity={args.identity}"] if args.identity else []
    command += [f"--keys={args.keys}"] if args.keys else []
    command += ["--insecure"] if args.insecure else []
    environment = {}
    if assets := os.environ.get("DRONEWRAPPER_ASSETS"):
        environment["DRONEWRAPPER_ASSETS"] = assets
    return UnitSpec(
        graph=graph,
        user=args.user,
        command=command,
        working_dir=REPO,
        devices=serial_devices(argvs),
        environment=environment,
    )


def _parser(prog: str, what: str) -> CommandParser:
    parser = CommandParser(prog=prog, description=what)
    parser.add_argument("graph", help="compose/NAME.yaml, or a bare graph name")
    parser.add_argument("--root", metavar="DIR", help="install under DIR (no start)")
    parser.add_argument("--unit-dir", metavar="DIR", help="write the unit here (no enable)")
    return parser


def install_main(argv: Sequence[str] | None = None) -> int:
    parser = _parser("dronewrapper install", "start a graph when this computer boots (systemd)")
    default_user = os.environ.get("SUDO_USER") or getpass.getuser()
    parser.add_argument("--user", default=default_user, help=f"run as (default {default_user})")
    parser.add_argument("--var", action="append", default=[], metavar="KEY=VALUE")
    parser.add_argument("--listen", action="append", default=[], metavar="ENDPOINT")
    parser.add_argument("--identity", default="", help="the router's certificate (keys)")
    parser.add_argument("--keys", default="", metavar="DIR", help="key store folder")
    parser.add_argument("--insecure", action="store_true", help="allow plain tcp/ off loopback")
    parser.add_argument("--print", action="store_true", help="print the unit, change nothing")
    parser.add_argument("--no-start", action="store_true", help="enable, but do not start now")
    args = parser.parse_args(argv)
    try:
        pwd.getpwnam(args.user)
    except KeyError:
        parser.error(f"--user {args.user!r}: no such user on this computer")
    try:
        spec = build_spec(args)
    except GraphError as exc:
        print(f"dronewrapper install: {exc}", file=sys.stderr)
        return 2
    text = render_unit(spec)
    if args.print:
        print(text, end="")
        return 0
    path = _unit_path(args, spec.graph)
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(text)
    except OSError as exc:
        print(f"dronewrapper install: cannot write {path}: {exc.strerror} (sudo?)", file=sys.stderr)
        return 1
    print(f"wrote {path}")
    if args.unit_dir:
        return 0
    name = unit_name(spec.graph)
    if not args.root and _systemctl(args, "daemon-reload") != 0:
        return 1
    if _systemctl(args, "enable", name) != 0:
        return 1
    if not args.root and not args.no_start and _systemctl(args, "start", name) != 0:
        return 1
    print(f"logs: journalctl -u {name} -f")
    return 0


def uninstall_main(argv: Sequence[str] | None = None) -> int:
    parser = _parser("dronewrapper uninstall", "stop starting a graph at boot (systemd)")
    args = parser.parse_args(argv)
    graph = Path(args.graph)
    name = unit_name(graph)
    path = _unit_path(args, graph)
    if not path.exists():
        print(f"dronewrapper uninstall: {path} is not there", file=sys.stderr)
        return 1
    if not args.unit_dir:
        stop = ["disable", name] if args.root else ["disable", "--now", name]
        if _systemctl(args, *stop) != 0:
            return 1
    path.unlink()
    print(f"removed {path}")
    if not args.root and not args.unit_dir:
        return _systemctl(args, "daemon-reload")
    return 0
