"""`dronewrapper up` refuses a graph whose port is taken, before starting anything (issue 12
item 10: two graphs on the same UDP port cross-talked silently)."""

from __future__ import annotations

import socket

import pytest

from support import free_endpoint, python_module

pytestmark = pytest.mark.integration


def test_a_taken_autopilot_port_is_refused_with_a_clear_message(spawn):
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as held:
        held.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)  # as the bridge holds it
        held.bind(("127.0.0.1", 0))
        port = held.getsockname()[1]
        argv = python_module(
            "dronewrapper", "up", "px4_sitl", "--var", f"onboard_port={port}",
            "--router", free_endpoint(),
        )  # fmt: skip
        proc = spawn(argv, "up")
        assert proc.proc.wait(60) == 1, proc.output()
    out = proc.output()
    assert f"UDP port {port} (${{onboard_port}}) is already in use" in out, out
    assert "--var onboard_port=N" in out
    assert "starting bridge_mavlink" not in out  # nothing was started
