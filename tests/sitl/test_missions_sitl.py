"""Opt-in: missions, return-to-launch and the envelope against real firmware.

``PX4_SITL_DIR`` (a PX4-Autopilot tree with ``build/px4_sitl_default``, SIH quadrotor) and
``AP_SITL_DIR`` (an ardupilot tree with ``build/sitl/bin/arducopter``) each turn on one test;
unset, the test is skipped with the reason (CI cannot build the firmware). Each flight runs
tests/sitl/mission_flight.py with the firmware in a private network namespace (``unshare
-n``, root only: the firmware's ports are fixed), and a working directory of its own.
"""

from __future__ import annotations

import contextlib
import json
import os
import signal
import subprocess
import sys
from pathlib import Path

import pytest

HERE = Path(__file__).parent
TIMEOUT_S = 800  # s for one flight (the firmware flies in real time)
STOP_GROUP = "kill -KILL -- -$fw"  # the firmware's process group (its state is not kept)


def _flight(tmp_path: Path, firmware: str, kind: str, connection: str) -> dict:
    """Run the firmware (``firmware`` execs it in a session of its own, whose process group
    is stopped at the end) and the flight in one private namespace; the flight's report."""
    script = (
        "ip link set lo up ; "
        f"({firmware}) > {tmp_path}/firmware.log 2>&1 & fw=$! ; echo $fw > {tmp_path}/fw.pid ; "
        f"{sys.executable} {HERE / 'mission_flight.py'} {kind} '{connection}' ; rc=$? ; "
        f"{STOP_GROUP} ; exit $rc"
    )
    env = {**os.environ, "PYTHONPATH": f"{HERE}:{os.environ.get('PYTHONPATH', '')}"}
    try:
        done = subprocess.run(
            ["unshare", "-n", "bash", "-c", script],
            capture_output=True,
            text=True,
            timeout=TIMEOUT_S,
            env=env,
            cwd=tmp_path,
        )
    finally:  # the firmware's process group, if the script could not stop it
        pid_file = tmp_path / "fw.pid"
        if pid_file.exists():
            with contextlib.suppress(ProcessLookupError, ValueError):
                os.killpg(int(pid_file.read_text()), signal.SIGKILL)
    lines = [line for line in done.stdout.splitlines() if line.startswith("{")]
    log = (tmp_path / "firmware.log").read_text(errors="replace")[-2000:]
    assert lines, f"no report (rc {done.returncode}):\n{done.stderr[-3000:]}\n{log}"
    report = json.loads(lines[-1])
    print(f"\n{kind}: {json.dumps(report, indent=1)}")
    assert done.returncode == 0, f"{report}\n{done.stderr[-3000:]}\n{log}"
    return report


def _judge(report: dict) -> None:
    assert report["mission_finished"], report
    assert max(report["waypoint_errors_m"]) < 1.0, report
    assert report["rtl_landed"] and report["rtl_landing_error_m"] < 1.0, report
    assert report["beyond_fence_refused"], report
    assert report["breach_action"], report


@pytest.mark.timeout(TIMEOUT_S + 60)
@pytest.mark.px4_sih  # opt-in: deselected unless PX4_SITL_DIR is set (tests/sitl/conftest.py)
@pytest.mark.skipif(os.geteuid() != 0, reason="a private network namespace needs root")
def test_px4_sitl_mission_rtl_and_fence(tmp_path):
    build = Path(os.environ["PX4_SITL_DIR"]) / "build" / "px4_sitl_default"
    assert (build / "bin" / "px4").is_file(), f"{build}/bin/px4: not built"
    (tmp_path / "etc").symlink_to(build / "etc")
    firmware = (
        "exec setsid env PX4_SIM_MODEL=sihsim_quadx PX4_SIMULATOR=sihsim HEADLESS=1 "
        f"{build / 'bin' / 'px4'} -d -i 7 {tmp_path}"
    )  # instance 7: its own lock and ports beside anyone's instance 0; tmp_path its rootfs
    _judge(_flight(tmp_path, firmware, "px4", "udpin:127.0.0.1:14547"))


@pytest.mark.timeout(TIMEOUT_S + 60)
@pytest.mark.ap_sitl  # opt-in: deselected unless AP_SITL_DIR is set (tests/sitl/conftest.py)
@pytest.mark.skipif(os.geteuid() != 0, reason="a private network namespace needs root")
def test_ardupilot_sitl_mission_rtl_and_fence(tmp_path):
    tree = Path(os.environ["AP_SITL_DIR"])
    binary = tree / "build" / "sitl" / "bin" / "arducopter"
    assert binary.is_file(), f"{binary}: not built"
    defaults = tree / "Tools" / "autotest" / "default_params" / "copter.parm"
    firmware = f"exec setsid {binary} --model quad --speedup 1 -I0 -w --defaults {defaults}"
    _judge(_flight(tmp_path, firmware, "ardupilot", "tcp:127.0.0.1:5760"))
