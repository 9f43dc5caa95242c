"""``dronewrapper doctor --hardware``: the companion computer's checklist, judged (pure).

What :mod:`dronewrapper.hardware_probe` found on this computer (the facts below) is judged
here, each finding a (verdict, sentence) that says what to fix: the autopilot's serial device
and whether this user may open it (the ``dialout`` group), whether MAVLink heartbeats arrive
at the configured baud (bytes without a single valid heartbeat mean another baud), the
cameras and their pixel formats, the clock, free disk for recordings, and the systemd units
of ``dronewrapper install``.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

from dronewrapper.health import FAIL, OK, WARN

Finding = tuple[str, str]

MAVLINK1_STX, MAVLINK2_STX = 0xFE, 0xFD
HEARTBEAT_CRC_EXTRA = 50
HEARTBEAT_PAYLOAD = 9
AUTOPILOTS = {3: "ArduPilot", 12: "PX4"}
EARLIEST_SANE_S = 1_704_067_200.0  # 2024-01-01 UTC: a clock before it was never set
DISK_FAIL_BYTES = 1_000_000_000
DISK_WARN_BYTES = 5_000_000_000
"""Recordings with images take about 1 GB every few minutes."""


def x25_crc(data: bytes, crc: int = 0xFFFF) -> int:
    """MAVLink's checksum (CRC-16/MCRF4XX) of ``data``."""
    for byte in data:
        tmp = byte ^ (crc & 0xFF)
        tmp = (tmp ^ (tmp << 4)) & 0xFF
        crc = ((crc >> 8) ^ (tmp << 8) ^ (tmp << 3) ^ (tmp >> 4)) & 0xFFFF
    return crc


@dataclass(frozen=True)
class HeardLine:
    """What arrived on a serial line while listening.

    Attributes:
        seconds: how long it listened.
        received: bytes that arrived.
        heartbeats: MAVLink HEARTBEATs with a valid checksum among them.
        autopilot: MAV_AUTOPILOT of the first heartbeat (12 PX4, 3 ArduPilot), or None.
        system: its system id, or None.
    """

    seconds: float
    received: int
    heartbeats: int = 0
    autopilot: int | None = None
    system: int | None = None


def scan_heartbeats(data: bytes, seconds: float) -> HeardLine:
    """The valid MAVLink 1/2 HEARTBEATs in ``data`` (bytes that arrived in ``seconds``)."""
    count, autopilot, system = 0, None, None
    i = 0
    while i < len(data) - 2:
        stx = data[i]
        if stx == MAVLINK2_STX and data[i + 1] == HEARTBEAT_PAYLOAD:
            header, msg_id_at = 10, (i + 7, i + 10)
        elif stx == MAVLINK1_STX and data[i + 1] == HEARTBEAT_PAYLOAD:
            header, msg_id_at = 6, (i + 5, i + 6)
        else:
            i += 1
            continue
        end = i + header + HEARTBEAT_PAYLOAD + 2
        frame = data[i:end]
        msg_id = int.from_bytes(data[msg_id_at[0] : msg_id_at[1]], "little")
        if len(frame) == end - i and msg_id == 0:
            body = frame[1 : header + HEARTBEAT_PAYLOAD] + bytes([HEARTBEAT_CRC_EXTRA])
            if x25_crc(body) == int.from_bytes(frame[-2:], "little"):
                count += 1
                if autopilot is None:
                    payload = frame[header : header + HEARTBEAT_PAYLOAD]
                    autopilot, system = payload[5], frame[5 if stx == MAVLINK2_STX else 3]
                i = end
                continue
        i += 1
    return HeardLine(seconds, len(data), count, autopilot, system)


@dataclass(frozen=True)
class SerialFacts:
    """The autopilot's serial device as this computer has it.

    Attributes:
        path: the device (``/dev/ttyTHS1``).
        exists: it is there.
        can_open: this process may read and write it.
        group: the device's group (``dialout``).
        user: who runs the check.
        groups_now: the groups this process has (a new membership needs a new login).
        groups_listed: the groups ``/etc/group`` lists the user in.
        candidates: serial devices that are there (``/dev/ttyUSB0`` ...).
        baud: the rate listened at.
        heard: what arrived at that rate (None: not listened).
    """

    path: str
    exists: bool
    can_open: bool = False
    group: str = ""
    user: str = ""
    groups_now: Sequence[str] = ()
    groups_listed: Sequence[str] = ()
    candidates: Sequence[str] = ()
    baud: int = 57600
    heard: HeardLine | None = None


def check_serial(facts: SerialFacts) -> list[Finding]:
    """The device is there, this user may open it, and heartbeats arrive at the baud."""
    path = facts.path
    if not facts.exists:
        seen = ", ".join(facts.candidates) or "none"
        return [
            (
                FAIL,
                f"serial: no {path} (serial devices here: {seen}); plug in the autopilot's USB "
                "or telemetry cable, or pass the right one with --serial",
            )
        ]
    if not facts.can_open:
        group = facts.group or "dialout"
        if group in facts.groups_listed and group not in facts.groups_now:
            fix = f"{facts.user} is in {group} but this login is older: log out and in again"
        else:
            fix = f"sudo usermod -aG {group} {facts.user}, then log out and in again"
        return [(FAIL, f"serial: {facts.user} may not open {path} (group {group}): {fix}")]
    found = [(OK, f"serial: {path} is there and {facts.user} may open it")]
    if facts.heard is not None:
        found.append(check_baud(path, facts.baud, facts.heard))
    return found


def check_baud(path: str, baud: int, heard: HeardLine) -> Finding:
    """Heartbeats at ``baud``: right; bytes without one: another baud; nothing: no talker."""
    where = f"{path} at {baud} baud"
    if heard.heartbeats:
        name = AUTOPILOTS.get(heard.autopilot or -1, f"autopilot type {heard.autopilot}")
        rate = heard.heartbeats / heard.seconds if heard.seconds > 0 else 0.0
        return OK, f"autopilot: {name} (system {heard.system}) heartbeats on {where}, {rate:.1f} Hz"
    if heard.received:
        return (
            FAIL,
            f"autopilot: {heard.received} bytes in {heard.seconds:.0f} s on {where} but no valid "
            "MAVLink heartbeat: the autopilot's port runs at another baud (PX4 SER_TEL2_BAUD, "
            "ArduPilot SERIALn_BAUD) or speaks something else (PX4 MAV_1_CONFIG, ArduPilot "
            "SERIALn_PROTOCOL = 2)",
        )
    return (
        FAIL,
        f"autopilot: nothing arrived on {where} in {heard.seconds:.0f} s: is it powered, are TX "
        "and RX crossed, is MAVLink enabled on that port (PX4 MAV_1_CONFIG)?",
    )


@dataclass(frozen=True)
class CameraFacts:
    """The video devices, and the pixel formats of each (None: could not be listed)."""

    devices: Sequence[str]
    formats: Mapping[str, Sequence[str] | None] = field(default_factory=dict)


def check_cameras(facts: CameraFacts) -> list[Finding]:
    """A camera is there, and says which formats it gives (MJPG for 30 fps on USB 2)."""
    if not facts.devices:
        return [(WARN, "camera: no /dev/video* device: plug in the USB camera (lsusb shows it)")]
    found = []
    for device in facts.devices:
        formats = facts.formats.get(device)
        if formats is None:
            found.append(
                (OK, f"camera: {device} (install v4l-utils to list its formats: v4l2-ctl)")
            )
        elif not formats:
            found.append((OK, f"camera: {device} has no capture formats (a metadata node)"))
        elif "MJPG" not in formats:
            listed = ", ".join(formats)
            found.append(
                (
                    WARN,
                    f"camera: {device} gives {listed} but not MJPG: at 640x480 a USB 2 camera "
                    "reaches 30 fps only in MJPG; set pixel_format: YUYV and a lower fps",
                )
            )
        else:
            found.append((OK, f"camera: {device} gives {', '.join(formats)}"))
    return found


def check_clock(now: float, synchronized: bool | None) -> Finding:
    """The clock is set, and kept in step with network time."""
    if now < EARLIEST_SANE_S:
        return (
            FAIL,
            "clock: it is set before 2024 (a Jetson has no clock battery by default): stamps "
            "across machines will be wrong; connect to a network with NTP "
            "(sudo timedatectl set-ntp true) or install chrony",
        )
    if synchronized is False:
        return (
            WARN,
            "clock: not synchronised with network time: latencies measured across machines "
            "will be off; sudo timedatectl set-ntp true (or chrony)",
        )
    if synchronized is None:
        return OK, "clock: set (whether it follows network time is unknown: no timedatectl)"
    return OK, "clock: set and synchronised with network time"


def check_disk(path: str, free_bytes: int) -> Finding:
    """Room for recordings at ``path``."""
    free_gb = free_bytes / 1e9
    if free_bytes < DISK_FAIL_BYTES:
        return FAIL, f"disk: {free_gb:.1f} GB free at {path}: too little to record; free space"
    if free_bytes < DISK_WARN_BYTES:
        return WARN, f"disk: {free_gb:.1f} GB free at {path}: minutes of recording with images"
    return OK, f"disk: {free_gb:.0f} GB free at {path}"


def check_units(states: Mapping[str, str]) -> list[Finding]:
    """The ``dronewrapper-*`` units and their states (``systemctl is-active``)."""
    if not states:
        return [(OK, "boot: no graph starts at boot (dronewrapper install GRAPH sets one up)")]
    found = []
    for name, state in sorted(states.items()):
        if state == "active":
            found.append((OK, f"boot: {name} is running"))
        elif state == "failed":
            found.append((FAIL, f"boot: {name} failed: see journalctl -u {name} -n 50"))
        elif state in ("activating", "reloading"):
            found.append((WARN, f"boot: {name} is starting (restarting after a failure?)"))
        else:
            found.append((WARN, f"boot: {name} is {state}: sudo systemctl start {name}"))
    return found
