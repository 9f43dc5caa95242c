"""``dronewrapper doctor --hardware``: what this computer has, gathered (the I/O side).

Each ``*_facts`` function looks at the machine and returns the facts
:mod:`dronewrapper.hardware` judges: the serial device (opened raw at the baud with termios and
listened to), the video devices (their formats from ``v4l2-ctl`` when it is installed), the
clock (``timedatectl``), free disk, and the ``dronewrapper-*`` systemd units
(``systemctl is-active``). ``dev`` and ``unit_dir`` are where devices and units are looked for.
"""

from __future__ import annotations

import contextlib
import getpass
import grp
import os
import re
import select
import shutil
import subprocess
import termios
import time
from collections.abc import Callable
from pathlib import Path

from dronewrapper import hardware
from dronewrapper.health import FAIL

SERIAL_PATTERNS = ("ttyUSB*", "ttyACM*", "ttyTHS*", "serial/by-id/*")
UNIT_DIR = Path("/etc/systemd/system")
_FORMAT = re.compile(r"\[\d+\]: '(\w+)'")


def serial_candidates(dev: Path = Path("/dev")) -> list[str]:
    """The serial devices under ``dev`` an autopilot is usually on."""
    return sorted(str(p) for pattern in SERIAL_PATTERNS for p in dev.glob(pattern))


def listen_serial(path: str, baud: int, seconds: float) -> hardware.HeardLine:
    """Open ``path`` raw at ``baud`` (8N1) and scan what arrives in ``seconds`` (OSError: it
    cannot be opened)."""
    speed = getattr(termios, f"B{baud}", None)
    if speed is None:
        raise ValueError(f"baud {baud} is not a standard rate")
    fd = os.open(path, os.O_RDONLY | os.O_NOCTTY | os.O_NONBLOCK)
    data = bytearray()
    try:
        attrs = termios.tcgetattr(fd)
        attrs[0] = 0  # iflag: no translation
        attrs[1] = 0  # oflag
        attrs[2] = termios.CS8 | termios.CREAD | termios.CLOCAL
        attrs[3] = 0  # lflag: raw, no echo
        attrs[4] = attrs[5] = speed
        termios.tcsetattr(fd, termios.TCSANOW, attrs)
        termios.tcflush(fd, termios.TCIFLUSH)
        start = time.monotonic()
        deadline = start + seconds
        while (left := deadline - time.monotonic()) > 0:
            readable, _, _ = select.select([fd], [], [], left)
            if readable:
                with contextlib.suppress(BlockingIOError):
                    data += os.read(fd, 4096)
    finally:
        os.close(fd)
    return hardware.scan_heartbeats(bytes(data), seconds)


def serial_facts(
    path: str, baud: int, seconds: float, dev: Path = Path("/dev"), listen: bool = True
) -> hardware.SerialFacts:
    """The device ``path``, whether this user may open it, and what arrives at ``baud``."""
    user = getpass.getuser()
    candidates = serial_candidates(dev)
    if not os.path.exists(path):
        return hardware.SerialFacts(path, False, user=user, candidates=candidates, baud=baud)
    group = _group_name(os.stat(path).st_gid)
    groups_now = sorted({_group_name(g) for g in os.getgroups()})
    listed = sorted(g.gr_name for g in grp.getgrall() if user in g.gr_mem)
    can_open = os.access(path, os.R_OK | os.W_OK)
    heard = None
    if can_open and listen:
        try:
            heard = listen_serial(path, baud, seconds)
        except OSError:
            can_open = False
    return hardware.SerialFacts(
        path, True, can_open, group, user, groups_now, listed, candidates, baud, heard
    )


def _group_name(gid: int) -> str:
    try:
        return grp.getgrgid(gid).gr_name
    except KeyError:
        return str(gid)


def camera_facts(
    dev: Path = Path("/dev"), run: Callable[..., str] | None = None
) -> hardware.CameraFacts:
    """The ``video*`` devices under ``dev``, with their formats from ``v4l2-ctl``."""
    devices = sorted(str(p) for p in dev.glob("video*"))
    formats: dict[str, list[str] | None] = {}
    tool = shutil.which("v4l2-ctl")
    for device in devices:
        if tool is None:
            formats[device] = None
            continue
        text = (run or _output)([tool, "-d", device, "--list-formats"])
        formats[device] = list(dict.fromkeys(_FORMAT.findall(text)))
    return hardware.CameraFacts(devices, formats)


def _output(argv: list[str]) -> str:
    """A command's standard output ("" when it fails or is not there)."""
    try:
        return subprocess.run(argv, capture_output=True, text=True, timeout=5, check=False).stdout
    except (OSError, subprocess.TimeoutExpired):
        return ""


def clock_synchronized() -> bool | None:
    """``timedatectl``'s NTPSynchronized (None: cannot tell)."""
    if shutil.which("timedatectl") is None:
        return None
    answer = _output(["timedatectl", "show", "-p", "NTPSynchronized", "--value"]).strip()
    return {"yes": True, "no": False}.get(answer)


def unit_states(unit_dir: Path = UNIT_DIR) -> dict[str, str]:
    """Each installed ``dronewrapper-*.service`` and its ``systemctl is-active`` state."""
    names = sorted(p.name for p in unit_dir.glob("dronewrapper-*.service"))
    states = {}
    for name in names:
        state = _output(["systemctl", "is-active", name]).strip()
        states[name] = state or "unknown (no systemd running)"
    return states


def run_hardware(
    report: Callable[[str, str], None],
    *,
    serial: str | None,
    baud: int,
    listen_s: float,
    recordings: str,
    dev: Path = Path("/dev"),
    unit_dir: Path = UNIT_DIR,
) -> int:
    """Every hardware check, reported; 1 if one failed."""
    findings = []
    path = serial
    if path is None:
        candidates = serial_candidates(dev)
        path = candidates[0] if len(candidates) == 1 else None
        if path is None:
            seen = ", ".join(candidates) or "none"
            findings.append((FAIL, f"serial: which device? pass --serial (here: {seen})"))
    if path is not None:
        findings += hardware.check_serial(serial_facts(path, baud, listen_s, dev))
    findings += hardware.check_cameras(camera_facts(dev))
    findings.append(hardware.check_clock(time.time(), clock_synchronized()))
    folder = Path(recordings)
    while not folder.exists() and folder != folder.parent:
        folder = folder.parent
    findings.append(hardware.check_disk(recordings, shutil.disk_usage(folder).free))
    findings += hardware.check_units(unit_states(unit_dir))
    for verdict, text in findings:
        report(verdict, text)
    return 1 if any(verdict == FAIL for verdict, _ in findings) else 0
