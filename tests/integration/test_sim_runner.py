"""The real-time loop in-process (no Zenoh): simulated time follows the wall clock times the
real-time factor, and a link answers whoever talks to it, over real UDP sockets."""

from __future__ import annotations

import contextlib
import logging
import threading

import pytest
from pymavlink.dialects.v20 import common as mavlink

from dronewrapper_sim.config import SimConfig
from dronewrapper_sim.runner import SimRunner
from dronewrapper_sim.world.scenario import load_scenario
from support import loopback_udp, wait_for

pytestmark = pytest.mark.integration


def test_runner_real_time_factor_and_reply_to_last_sender():
    first, second = loopback_udp(0.2), loopback_udp(0.2)
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
        thread.start()
        wait_for(lambda: runner.clock[1] > 0, 10, what="the loop running")
        # the loop's own (wall, simulated, slipped) readings, taken together: a stall of this
        # loaded process between a reading and its use cannot skew them
        wall0, sim0, slip0 = runner.clock
        msgs: list = []
        parser = mavlink.MAVLink(None)

        def running_time() -> float:
            """Wall time (s) the clock ran (not slipped after a stall) since the first reading."""
            wall, _, slipped = runner.clock
            return wall - wall0 - (slipped - slip0)

        def enough() -> bool:  # 2 s of running time (longer if a loaded machine stalls us)
            with contextlib.suppress(TimeoutError):
                msgs.extend(parser.parse_buffer(first.recvfrom(65535)[0]) or [])
            return running_time() >= 2.0

        wait_for(enough, 30, interval=0.0, what="2 s of the real-time loop")
        wall1, sim1, slip1 = runner.clock
        kinds = {m.get_type() for m in msgs}
        assert {"HEARTBEAT", "ATTITUDE", "LOCAL_POSITION_NED"} <= kinds
        assert all(m.get_srcSystem() == 1 for m in msgs)
        # simulated time = running wall time x 2 (to a physics step)
        ratio = (sim1 - sim0) / (wall1 - wall0 - (slip1 - slip0))
        assert ratio == pytest.approx(2.0, rel=0.05), (ratio, wall1 - wall0, slip1 - slip0)
        # simulated time drives the streams: ATTITUDE is 100 Hz of simulated time (200 per
        # wall second at this factor; a wall-clock schedule would give 50 per simulated
        # second). Counted on the messages' own stamps; a stalled loop drops a few at most.
        stamps = [m.time_boot_ms for m in msgs if m.get_type() == "ATTITUDE"]
        assert len(stamps) > 50, len(stamps)
        rate = (len(stamps) - 1) / ((stamps[-1] - stamps[0]) / 1000.0)
        assert 70.0 < rate <= 105.0, f"ATTITUDE at {rate:.1f} Hz of simulated time"

        # another peer talks: replies and telemetry now go to it
        client = mavlink.MAVLink(None, srcSystem=250, srcComponent=190)
        request = mavlink.MAVLink_param_request_read_message(1, 1, b"COM_OF_LOSS_T", -1)
        second.sendto(request.pack(client), ("127.0.0.1", runner.links["onboard"].local_port))
        replies: list = []
        reply_parser = mavlink.MAVLink(None)

        def answered() -> bool:
            with contextlib.suppress(TimeoutError):
                replies.extend(reply_parser.parse_buffer(second.recvfrom(65535)[0]) or [])
            return {"PARAM_VALUE", "ATTITUDE"} <= {m.get_type() for m in replies}

        wait_for(answered, 10, interval=0.0, what="the reply and telemetry on the new peer")
        assert runner.links["onboard"].remote[1] == second.getsockname()[1]
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
    root = logging.getLogger()
    handlers = list(root.handlers)
    try:
        assert main([*argv, "--udp-onboard", "off", "--udp-gcs", "off"]) == 2
    finally:  # main's log handler writes to the captured stderr, which closes after this test
        for handler in root.handlers[:]:
            if handler not in handlers:
                root.removeHandler(handler)
    err = capsys.readouterr().err
    assert "no_such_world" in err and "beacon_static" in err


def test_a_garbage_datagram_cannot_swallow_the_next_one():
    """Garbage ending in what looks like the header of a signed MAVLink 2 frame (0xFD, a
    length, incompat flags with the signing bit) must not eat the start of the next datagram."""
    from dronewrapper_sim.mavlink_io import MavlinkUdpLink, UdpEndpoint

    peer = loopback_udp(0.2)
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
