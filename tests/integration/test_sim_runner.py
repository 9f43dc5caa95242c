"""The real-time loop in-process (no Zenoh): simulated time follows the wall clock times the
real-time factor, and a link answers whoever talks to it, over real UDP sockets."""

from __future__ import annotations

import socket
import threading
import time

import pytest
from pymavlink.dialects.v20 import common as mavlink

from dronewrapper_sim.config import SimConfig
from dronewrapper_sim.runner import SimRunner
from dronewrapper_sim.world.scenario import load_scenario
from support import wait_for

pytestmark = pytest.mark.integration


def udp_socket() -> socket.socket:
    sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    sock.bind(("127.0.0.1", 0))
    sock.settimeout(0.2)
    return sock


def drain(sock: socket.socket, seconds: float) -> list:
    parser = mavlink.MAVLink(None)
    out, deadline = [], time.monotonic() + seconds
    while time.monotonic() < deadline:
        try:
            data, _ = sock.recvfrom(65535)
        except TimeoutError:
            continue
        out.extend(parser.parse_buffer(data) or [])
    return out


def test_runner_real_time_factor_and_reply_to_last_sender():
    first, second = udp_socket(), udp_socket()
    config = SimConfig(
        scenario="empty",
        cameras=False,
        udp_onboard=f"{first.getsockname()[1]}:0",
        udp_gcs="off",
        realtime_factor=2.0,
    )
    runner = SimRunner(config, load_scenario("empty"), node=None)
    stop = threading.Event()
    thread = threading.Thread(target=runner.run, args=(stop,), daemon=True)
    try:
        assert list(runner.links) == ["onboard"]
        wall0, sim0 = time.monotonic(), runner.autopilot.time_s
        thread.start()
        msgs = drain(first, 2.0)
        kinds = {m.get_type() for m in msgs}
        assert {"HEARTBEAT", "ATTITUDE", "LOCAL_POSITION_NED"} <= kinds
        assert all(m.get_srcSystem() == 1 for m in msgs)
        elapsed_sim = runner.autopilot.time_s - sim0
        elapsed_wall = time.monotonic() - wall0
        assert elapsed_sim / elapsed_wall == pytest.approx(2.0, rel=0.25)
        # simulated time drives the streams: ~2 x 100 ATTITUDE per wall second
        attitude_rate = sum(m.get_type() == "ATTITUDE" for m in msgs) / 2.0
        assert 120 < attitude_rate < 210

        # another peer talks: replies and telemetry now go to it
        client = mavlink.MAVLink(None, srcSystem=250, srcComponent=190)
        request = mavlink.MAVLink_param_request_read_message(1, 1, b"COM_OF_LOSS_T", -1)
        second.sendto(request.pack(client), ("127.0.0.1", runner.links["onboard"].local_port))
        replies = drain(second, 1.0)
        assert any(m.get_type() == "PARAM_VALUE" for m in replies)
        assert any(m.get_type() == "ATTITUDE" for m in replies)
        wait_for(lambda: runner.links["onboard"].remote[1] == second.getsockname()[1], 2)
    finally:
        stop.set()
        thread.join(5)
        runner.close()
        first.close()
        second.close()
    assert not thread.is_alive()


def test_unknown_scenario_exits_2_naming_the_known_ones(router, capsys):
    from dronewrapper_sim.cli import main

    argv = ["--scenario", "no_such_world", "--connect", router]
    assert main([*argv, "--udp-onboard", "off", "--udp-gcs", "off"]) == 2
    err = capsys.readouterr().err
    assert "no_such_world" in err and "beacon_static" in err


def test_a_garbage_datagram_cannot_swallow_the_next_one():
    """Garbage ending in what looks like the header of a signed MAVLink 2 frame (0xFD, a
    length, incompat flags with the signing bit) must not eat the start of the next datagram."""
    from dronewrapper_sim.mavlink_io import MavlinkUdpLink, UdpEndpoint

    peer = udp_socket()
    link = MavlinkUdpLink("onboard", UdpEndpoint("127.0.0.1", peer.getsockname()[1], 0), sysid=1)
    try:
        target = ("127.0.0.1", link.local_port)
        client = mavlink.MAVLink(None, srcSystem=250, srcComponent=190)
        peer.sendto(b"\xfd\x09garbage that is not MAVLink" * 3, target)
        peer.sendto(b"", target)
        request = mavlink.MAVLink_param_request_read_message(1, 1, b"COM_OF_LOSS_T", -1)
        peer.sendto(request.pack(client), target)
        got: list = []

        def request_arrived() -> bool:
            got.extend(link.receive())
            return any(m.get_type() == "PARAM_REQUEST_READ" for m in got)

        wait_for(request_arrived, 10, what="the valid datagram after the garbage")
        assert link.bad > 0  # the garbage was seen and dropped
        assert link.remote[1] == peer.getsockname()[1]
    finally:
        link.close()
        peer.close()
