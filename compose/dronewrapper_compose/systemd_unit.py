"""The systemd unit that starts a graph when the companion computer boots (pure).

One unit per graph, ``dronewrapper-NAME.service``: ``dronewrapper up GRAPH`` as the user who
owns the keys, in the repository, started after the network is online and after the
autopilot's serial device exists (``Requires=`` + ``After=`` its ``.device`` unit: systemd
waits for udev to announce it). Not ``BindsTo=``: that would stop the whole graph, controller
and all, when the serial device blinks out in flight, while the bridge reopens the device by
itself. Restarted on failure (3 s apart, at most 5 times in 2 minutes); stopped with SIGINT,
the launcher's Ctrl-C (the controller lands, for up to 60 s); its output goes to the journal
(``journalctl -u dronewrapper-NAME``).
"""

from __future__ import annotations

import re
import shlex
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path

UNIT_PREFIX = "dronewrapper-"
STOP_TIMEOUT_S = 90  # the controller lands for up to 60 s, then every process stops
RESTART_S = 3
GROUPS = ("dialout", "video")  # the serial port and the camera
_CONNECTION = re.compile(r"^connection=(/dev/\S+)$")


def unit_name(graph: Path | str) -> str:
    """The unit of a graph file: ``dronewrapper-px4_real.service`` for ``compose/px4_real.yaml``."""
    stem = Path(graph).name.removesuffix(".yaml").removesuffix(".yml")
    return f"{UNIT_PREFIX}{escape_name(stem)}.service"


def escape_name(text: str) -> str:
    """``systemd-escape``: letters, digits, ``_`` and ``.`` (not first) kept, ``/`` to ``-``,
    anything else as ``\\xNN``."""
    out = []
    for i, char in enumerate(text):
        if char == "/":
            out.append("-")
        elif (char.isascii() and char.isalnum()) or char == "_" or (char == "." and i > 0):
            out.append(char)
        else:
            out.extend(f"\\x{byte:02x}" for byte in char.encode())
    return "".join(out)


def device_unit(path: str) -> str:
    """``systemd-escape --path --suffix=device``: ``/dev/ttyUSB0`` -> ``dev-ttyUSB0.device``."""
    trimmed = "/".join(part for part in path.split("/") if part)
    return f"{escape_name(trimmed)}.device"


def serial_devices(argvs: Iterable[Sequence[str]]) -> list[str]:
    """The ``/dev/...`` devices the graph's processes are given as their ``connection``."""
    found: list[str] = []
    for argv in argvs:
        for arg in argv:
            match = _CONNECTION.match(arg)
            if match and match.group(1) not in found:
                found.append(match.group(1))
    return found


@dataclass(frozen=True)
class UnitSpec:
    """What the unit runs, as whom and where.

    Attributes:
        graph: the graph file (absolute).
        user: the user the graph runs as (its home holds the keys).
        command: ``dronewrapper up GRAPH ...`` as an argv (absolute interpreter first).
        working_dir: the repository.
        devices: serial devices to wait for.
        environment: extra environment (``DRONEWRAPPER_ASSETS`` ...).
        groups: supplementary groups (serial port, camera).
    """

    graph: Path
    user: str
    command: Sequence[str]
    working_dir: Path
    devices: Sequence[str] = ()
    environment: Mapping[str, str] = field(default_factory=dict)
    groups: Sequence[str] = GROUPS


def _quote(arg: str) -> str:
    """One ExecStart argument (systemd's quoting is shell-like; ``%`` and ``$`` doubled)."""
    return shlex.quote(arg.replace("%", "%%").replace("$", "$$"))


def render_unit(spec: UnitSpec) -> str:
    """The unit file's text."""
    devices = [device_unit(d) for d in spec.devices]
    after = " ".join(["network-online.target", *devices])
    lines = [
        "[Unit]",
        f"Description=DroneWrapper graph {spec.graph.name}",
        f"Documentation=file://{spec.working_dir / 'docs' / 'jetson.md'}",
        "Wants=network-online.target",
        f"After={after}",
        *([f"Requires={' '.join(devices)}"] if devices else []),
        "StartLimitIntervalSec=120",
        "StartLimitBurst=5",
        "",
        "[Service]",
        "Type=simple",
        f"User={spec.user}",
        *([f"SupplementaryGroups={' '.join(spec.groups)}"] if spec.groups else []),
        f"WorkingDirectory={spec.working_dir}",
        "Environment=PYTHONUNBUFFERED=1",
        *(f"Environment={_quote(f'{k}={v}')}" for k, v in sorted(spec.environment.items())),
        f"ExecStart={' '.join(_quote(a) for a in spec.command)}",
        "Restart=on-failure",
        f"RestartSec={RESTART_S}",
        "KillSignal=SIGINT",
        f"TimeoutStopSec={STOP_TIMEOUT_S}",
        "StandardOutput=journal",
        "StandardError=journal",
        f"SyslogIdentifier={unit_name(spec.graph).removesuffix('.service')}",
        "",
        "[Install]",
        "WantedBy=multi-user.target",
        "",
    ]
    return "\n".join(lines)
