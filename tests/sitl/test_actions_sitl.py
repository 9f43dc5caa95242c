"""Opt-in: go-to, missions in both frames, issue 34's breach and Ctrl-C during a mission, through
the SDK against real PX4 SITL (SIH) and ArduCopter SITL (tests/sitl/actions_flight.py).

``PX4_SITL_DIR`` / ``AP_SITL_DIR`` each turn on one test (deselected otherwise, with the reason:
CI cannot build the firmware). Each flight runs in a private network namespace (``unshare -n``,
root only) with the firmware instance of ``DRONEWRAPPER_SITL_INSTANCE`` (default: PX4 7,
ArduCopter 3: PX4's server lock is machine-wide, whatever the namespace).
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
from pathlib import Path

import pytest

HERE = Path(__file__).parent
CEILING_M = 15.0  # actions_flight.CEILING_M
TIMEOUT_S = 900  # s for one flight: the firmware flies in real time
CTRL_C_BOUND_S = 120.0
"""From the Ctrl-C to on the ground and disarmed (docs/design.md "Long actions"): the rest of a
three-item mission (under 30 s), the commander's absence (5-6 s), the return and landing (under
60 s from 6 m away, at 4 m), with room for a loaded machine."""


def _flight(kind: str, instance: str) -> dict:
    env = {**os.environ, "DRONEWRAPPER_SITL_INSTANCE": os.environ.get(
        "DRONEWRAPPER_SITL_INSTANCE", instance)}  # fmt: skip
    script = f"ip link set lo up && exec {sys.executable} {HERE / 'actions_flight.py'} {kind}"
    proc = subprocess.Popen(
        ["unshare", "-n", "bash", "-c", script],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=env,
        start_new_session=True,
    )
    try:
        out, err = proc.communicate(timeout=TIMEOUT_S)
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait(10)
    lines = [line for line in out.splitlines() if line.startswith("{")]
    assert lines, f"no report (rc {proc.returncode}):\n{err[-3000:]}"
    report = json.loads(lines[-1])
    print(f"\n{kind}: {json.dumps(report, indent=1)}")
    return report


def _judge(report: dict) -> None:
    assert "failed" not in report, report
    for frame in ("local", "global"):
        assert report[frame]["finished"], report[frame]
        assert max(report[frame]["errors_m"]) < 1.0, report[frame]
    breach = report["breach"]
    assert breach["breached"] and breach["failsafe"] == "breach:return", breach
    assert breach["landed"], breach
    assert breach["max_altitude_m"] <= CEILING_M, breach
    ctrl_c = report["ctrl_c"]
    assert ctrl_c["started"] and ctrl_c["app_exited"] and ctrl_c["landed"], ctrl_c
    assert ctrl_c["ctrl_c_to_ground_s"] <= CTRL_C_BOUND_S, ctrl_c
    assert max(ctrl_c["errors_m"]) < 1.0, ctrl_c
    assert ctrl_c["max_altitude_m"] <= CEILING_M, ctrl_c


@pytest.mark.timeout(TIMEOUT_S + 60)
@pytest.mark.px4_sih  # opt-in: deselected unless PX4_SITL_DIR is set (tests/sitl/conftest.py)
@pytest.mark.skipif(os.geteuid() != 0, reason="a private network namespace needs root")
def test_px4_sitl_actions_through_the_sdk():
    _judge(_flight("px4", "7"))


@pytest.mark.timeout(TIMEOUT_S + 60)
@pytest.mark.ap_sitl  # opt-in: deselected unless AP_SITL_DIR is set (tests/sitl/conftest.py)
@pytest.mark.skipif(os.geteuid() != 0, reason="a private network namespace needs root")
def test_ardupilot_sitl_actions_through_the_sdk():
    _judge(_flight("ardupilot", "3"))
