"""The ``dronewrapper`` command.

    dronewrapper router [--listen ENDPOINT]          a Zenoh router (default tcp/127.0.0.1:7447)
    dronewrapper keys init|issue|list|revoke|...     the project CA, certificates, MAVLink key
    dronewrapper echo KEYEXPR [--count N]            print decoded messages
    dronewrapper alive [--connect ENDPOINT]          drones and processes online, with health
    dronewrapper doctor [--connect ENDPOINT]         diagnose a setup and say what to fix
    dronewrapper doctor --hardware [--serial DEV]    this computer's serial port, camera, clock
    dronewrapper up compose/GRAPH.yaml [...]         run a process graph (needs the stack)
    dronewrapper install GRAPH [--user USER] [...]   start the graph at boot (systemd unit)
    dronewrapper uninstall GRAPH                     remove that unit
    dronewrapper sim [--scenario NAME] [...]         the simulated aircraft and world
    dronewrapper detect FILE [--detector NAME] [...] run perception offline on a file
    dronewrapper station [--host H] [--port P]       the web ground station (loopback)
    dronewrapper ros2 [--set domain_id=N] [...]      the drone as ROS 2 topics/services (rmw_zenoh)
    dronewrapper record [KEYEXPR...] -o FILE.mcap    the bus to MCAP (--info FILE summarises)
    dronewrapper replay FILE.mcap [--rate R] [...]   a recording back on the bus
    dronewrapper foxglove [KEYEXPR...] [--port P]    the live bus to Foxglove (WebSocket)
    dronewrapper mavlink-forward [--udp HOST:PORT]   a drone's MAVLink for QGroundControl (UDP)
    dronewrapper bench --quick [--target-ms MS]      this computer's speed, settings to use (stack)
    dronewrapper --version                           the installed version

``up``, ``install``, ``uninstall``, ``sim``, ``detect``, ``station``, ``ros2`` and ``bench`` come
with the on-board stack (``make setup``), whose distributions add them through the
``dronewrapper.commands`` entry points; the SDK alone (``pip install ./sdk``) has ``router``,
``echo``, ``alive`` and ``doctor``; ``record``, ``replay`` and ``foxglove`` come with its
``record`` extra (``pip install './tools[record]'``).
"""

from __future__ import annotations

import importlib
import logging
import os
import sys
from collections.abc import Sequence

from dronewrapper.command_line import client_session, stop_on_signals
from dronewrapper.runtime.arguments import CommandParser, plain_text
from dronewrapper.runtime.options import DEFAULT_ROUTER, add_zenoh_args, options_from_args
from dronewrapper.runtime.service import setup_logging

COMMANDS_GROUP = "dronewrapper.commands"
"""The entry-point group through which the on-board distributions add their subcommands
(``up = "dronewrapper_compose.up:main"``): this command names none of them."""

STACK_COMMANDS = ("up", "install", "uninstall", "sim", "detect", "station", "ros2", "bench")
"""The subcommands the on-board stack adds (for the message when it is not installed)."""

# subcommand -> (module, function) of the SDK's record extra (mcap, foxglove-sdk)
_RECORD_COMMANDS = {
    "record": ("dronewrapper.record.cli", "record_main"),
    "replay": ("dronewrapper.record.cli", "replay_main"),
    "foxglove": ("dronewrapper.record.cli", "foxglove_main"),
}


def _router(argv: Sequence[str]) -> int:
    from dronewrapper.router import router_options, run_router

    parser = CommandParser(prog="dronewrapper router", description="a Zenoh router")
    parser.add_argument(
        "--listen", action="append", metavar="ENDPOINT", help=f"default {DEFAULT_ROUTER}"
    )
    parser.add_argument(
        "--connect", action="append", default=[], metavar="ENDPOINT", help="another router"
    )
    parser.add_argument(
        "--identity", default="", metavar="NAME", help="the drone's certificate (tls/ listeners)"
    )
    parser.add_argument("--keys", default="", metavar="DIR", help="key store folder")
    parser.add_argument(
        "--insecure", action="store_true", help="allow plain tcp/ off loopback (trusted networks)"
    )
    parser.add_argument(
        "--namespace", action="append", default=None, help="vehicles the access control covers"
    )
    args = parser.parse_args(argv)
    setup_logging()
    try:
        options = router_options(
            args.listen,
            args.connect,
            identity=args.identity,
            keys_dir=args.keys,
            insecure=args.insecure,
            acl_namespaces=args.namespace,
        )
        if options.identity:  # say what a rejected TLS handshake means, not Zenoh's hint
            from dronewrapper.zenoh_log import relay_zenoh_log

            relay_zenoh_log(logging.getLogger("router"))
        run_router(options, stop_on_signals())
    except (ValueError, ConnectionError, FileNotFoundError) as exc:
        print(f"dronewrapper router: {exc}", file=sys.stderr)
        return 1
    return 0


def _version() -> str:
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version("dronewrapper")
    except PackageNotFoundError:  # running from a source tree that was not installed
        return "unknown (not installed)"


def _quiet_broken_pipe() -> None:
    """After the reader of stdout went away (``| head``), let the interpreter exit quietly."""
    devnull = os.open(os.devnull, os.O_WRONLY)
    os.dup2(devnull, sys.stdout.fileno())


def _echo(argv: Sequence[str]) -> int:
    import zenoh

    from dronewrapper.echo import echo, keyexpr_problem, path_warning
    from dronewrapper.runtime.errors import zenoh_error_text

    parser = CommandParser(prog="dronewrapper echo", description="print messages")
    parser.add_argument("keyexpr", help="key expression, e.g. drone/mavros/state or drone/**")
    parser.add_argument("--count", "-n", type=int, default=0, help="stop after N messages")
    parser.add_argument("--duration", type=float, default=0.0, help="stop after S seconds")
    add_zenoh_args(parser, default_mode="client")
    args = parser.parse_args(argv)
    problem = keyexpr_problem(args.keyexpr)
    if problem is None:
        try:
            zenoh.KeyExpr(args.keyexpr)
        except zenoh.ZError as exc:
            problem = f"{args.keyexpr!r} is not a key expression: {zenoh_error_text(exc)}"
    if problem:
        print(f"dronewrapper echo: {problem}", file=sys.stderr)
        return 2
    if warning := path_warning(args.keyexpr):
        print(f"dronewrapper echo: warning: {warning}", file=sys.stderr)
    stop = stop_on_signals()
    session = client_session(args, "dronewrapper echo")
    if session is None:
        return 1
    try:
        echo(session, args.keyexpr, count=args.count, duration=args.duration, stop=stop)
    finally:
        session.close()
    if sys.stdout.closed or not _stdout_writable():
        _quiet_broken_pipe()
    return 0


def _stdout_writable() -> bool:
    try:
        sys.stdout.flush()
    except (BrokenPipeError, ValueError):
        return False
    return True


def _alive(argv: Sequence[str]) -> int:
    from dronewrapper.discovery import services_by_namespace
    from dronewrapper.doctor import describe_drone, listen, topic_families

    parser = CommandParser(
        prog="dronewrapper alive", description="drones and processes online, with health"
    )
    parser.add_argument(
        "--seconds", type=float, default=1.5, metavar="S", help="seconds to hear states (1.5)"
    )
    add_zenoh_args(parser, default_mode="client")
    args = parser.parse_args(argv)
    session = client_session(args, "dronewrapper alive")
    if session is None:
        return 1
    try:
        keys = sorted(str(r.ok.key_expr) for r in session.liveliness().get("*/alive/*") if r.ok)
        heard = listen(session, topic_families(images=False), args.seconds) if keys else None
    finally:
        session.close()
    for ns, processes in services_by_namespace(set(keys)).items():
        verdict, sentence = describe_drone(ns, processes, heard.latest if heard else {})
        print(f"{'' if verdict == 'ok' else verdict.upper() + ' '}{sentence}")
        for name in processes:
            print(f"  {ns}/alive/{name}")
    if not keys:
        print("nothing alive on this router", file=sys.stderr)
    return 0


def _doctor(argv: Sequence[str]) -> int:
    from dronewrapper.doctor import run_doctor

    parser = CommandParser(
        prog="dronewrapper doctor", description="diagnose a setup and say what to fix"
    )
    parser.add_argument(
        "--seconds", type=float, default=3.0, metavar="S", help="seconds to listen (3)"
    )
    parser.add_argument("--images", action="store_true", help="also measure camera streams")
    parser.add_argument("--no-bandwidth", action="store_true", help="skip the bandwidth probe")
    hardware = parser.add_argument_group("this computer's hardware (--hardware)")
    hardware.add_argument(
        "--hardware", action="store_true", help="check the serial port, camera, clock, disk, boot"
    )
    hardware.add_argument("--serial", metavar="DEV", help="the autopilot's serial device")
    hardware.add_argument("--baud", type=int, default=57600, help="its baud rate (57600)")
    hardware.add_argument(
        "--recordings", default=".", metavar="DIR", help="where recordings go (.)"
    )
    add_zenoh_args(parser, default_mode="client")
    args = parser.parse_args(argv)
    labels = {"ok": "ok  ", "warn": "warn", "fail": "FAIL"}

    def report(verdict: str, text: str) -> None:
        print(f"{labels[verdict]} {text}", flush=True)

    if args.hardware:
        from dronewrapper.hardware_probe import run_hardware

        return run_hardware(
            report,
            serial=args.serial,
            baud=args.baud,
            listen_s=max(args.seconds, 2.0),  # a heartbeat is 1 Hz: two of them at least
            recordings=args.recordings,
        )

    return run_doctor(
        options_from_args(args),
        report,
        listen_s=args.seconds,
        images=args.images,
        bandwidth=not args.no_bandwidth,
    )


def _mavlink_forward(argv: Sequence[str]) -> int:
    from dronewrapper.mavlink_forward import PORTS, forward, parse_udp
    from dronewrapper.runtime.node import Node

    parser = CommandParser(
        prog="dronewrapper mavlink-forward",
        description="a drone's MAVLink (bridge gcs_over_zenoh) as UDP for QGroundControl",
    )
    parser.add_argument(
        "--udp", default="127.0.0.1:14550", metavar="HOST:PORT", help="QGC's port (default)"
    )
    add_zenoh_args(parser, default_mode="client")
    args = parser.parse_args(argv)
    try:
        qgc = parse_udp(args.udp)
    except ValueError as exc:
        parser.error(str(exc))
    setup_logging()
    options = options_from_args(args, name="mavlink_forward")
    try:
        with Node("mavlink_forward", options, ports=PORTS) as node:
            forward(node, qgc, node.stop_event)
    except ConnectionError as exc:
        print(f"dronewrapper mavlink-forward: {exc}", file=sys.stderr)
        return 1
    return 0


def _keys(argv: Sequence[str]) -> int:
    try:
        from dronewrapper.keys_cli import main as keys_main
    except ModuleNotFoundError as exc:  # the SDK without the security extra
        print(
            f"dronewrapper keys: needs {exc.name} (pip install './tools[security]')",
            file=sys.stderr,
        )
        return 2
    return keys_main(argv)


def _missing(command: str, need: str, exc: ModuleNotFoundError | None) -> int:
    """Say what ``command`` needs that is not installed; exit status 2."""
    missing = f" ({exc.name} is missing)" if exc is not None else ""
    print(
        f"dronewrapper {command}: needs {need}{missing}; run `make setup` in the repository",
        file=sys.stderr,
    )
    return 2


def main(argv: Sequence[str] | None = None) -> int:
    """Dispatch ``dronewrapper SUBCOMMAND ...``."""
    argv = list(sys.argv[1:] if argv is None else argv)
    if not argv or argv[0] in ("-h", "--help"):
        print(plain_text(__doc__.strip()))
        return 0 if argv else 2
    if argv[0] in ("-V", "--version"):
        print(f"dronewrapper {_version()}")
        return 0
    command, rest = argv[0], argv[1:]
    local = {
        "router": _router,
        "echo": _echo,
        "alive": _alive,
        "doctor": _doctor,
        "keys": _keys,
        "mavlink-forward": _mavlink_forward,
    }
    if command in local:
        return local[command](rest)
    if command in _RECORD_COMMANDS:
        module_name, func = _RECORD_COMMANDS[command]
        try:
            entry = getattr(importlib.import_module(module_name), func)
            import foxglove  # noqa: F401  (the record extra, checked before running)
            import mcap  # noqa: F401
        except ModuleNotFoundError as exc:
            return _missing(
                command, "the record extra: pip install 'dronewrapper-tools[record]'", exc
            )
        return int(entry(rest) or 0)
    from importlib.metadata import entry_points  # here: the SDK's own commands start faster

    found = [ep for ep in entry_points(group=COMMANDS_GROUP) if ep.name == command]
    if found:
        try:
            entry = found[0].load()
        except ModuleNotFoundError as exc:
            return _missing(command, "the on-board stack", exc)
        return int(entry(rest) or 0)
    if command in STACK_COMMANDS:
        return _missing(command, "the on-board stack", None)
    usage = plain_text(__doc__.strip())
    print(f"dronewrapper: unknown command {command!r}\n\n{usage}", file=sys.stderr)
    return 2


if __name__ == "__main__":
    raise SystemExit(main())
