"""``dronewrapper doctor --hardware`` on a pseudo-terminal with an autopilot's heartbeats on
its far end (and then with bytes at another baud's garbling)."""

from __future__ import annotations

import os
import subprocess
import threading
import time
import tty

import pytest
from pymavlink.dialects.v20 import common as mavlink2

from support import python_module

pytestmark = pytest.mark.integration


def talk(master: int, stop: threading.Event, garble: bool) -> None:
    """Write a PX4 heartbeat every 0.2 s (garbled: what another baud would read)."""
    mav = mavlink2.MAVLink(None, srcSystem=1, srcComponent=1)
    while not stop.wait(0.2):
        frame = mavlink2.MAVLink_heartbeat_message(2, 12, 0, 0, 3, 3).pack(mav)
        if garble:
            frame = bytes((b * 7 + 3) & 0xFF for b in frame)
        try:
            os.write(master, frame)
        except OSError:
            return


def doctor_on_a_pty(tmp_path, garble: bool) -> subprocess.CompletedProcess:
    master, slave = os.openpty()
    tty.setraw(master)
    tty.setraw(slave)
    stop = threading.Event()
    talker = threading.Thread(target=talk, args=(master, stop, garble), daemon=True)
    talker.start()
    try:
        return subprocess.run(
            python_module(
                "dronewrapper", "doctor", "--hardware", "--serial", os.ttyname(slave),
                "--baud", "57600", "--seconds", "2", "--recordings", str(tmp_path),
            ),
            capture_output=True, text=True, timeout=60,
        )  # fmt: skip
    finally:
        stop.set()
        talker.join(timeout=2)
        os.close(master)
        os.close(slave)


def test_heartbeats_at_the_baud_are_found(tmp_path):
    start = time.monotonic()
    done = doctor_on_a_pty(tmp_path, garble=False)
    lines = done.stdout.splitlines()
    assert any(line.startswith("ok   serial: /dev/pts/") for line in lines), done.stdout
    assert any(line.startswith("ok   autopilot: PX4 (system 1)") for line in lines), done.stdout
    assert any(line.startswith(("ok   disk:", "warn disk:", "FAIL disk:")) for line in lines)
    assert any(" clock: " in line for line in lines) and any(" camera" in line for line in lines)
    assert time.monotonic() - start < 50


def test_bytes_without_a_heartbeat_point_at_the_baud(tmp_path):
    done = doctor_on_a_pty(tmp_path, garble=True)
    assert done.returncode == 1
    assert "FAIL autopilot:" in done.stdout and "another baud" in done.stdout, done.stdout
