"""Start a user's own firmware build for the world to fly around: PX4 SITL (SIH) or ArduCopter
SITL, as a free instance number in a working directory of its own, stopped at the end.

Nothing here builds or fetches firmware: it runs a build that exists. An instance number shifts
the firmware's fixed ports out of the way of anything else on the machine (PX4 ``-i N``: onboard
link UDP 14540+N, SIH truth 19410+N; ArduCopter ``-I N``: SERIAL0/1/2 on TCP 5760/5762/5763 +
10 N). :attr:`Firmware.variables` are the graph variables that reach it
(compose/{px4,ardupilot}_sitl_*.yaml). ``DRONEWRAPPER_SITL_INSTANCE=N`` names the instance
instead (for a machine where instance numbers are shared out among users: PX4's lock
``/tmp/px4_lock-N`` is machine-wide, even across network namespaces).

``serial=(DEVICE, BAUD)`` also puts the autopilot's MAVLink on a serial device (a pseudo-terminal
of dronewrapper_sim.serial_relay, as on a flight controller's TELEM port): PX4 starts a MAVLink
instance there in onboard mode (``mavlink start -d DEVICE -b BAUD -m onboard``, a companion
computer's TELEM2 setup, its data rate left to PX4: baud / 20 B/s), ArduCopter runs its SERIAL0
there (``--serial0 uart:DEVICE:BAUD``, ``SERIAL0_BAUD`` to match). Each sizes its streams to the
baud.
"""

from __future__ import annotations

import contextlib
import fcntl
import os
import re
import signal
import socket
import subprocess
import time
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import IO

from dronewrapper.runtime.children import die_with_parent

PX4_UDP_PORTS = (14540, 14580, 18570, 19410, 19450)  # + N: every UDP port PX4 instance N uses
AP_TCP_BASE = 5760  # SERIAL0 of ArduCopter instance N: 5760 + 10 N; SERIAL1 + 2, SERIAL2 + 3
INSTANCE_ENV = "DRONEWRAPPER_SITL_INSTANCE"
PX4_LOCK = "/tmp/px4_lock-{}"  # PX4's server lock of instance N (POSIX record lock)
PX4_SOCKET = "/tmp/px4-sock-{}"  # PX4's client socket of instance N
PX4_MAVLINK_START_S = 60.0  # s for PX4 to boot far enough to start a MAVLink instance


@dataclass(frozen=True)
class Firmware:
    """A running firmware: ``px4`` or ``ardupilot``, its instance, the graph variables that
    reach it, its log file and its version."""

    autopilot: str
    instance: int
    variables: dict[str, str]
    log: Path
    version: str


def px4_build_dir(root: Path) -> Path:
    """``build/px4_sitl_default`` of a PX4-Autopilot tree (or ``root`` itself if it is one)."""
    for build in (root, root / "build" / "px4_sitl_default"):
        if (build / "bin" / "px4").is_file():
            return build
    raise FileNotFoundError(
        f"{root}: no PX4 SITL build (bin/px4) here or in build/px4_sitl_default"
    )


def arducopter_binary(root: Path) -> Path:
    """``build/sitl/bin/arducopter`` of an ArduPilot tree."""
    binary = root / "build" / "sitl" / "bin" / "arducopter"
    if not binary.is_file():
        raise FileNotFoundError(f"{binary}: no ArduCopter SITL build")
    return binary


def _free(kind: int, port: int) -> bool:
    with socket.socket(socket.AF_INET, kind) as sock:
        try:
            sock.bind(("127.0.0.1", port))
        except OSError:
            return False
    return True


def _px4_unlocked(n: int) -> bool:
    """No PX4 server of instance ``n`` holds its lock (on this machine, any namespace)."""
    try:
        fd = os.open(PX4_LOCK.format(n), os.O_RDWR)
    except FileNotFoundError:
        return True
    except OSError:
        return False
    try:
        fcntl.lockf(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        fcntl.lockf(fd, fcntl.LOCK_UN)
        return True
    except OSError:
        return False
    finally:
        os.close(fd)


def _named_instance() -> int | None:
    value = os.environ.get(INSTANCE_ENV, "").strip()
    if not value:
        return None
    if not value.isdigit():
        raise ValueError(f"{INSTANCE_ENV}={value!r}: not an instance number")
    return int(value)


def free_px4_instance() -> int:
    """``DRONEWRAPPER_SITL_INSTANCE``, or an instance 1..9 whose UDP ports are all free now and
    whose lock no PX4 holds (PX4 shifts its ports only up to 9)."""
    named = _named_instance()
    if named is not None:
        return named
    for n in range(1, 10):
        if _px4_unlocked(n) and all(_free(socket.SOCK_DGRAM, port + n) for port in PX4_UDP_PORTS):
            return n
    raise RuntimeError("no free PX4 SITL instance (1..9)")


def free_ardupilot_instance() -> int:
    """``DRONEWRAPPER_SITL_INSTANCE``, or an instance 1..59 whose SERIAL0..2 TCP ports are free
    now."""
    named = _named_instance()
    if named is not None:
        return named
    for n in range(1, 60):
        if all(_free(socket.SOCK_STREAM, AP_TCP_BASE + 10 * n + k) for k in range(4)):
            return n
    raise RuntimeError("no free ArduCopter SITL instance")


def px4_version(build: Path) -> str:
    """``PX4 <tag> (<commit>)`` from the build's generated version header."""
    header = build / "src" / "lib" / "version" / "build_git_version.h"
    text = header.read_text() if header.is_file() else ""
    commit = re.search(r'PX4_GIT_VERSION_STR\s+"([0-9a-f]+)"', text)
    tag = re.search(r'PX4_GIT_TAG_STR\s+"([^"]*)"', text)
    return f"PX4 {tag.group(1) if tag else '?'} ({commit.group(1)[:10] if commit else '?'})"


def ardupilot_version(root: Path) -> str:
    """``ArduCopter V…`` from the tree's ArduCopter/version.h."""
    header = root / "ArduCopter" / "version.h"
    text = header.read_text() if header.is_file() else ""
    found = re.search(r'#define THISFIRMWARE "([^"]+)"', text)
    return found.group(1) if found else "ArduCopter ?"


def _start_logged(
    argv: list[str], cwd: Path, log: IO[bytes], env: dict[str, str] | None = None
) -> subprocess.Popen:
    """``argv`` started in ``cwd`` (``env``: its whole environment; None: ours), reading
    nothing, writing all it says to ``log``; it dies with this process."""
    return subprocess.Popen(
        argv,
        cwd=cwd,
        env=env,
        stdin=subprocess.DEVNULL,
        stdout=log,
        stderr=subprocess.STDOUT,
        preexec_fn=die_with_parent,
    )


def _stop(proc: subprocess.Popen) -> None:
    proc.send_signal(signal.SIGTERM)
    try:
        proc.wait(10)
    except subprocess.TimeoutExpired:
        proc.kill()
        proc.wait(5)


def start_px4_mavlink(build: Path, instance: int, device: str, baud: int, log: Path) -> None:
    """A MAVLink instance of PX4 SITL ``instance`` on a serial ``device`` at ``baud``, in
    onboard mode; retried while PX4 boots (its client's answer can be lost then: its log says
    whether the instance started). RuntimeError after :data:`PX4_MAVLINK_START_S`."""
    start = [str(build / "bin" / "px4-mavlink"), "--instance", str(instance), "start",
             "-d", device, "-b", str(baud), "-m", "onboard"]  # fmt: skip
    deadline = time.monotonic() + PX4_MAVLINK_START_S
    while time.monotonic() < deadline:
        if f"on {device} @" in log.read_text(errors="replace"):
            return
        if subprocess.run(start, capture_output=True, timeout=10).returncode == 0:
            return
        time.sleep(1.0)
    raise RuntimeError(f"PX4 started no MAVLink instance on {device} in {PX4_MAVLINK_START_S} s")


@contextlib.contextmanager
def px4_sih(
    root: Path,
    workdir: Path,
    *,
    instance: int | None = None,
    env: dict[str, str] | None = None,
    serial: tuple[str, int] | None = None,
) -> Iterator[Firmware]:
    """PX4 SITL with its SIH quadrotor (``sihsim_quadx``) in ``workdir``: ``instance`` (None: a
    free one), ``env`` added to its environment (``PX4_PARAM_ZENOH_ENABLE=1``: its zenoh
    module on, in a px4_sitl_zenoh build), ``serial`` (device, baud): a MAVLink instance on that
    serial device too."""
    build = px4_build_dir(root)
    instance = free_px4_instance() if instance is None else instance
    extra = env or {}
    home = workdir / "px4"
    (home / "rootfs").mkdir(parents=True, exist_ok=True)
    for name in ("bin", "etc"):
        if not (home / name).exists():
            (home / name).symlink_to(build / name)
    env = {
        **os.environ,
        "PX4_SIM_MODEL": "sihsim_quadx",
        "PX4_SIMULATOR": "sihsim",
        "HEADLESS": "1",
        **extra,
    }
    log_path = workdir / "px4.log"
    with open(log_path, "wb") as log:
        proc = _start_logged(
            # its working directory named (-w), with the build's etc/ as its data: without
            # them PX4 works in the build's rootfs/N, and its missions and parameters outlive
            # the run (a new mission flown from the last one's current item)
            [
                "../bin/px4",
                "-i",
                str(instance),
                "-d",
                "-w",
                str(home / "rootfs"),
                str(build / "etc"),
            ],
            home / "rootfs",
            log,
            env,
        )
        try:
            if serial is not None:
                start_px4_mavlink(build, instance, *serial, log_path)
            variables = {"onboard_port": str(14540 + instance), "truth_port": str(19410 + instance)}
            yield Firmware("px4", instance, variables, log_path, px4_version(build))
        finally:
            _stop(proc)
            Path(PX4_SOCKET.format(instance)).unlink(missing_ok=True)  # PX4 leaves it behind


@contextlib.contextmanager
def arducopter(
    root: Path, workdir: Path, *, serial: tuple[str, int] | None = None
) -> Iterator[Firmware]:
    """ArduCopter SITL (quad model, the copter defaults, wiped parameters), a free instance, in
    ``workdir``. It waits for a client on SERIAL0 before it starts flying; with ``serial``
    (device, baud) its SERIAL0 is that serial device instead (MAVLink 2 at that baud)."""
    binary = arducopter_binary(root)
    defaults = str(root / "Tools" / "autotest" / "default_params" / "copter.parm")
    instance = free_ardupilot_instance()
    log_path = workdir / "arducopter.log"
    serial_args = []
    if serial is not None:
        device, baud = serial
        extra = workdir / "serial0.parm"
        extra.write_text(f"SERIAL0_BAUD {baud // 1000}\nSERIAL0_PROTOCOL 2\n")
        defaults += f",{extra}"
        serial_args = ["--serial0", f"uart:{device}:{baud}"]
    argv = [
        str(binary), "--model", "quad", "--speedup", "1", f"-I{instance}", "-w",
        "--defaults", defaults, *serial_args,
    ]  # fmt: skip
    with open(log_path, "wb") as log:
        proc = _start_logged(argv, workdir, log)
        try:
            port = AP_TCP_BASE + 10 * instance
            variables = {"sitl_port": str(port), "truth_port": str(port + 2)}
            yield Firmware("ardupilot", instance, variables, log_path, ardupilot_version(root))
        finally:
            _stop(proc)
