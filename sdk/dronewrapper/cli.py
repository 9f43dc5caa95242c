"""The ``dronewrapper`` command.

    dronewrapper router [--listen ENDPOINT]          a Zenoh router (default tcp/127.0.0.1:7447)
    dronewrapper echo KEYEXPR [--count N]            print decoded messages
    dronewrapper alive [--connect ENDPOINT]          list running processes, by namespace
    dronewrapper up compose/GRAPH.yaml [...]         run a process graph (needs the stack)
    dronewrapper sim [--scenario NAME] [...]         the simulated aircraft and world
    dronewrapper detect FILE [--detector NAME] [...] run perception offline on a file
    dronewrapper record [KEYEXPR...] -o FILE.mcap    the bus to MCAP (--info FILE summarises)
    dronewrapper replay FILE.mcap [--rate R] [...]   a recording back on the bus
    dronewrapper foxglove [KEYEXPR...] [--port P]    the live bus to Foxglove (WebSocket)

``up``, ``sim`` and ``detect`` come with the on-board stack (``make setup``); the SDK alone
(``pip install ./sdk``) has ``router``, ``echo`` and ``alive``; ``record``, ``replay`` and
``foxglove`` come with its ``record`` extra (``pip install './sdk[record]'``).
"""

from __future__ import annotations

import argparse
import importlib
import signal
import sys
import threading
from collections.abc import Sequence

from dronewrapper.runtime.options import DEFAULT_ROUTER, add_zenoh_args, options_from_args
from dronewrapper.runtime.service import setup_logging

# subcommand -> (module, function) in the on-board stack, imported only when used
_STACK_COMMANDS = {
    "up": ("dronewrapper_compose.launcher", "main"),
    "sim": ("dronewrapper_sim.cli", "main"),
    "detect": ("dronewrapper_perception.detect_cli", "main"),
}

# subcommand -> (module, function) of the SDK's record extra (mcap, foxglove-sdk)
_RECORD_COMMANDS = {
    "record": ("dronewrapper.record.cli", "record_main"),
    "replay": ("dronewrapper.record.cli", "replay_main"),
    "foxglove": ("dronewrapper.record.cli", "foxglove_main"),
}


def _stop_on_signals() -> threading.Event:
    stop = threading.Event()
    for sig in (signal.SIGINT, signal.SIGTERM):
        signal.signal(sig, lambda *_: stop.set())
    return stop


def _router(argv: Sequence[str]) -> int:
    from dronewrapper.router import router_options, run_router

    parser = argparse.ArgumentParser(prog="dronewrapper router", description="a Zenoh router")
    parser.add_argument(
        "--listen", action="append", metavar="ENDPOINT", help=f"default {DEFAULT_ROUTER}"
    )
    parser.add_argument(
        "--connect", action="append", default=[], metavar="ENDPOINT", help="another router"
    )
    args = parser.parse_args(argv)
    setup_logging()
    try:
        options = router_options(args.listen, args.connect)
        run_router(options, _stop_on_signals())
    except (ValueError, ConnectionError) as exc:
        print(f"dronewrapper router: {exc}", file=sys.stderr)
        return 1
    return 0


def _echo(argv: Sequence[str]) -> int:
    from dronewrapper.echo import echo
    from dronewrapper.runtime.node import open_session

    parser = argparse.ArgumentParser(prog="dronewrapper echo", description="print messages")
    parser.add_argument("keyexpr", help="key expression, e.g. drone/mavros/state or drone/**")
    parser.add_argument("--count", "-n", type=int, default=0, help="stop after N messages")
    parser.add_argument("--duration", type=float, default=0.0, help="stop after S seconds")
    add_zenoh_args(parser, default_mode="client")
    args = parser.parse_args(argv)
    stop = _stop_on_signals()
    try:
        session = open_session(options_from_args(args))
    except ConnectionError as exc:
        print(f"dronewrapper echo: {exc}", file=sys.stderr)
        return 1
    try:
        echo(session, args.keyexpr, count=args.count, duration=args.duration, stop=stop)
    finally:
        session.close()
    return 0


def _alive(argv: Sequence[str]) -> int:
    from dronewrapper.runtime.node import open_session

    parser = argparse.ArgumentParser(prog="dronewrapper alive", description="running processes")
    add_zenoh_args(parser, default_mode="client")
    args = parser.parse_args(argv)
    try:
        session = open_session(options_from_args(args))
    except ConnectionError as exc:
        print(f"dronewrapper alive: {exc}", file=sys.stderr)
        return 1
    try:
        keys = sorted(str(r.ok.key_expr) for r in session.liveliness().get("*/alive/*") if r.ok)
    finally:
        session.close()
    for key in keys:
        print(key)
    return 0


def main(argv: Sequence[str] | None = None) -> int:
    """Dispatch ``dronewrapper SUBCOMMAND ...``."""
    argv = list(sys.argv[1:] if argv is None else argv)
    if not argv or argv[0] in ("-h", "--help"):
        print(__doc__.strip())
        return 0 if argv else 2
    command, rest = argv[0], argv[1:]
    local = {"router": _router, "echo": _echo, "alive": _alive}
    if command in local:
        return local[command](rest)
    if command in _STACK_COMMANDS or command in _RECORD_COMMANDS:
        module_name, func = {**_STACK_COMMANDS, **_RECORD_COMMANDS}[command]
        try:
            module = importlib.import_module(module_name)
            entry = getattr(module, func)
            if command in _RECORD_COMMANDS:
                import foxglove  # noqa: F401  (the record extra, checked before running)
                import mcap  # noqa: F401
        except ModuleNotFoundError as exc:
            need = (
                "the record extra: pip install 'dronewrapper[record]'"
                if command in _RECORD_COMMANDS
                else "the on-board stack"
            )
            print(
                f"dronewrapper {command}: needs {need} ({exc.name} is missing); "
                "run `make setup` in the repository",
                file=sys.stderr,
            )
            return 2
        return int(entry(rest) or 0)
    print(f"dronewrapper: unknown command {command!r}\n\n{__doc__.strip()}", file=sys.stderr)
    return 2


if __name__ == "__main__":
    raise SystemExit(main())
