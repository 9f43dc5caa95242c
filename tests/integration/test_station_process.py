"""`dronewrapper station` as a real process: serves, announces itself, exits cleanly."""

from __future__ import annotations

import json
import re
import signal
import subprocess
import sys
import urllib.request

import pytest

from dronewrapper.discovery import alive_services
from support import client_node, free_port, python_module, wait_for

pytestmark = pytest.mark.integration


def test_station_serves_and_stops_on_sigint(router, spawn):
    port = free_port()
    station = spawn(
        python_module("dronewrapper", "station", "--connect", router, "--port", str(port)),
        "station",
    )
    url = wait_for(
        lambda: re.search(r"station: open (http://\S+)", station.output()),
        30,
        what="the station's address",
    ).group(1)
    assert url == f"http://127.0.0.1:{port}/"  # loopback: no token
    with urllib.request.urlopen(url + "api/session", timeout=10) as reply:
        assert json.loads(reply.read())["role"] == "operator"
    with client_node(router) as node:
        wait_for(
            lambda: "drone/alive/station" in alive_services(node.session), 10, what="liveliness"
        )
    station.proc.send_signal(signal.SIGINT)
    assert station.proc.wait(15) == 0, station.output()


def test_bad_config_names_the_key():
    result = subprocess.run(
        [*python_module("dronewrapper", "station"), "--set", "teleop.horizontal=-1"],
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert result.returncode == 2
    assert "teleop.horizontal" in result.stderr


def test_help():
    result = subprocess.run(
        [sys.executable, "-m", "dronewrapper_ground_station", "--help"],
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert result.returncode == 0 and "--host" in result.stdout and "--port" in result.stdout
