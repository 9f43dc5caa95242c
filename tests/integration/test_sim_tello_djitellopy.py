"""The most used third-party Tello library, djitellopy, flown unchanged against the simulated
Tello in its own network namespace (``--netns``, root): connect, stream on and a frame,
take-off, moves, rotation, rc, stop, land. And the namespace's veth pair is gone after the
sim exits, also after it was killed with SIGKILL.

djitellopy binds 8889, 8890 and 11111 on every interface (as on a laptop on the Tello's
Wi-Fi) and keeps module-level sockets, so it flies from a child process of its own, in an
empty network namespace (``unshare --net``, the "laptop") where the sim is started too: its
``--netns`` namespace hangs off that one, and no port can collide with other tests.
"""

from __future__ import annotations

import json
import os
import random
import signal
import subprocess
import sys

import pytest

from support import REPO, python_module, wait_for

pytestmark = pytest.mark.integration

FLIGHT = r"""
import json, signal, subprocess, sys, time
from pathlib import Path

from dronewrapper.runtime.children import die_with_parent

# an empty network namespace of our own (unshare -n): djitellopy's 8889/8890/11111 on every
# interface cannot collide with other tests on this machine
subprocess.run(["ip", "link", "set", "lo", "up"], check=True)
log = Path(sys.argv[1])
with open(log, "wb") as out_file:
    sim = subprocess.Popen(
        [sys.executable, "-m", "dronewrapper_sim", "--aircraft", "tello", "--netns"],
        stdout=out_file, stderr=subprocess.STDOUT, preexec_fn=die_with_parent,
    )
deadline = time.time() + 30
while "ready:" not in log.read_text() and sim.poll() is None and time.time() < deadline:
    time.sleep(0.1)

def links():
    return subprocess.run(["ip", "-o", "link"], capture_output=True, text=True).stdout

out = {"veth_while_running": f"tsim{sim.pid}h" in links()}
from djitellopy import Tello

tello = Tello(host="192.168.10.1")
tello.connect()
out["battery"] = tello.get_battery()
out["sdk"] = tello.query_sdk_version()
tello.streamon()
reader = tello.get_frame_read()
deadline = time.time() + 15
while time.time() < deadline and reader.frame.shape != (720, 960, 3):
    time.sleep(0.05)
out["frame"] = list(reader.frame.shape)
out["frame_std"] = float(reader.frame.std())
tello.takeoff()
out["height_takeoff"] = tello.get_height()
tello.move_forward(50)
tello.move_up(30)
out["height_up"] = tello.get_height()
tello.rotate_clockwise(90)
out["yaw_cw"] = tello.get_yaw()
tello.send_rc_control(0, 60, 0, 0)
time.sleep(1.5)
out["rc_vgx_vgy"] = [tello.get_speed_x(), tello.get_speed_y()]
tello.send_rc_control(0, 0, 0, 0)
tello.send_control_command("stop")
tello.land()
time.sleep(0.3)  # the next state datagram (10 Hz) after the 'ok'
out["height_landed"] = tello.get_height()
tello.streamoff()
sim.send_signal(signal.SIGINT)
out["sim_exit"] = sim.wait(15)
out["veth_after_exit"] = f"tsim{sim.pid}h" in links()
print("RESULT " + json.dumps(out), flush=True)
"""


def veth_pairs() -> str:
    return subprocess.run(["ip", "-o", "link", "show"], capture_output=True, text=True).stdout


def test_djitellopy_flies_the_sim_through_netns(tmp_path):
    assert os.geteuid() == 0, "this test needs root: --netns creates a namespace and veth pair"
    log = tmp_path / "tello.log"
    flight = subprocess.run(
        ["unshare", "--net", "--", sys.executable, "-c", FLIGHT, str(log)],
        capture_output=True,
        text=True,
        timeout=150,
        cwd=REPO,
    )
    lines = [line for line in flight.stdout.splitlines() if line.startswith("RESULT ")]
    sim_log = log.read_text() if log.exists() else ""
    assert lines, flight.stdout + flight.stderr + sim_log
    out = json.loads(lines[0][len("RESULT ") :])
    assert out["veth_while_running"], sim_log
    assert out["battery"] == 100
    assert out["sdk"] == "20"
    assert out["frame"] == [720, 960, 3]
    assert out["frame_std"] > 5  # a rendered scene, decoded by djitellopy's PyAV reader
    assert 80 <= out["height_takeoff"] <= 120  # cm
    assert out["height_up"] - out["height_takeoff"] == pytest.approx(30, abs=8)
    assert out["yaw_cw"] == pytest.approx(90, abs=3)  # clockwise > 0
    vgx, vgy = out["rc_vgx_vgy"]  # forward after cw 90: to the right of the power-on heading
    assert vgy >= 3 and abs(vgx) <= 2
    assert out["height_landed"] == 0
    assert out["sim_exit"] == 0, sim_log
    assert not out["veth_after_exit"]  # removed at exit
    assert "Traceback" not in sim_log


def test_netns_is_gone_after_sigkill(spawn):
    assert os.geteuid() == 0, "this test needs root: --netns creates a namespace and veth pair"
    a, b = random.randrange(200, 250), random.randrange(256)  # unlikely to be in use
    proc = spawn(
        python_module(
            "dronewrapper_sim", "--aircraft", "tello", "--netns",
            "--set", f"tello.netns_subnet=10.{a}.{b}.0/24", "--set", "tello.video=false",
        ),
        "tello",
    )  # fmt: skip
    wait_for(lambda: "ready:" in proc.output() or not proc.alive(), 30, what="sim ready")
    assert proc.alive(), proc.output()
    host_if = f"tsim{proc.proc.pid}h"
    assert host_if in veth_pairs()
    addresses = subprocess.run(
        ["ip", "-o", "addr", "show", host_if], capture_output=True, text=True
    )
    assert f"10.{a}.{b}.2/24" in addresses.stdout
    os.kill(proc.proc.pid, signal.SIGKILL)
    proc.proc.wait(10)
    wait_for(lambda: host_if not in veth_pairs(), 10, what=f"{host_if} freed by the kernel")
