"""The common entry point of every service process.

A service's ``__main__`` is a ``main(argv)`` and a guard, so that a host process
(:mod:`dronewrapper.runtime.host`) can run it beside other services as well::

    from dronewrapper.runtime.service import run_service
    from dronewrapper_perception.config import Config
    from dronewrapper_perception.node import run

    def main(argv=None):
        return run_service("perception", __doc__, Config, run, argv)

    if __name__ == "__main__":
        raise SystemExit(main())

``run_service`` parses the common flags (Zenoh flags, ``--config FILE``, ``--set KEY=VALUE``,
``--log-level``), loads the config strictly, opens the Node (SIGINT/SIGTERM -> stop), calls
``run(node, config)`` and closes the session whatever happens. Hosted with other services in
one process (:mod:`dronewrapper.runtime.host`), the Node joins the process's shared session
and closes only what it declared. Exit status: 0 after a clean
stop, 2 for a bad config or bad flags, 1 when ``run`` raised.
"""

from __future__ import annotations

import argparse
import logging
import sys
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import TypeVar

from dronewrapper.runtime import host
from dronewrapper.runtime.arguments import CommandParser, first_line
from dronewrapper.runtime.config import ConfigError, load_config
from dronewrapper.runtime.config_help import config_help
from dronewrapper.runtime.node import Node
from dronewrapper.runtime.options import add_zenoh_args, options_from_args
from dronewrapper.runtime.ports import Ports

C = TypeVar("C")

LOG_FORMAT = "%(asctime)s.%(msecs)03d %(levelname)-7s %(name)s: %(message)s"


def setup_logging(level: str = "INFO") -> None:
    """Log to stderr with timestamps (the launcher prefixes each line with the process name)."""
    logging.basicConfig(level=level.upper(), format=LOG_FORMAT, datefmt="%H:%M:%S", force=True)


def command_line_name(name: str) -> str:
    """How the user started service ``name``, for ``usage:`` lines: ``python -m PACKAGE`` or
    ``dronewrapper NAME`` (else just ``name``)."""
    spec = getattr(sys.modules.get("__main__"), "__spec__", None)
    package = spec.parent if spec is not None and spec.name.endswith("__main__") else ""
    if package == "dronewrapper" or (not package and Path(sys.argv[0]).name == "dronewrapper"):
        return f"dronewrapper {name}"  # the dronewrapper command, or python -m dronewrapper
    return f"python -m {package}" if package else name


def service_parser(
    name: str,
    description: str | None,
    *,
    default_mode: str = "peer",
    config_type: type | None = None,
):
    """An ArgumentParser with the flags every service takes; its help ends with the keys of
    ``config_type`` (:func:`~dronewrapper.runtime.config_help.config_help`)."""
    parser = CommandParser(
        prog=command_line_name(name),
        description=first_line(description),
        epilog=config_help(config_type) if config_type is not None else None,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument("--config", metavar="FILE", help="YAML or JSON config file")
    parser.add_argument(
        "--set",
        action="append",
        default=[],
        metavar="KEY=VALUE",
        help="override one config key (dotted path), repeatable",
    )
    parser.add_argument("--log-level", default="INFO", help="DEBUG, INFO, WARNING, ERROR")
    add_zenoh_args(parser, default_mode=default_mode)
    return parser


def run_service(
    name: str,
    description: str | None,
    config_type: type[C],
    run: Callable[[Node, C], int | None],
    argv: Sequence[str] | None = None,
    *,
    add_args: Callable[[argparse.ArgumentParser], None] | None = None,
    configure: Callable[[argparse.Namespace, list[str]], None] | None = None,
    ports: Ports | None = None,
) -> int:
    """Parse flags, load the config, run the service on a Node and exit cleanly.

    ``add_args`` may add service-specific flags; ``configure(args, overrides)`` may turn them
    into config overrides (appended to ``--set``) before the config is loaded. ``ports``: what
    the service declares it publishes, subscribes to, serves and calls; its node refuses the rest.
    """
    parser = service_parser(name, description, config_type=config_type)
    if add_args:
        add_args(parser)
    args = parser.parse_args(argv)
    setup_logging(args.log_level)
    log = logging.getLogger(name)
    overrides = list(args.set)
    if configure:
        configure(args, overrides)
    try:
        config = load_config(config_type, args.config, overrides)
    except ConfigError as exc:
        print(f"{name}: {exc}", file=sys.stderr)
        return 2
    try:
        options = options_from_args(args, name=name)
    except ValueError as exc:
        print(f"{name}: {exc}", file=sys.stderr)
        return 2
    member = host.current()  # hosted with other services in one process (runtime/host.py)
    try:
        if member is None:
            node = Node(name, options, ports=ports)
        else:
            session = member.host.session_for(options)
            node = Node(name, options, session=session, handle_signals=False, ports=ports)
            member.attach(node)
        with node:
            code = run(node, config)
    except ConnectionError as exc:
        log.error("%s", exc)
        return 1
    except KeyboardInterrupt:
        return 0
    except SystemExit as exc:
        return int(exc.code or 0)
    except Exception:
        log.exception("%s failed", name)
        return 1
    return int(code or 0)
