"""``dronewrapper install`` / ``uninstall`` into a temporary root, and the unit checked by
``systemd-analyze verify`` (Debian's systemd; nothing is installed on this machine)."""

from __future__ import annotations

import shutil
import subprocess
from pathlib import Path

import pytest

from support import python_module

pytestmark = pytest.mark.integration

GRAPH = "compose/px4_real_follow_person_secure.yaml"
UNIT = "dronewrapper-px4_real_follow_person_secure.service"


def dronewrapper(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run(
        python_module("dronewrapper", *args), capture_output=True, text=True, timeout=60
    )


def install_args(root: Path) -> list[str]:
    return [
        "install", GRAPH, "--user", "root", "--root", str(root),
        "--var", "serial=/dev/ttyTHS1", "--var", "baud=921600",
        "--listen", "tls/0.0.0.0:7448", "--identity", "drone1",
    ]  # fmt: skip


def test_install_writes_enables_and_uninstall_removes(tmp_path):
    done = dronewrapper(*install_args(tmp_path))
    assert done.returncode == 0, done.stderr + done.stdout
    unit = tmp_path / "etc/systemd/system" / UNIT
    text = unit.read_text()
    assert "Requires=dev-ttyTHS1.device" in text
    assert "--listen=tls/0.0.0.0:7448 --identity=drone1" in text
    wanted = tmp_path / "etc/systemd/system/multi-user.target.wants" / UNIT
    assert wanted.is_symlink()
    done = dronewrapper("uninstall", GRAPH, "--root", str(tmp_path))
    assert done.returncode == 0, done.stderr + done.stdout
    assert not unit.exists() and not wanted.exists()


def test_systemd_analyze_verifies_the_unit(tmp_path):
    assert shutil.which("systemd-analyze"), "apt-get install systemd (see .ci/run)"
    done = dronewrapper(*install_args(tmp_path), "--print")
    assert done.returncode == 0, done.stderr
    unit = tmp_path / UNIT
    unit.write_text(done.stdout)
    verify = subprocess.run(
        ["systemd-analyze", "verify", "--man=no", str(unit)],
        capture_output=True, text=True, timeout=60,
    )  # fmt: skip
    problems = [line for line in verify.stderr.splitlines() if UNIT in line]
    assert verify.returncode == 0 and not problems, verify.stderr


def test_a_wrong_graph_variable_or_a_tls_listener_without_identity_is_refused(tmp_path):
    done = dronewrapper("install", GRAPH, "--user", "root", "--print", "--var", "baud=fast")
    assert done.returncode == 2 and "baud" in done.stderr
    done = dronewrapper(
        "install", GRAPH, "--user", "root", "--print", "--listen", "tls/0.0.0.0:7448"
    )
    assert done.returncode == 2 and "--identity" in done.stderr
    assert not any(tmp_path.iterdir())
