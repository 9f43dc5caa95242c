"""Real autopilot firmware for the opt-in SITL tier: where the builds are and how to start one.

``PX4_SITL_DIR`` names a PX4-Autopilot tree (or its ``build/px4_sitl_default``) built for SITL;
``AP_SITL_DIR`` names an ArduPilot tree with ``build/sitl/bin/arducopter``. Each firmware runs as
a free instance number in a working directory of its own, so its fixed ports shift out of the
way of anything else on the machine (PX4 ``-i N``: onboard link 14540+N, SIH truth 19410+N;
ArduCopter ``-I N``: SERIAL0/1/2 on TCP 5760/5762/5763 + 10 N), and is stopped at the end.
Nothing here builds the firmware: CI has no way to fetch its sources.
"""

from __future__ import annotations

import contextlib
import os
import re
import signal
import socket
import subprocess
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

from ardupilot_sitl import arducopter_sitl

from dronewrapper_compose.launcher import die_with_parent

PX4_ENV = "PX4_SITL_DIR"
AP_ENV = "AP_SITL_DIR"
PX4_PORTS = (14540, 14580, 18570, 19410, 19450)  # + N: every UDP port instance N uses


@dataclass(frozen=True)
class Firmware:
    """A running firmware: which, its instance, the graph variables that reach it, its log."""

    autopilot: str  # px4 | ardupilot
    instance: int
    variables: dict[str, str]
    log: Path
    version: str


def px4_build() -> Path | None:
    """``build/px4_sitl_default`` of the tree ``PX4_SITL_DIR`` names (None: tier off)."""
    value = os.environ.get(PX4_ENV, "").strip()
    if not value:
        return None
    root = Path(value).expanduser()
    for build in (root, root / "build" / "px4_sitl_default"):
        if (build / "bin" / "px4").is_file():
            return build
    return root / "build" / "px4_sitl_default"  # missing: the start says so


def arducopter_binary() -> Path | None:
    """``build/sitl/bin/arducopter`` of the tree ``AP_SITL_DIR`` names (None: tier off)."""
    value = os.environ.get(AP_ENV, "").strip()
    return Path(value).expanduser() / "build" / "sitl" / "bin" / "arducopter" if value else None


def _udp_free(port: int) -> bool:
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as sock:
        try:
            sock.bind(("127.0.0.1", port))
        except OSError:
            return False
    return True


def free_px4_instance() -> int:
    """An instance 1..9 whose UDP ports are all free now (PX4 shifts them only up to 9)."""
    for instance in range(1, 10):
        if all(_udp_free(port + instance) for port in PX4_PORTS):
            return instance
    raise RuntimeError("no free PX4 SITL instance (1..9)")


def _px4_version(build: Path) -> str:
    header = build / "src" / "lib" / "version" / "build_git_version.h"
    text = header.read_text() if header.is_file() else ""
    found = re.search(r'PX4_GIT_VERSION_STR\s+"([0-9a-f]+)"', text)
    tag = re.search(r'PX4_GIT_TAG_STR\s+"([^"]*)"', text)
    return f"PX4 {tag.group(1) if tag else '?'} ({found.group(1)[:10] if found else '?'})"


@contextlib.contextmanager
def px4_sih(build: Path, workdir: Path) -> Iterator[Firmware]:
    """PX4 SITL with its SIH quadrotor (airframe sihsim_quadx), instance N, in ``workdir``."""
    binary = build / "bin" / "px4"
    if not binary.is_file():
        raise FileNotFoundError(f"{binary}: no PX4 SITL build ({PX4_ENV})")
    instance = free_px4_instance()
    home = workdir / "px4"
    (home / "rootfs").mkdir(parents=True, exist_ok=True)
    for name in ("bin", "etc"):
        link = home / name
        if not link.exists():
            link.symlink_to(build / name)
    log_path = workdir / "px4.log"
    env = {
        **os.environ,
        "PX4_SIM_MODEL": "sihsim_quadx",
        "PX4_SIMULATOR": "sihsim",
        "HEADLESS": "1",
    }
    with open(log_path, "wb") as log:
        proc = subprocess.Popen(
            ["../bin/px4", "-i", str(instance), "-d"],
            cwd=home / "rootfs",
            env=env,
            stdin=subprocess.DEVNULL,
            stdout=log,
            stderr=subprocess.STDOUT,
            preexec_fn=die_with_parent,
        )
        try:
            yield Firmware(
                "px4",
                instance,
                {
                    "onboard_port": str(14540 + instance),
                    "truth_port": str(19410 + instance),
                },
                log_path,
                _px4_version(build),
            )
        finally:
            _stop(proc)


@contextlib.contextmanager
def arducopter(binary: Path, workdir: Path) -> Iterator[Firmware]:
    """ArduCopter SITL (quad model, copter defaults, wiped parameters), a free instance."""
    with arducopter_sitl(binary, workdir) as (port, log_path):
        instance = (port - 5760) // 10
        version = _ardupilot_version(binary)
        yield Firmware(
            "ardupilot",
            instance,
            {"sitl_port": str(port), "truth_port": str(port + 2)},
            log_path,
            version,
        )


def _ardupilot_version(binary: Path) -> str:
    tree = binary.resolve().parents[3]
    header = tree / "ArduCopter" / "version.h"
    text = header.read_text() if header.is_file() else ""
    found = re.search(r'#define THISFIRMWARE "([^"]+)"', text)
    return found.group(1) if found else "ArduCopter ?"


def _stop(proc: subprocess.Popen) -> None:
    proc.send_signal(signal.SIGTERM)
    try:
        proc.wait(10)
    except subprocess.TimeoutExpired:
        proc.kill()
        proc.wait(5)
