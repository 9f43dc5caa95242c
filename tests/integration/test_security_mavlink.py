"""MAVLink 2 signing end to end: the simulated autopilot (a real process on loopback UDP)
rejects unsigned, wrongly signed and replayed commands once a key is provisioned, takes the
first SETUP_SIGNING unsigned and no other, and refuses a key change while armed."""

from __future__ import annotations

import time

import pytest
from mavlink_signer import encoder
from pymavlink.dialects.v20 import common as mavlink

from dronewrapper.security.keystore import KeyStore
from dronewrapper_sim.mavlink_io import signing_timestamp
from support import loopback_udp, python_module, wait_for

pytestmark = pytest.mark.integration

ARM = mavlink.MAV_CMD_COMPONENT_ARM_DISARM
ACK_WAIT_S = 1.5  # a sim that answers answers within a tick; bounded wait per command


class Station:
    """A ground station on a free UDP port: signs with ``key`` (None: unsigned), reads acks."""

    def __init__(self) -> None:
        self.sock = loopback_udp(0.05)
        self.port = self.sock.getsockname()[1]
        self.parser = mavlink.MAVLink(None)
        self.parser.robust_parsing = True
        self.peer: tuple[str, int] | None = None
        self.armed = False
        self.heartbeats = 0

    def encoder(self, key: bytes | None, *, timestamp: int | None = None) -> mavlink.MAVLink:
        """This station's encoder (system 245, component 191), signing with ``key``."""
        return encoder(key, timestamp, system=245, component=191)

    def pump(self, seconds: float, until=None) -> list:
        """Read for ``seconds``, or until ``until(acks)`` holds; returns the COMMAND_ACKs seen
        (tracks HEARTBEAT's armed bit)."""
        acks = []
        end = time.monotonic() + seconds
        while time.monotonic() < end and not (until and until(acks)):
            try:
                data, addr = self.sock.recvfrom(65535)
            except (TimeoutError, OSError):
                continue
            self.peer = addr
            for msg in self.parser.parse_buffer(data) or []:
                if msg.get_type() == "HEARTBEAT" and msg.get_srcComponent() == 1:
                    self.heartbeats += 1
                    self.armed = bool(msg.base_mode & mavlink.MAV_MODE_FLAG_SAFETY_ARMED)
                elif msg.get_type() == "COMMAND_ACK":
                    acks.append(msg)
        return acks

    def send_bytes(self, data: bytes) -> None:
        assert self.peer is not None
        self.sock.sendto(data, self.peer)

    def command(self, mav: mavlink.MAVLink, arm: bool) -> bytes:
        """Send an arm/disarm COMMAND_LONG packed by ``mav``; returns its bytes."""
        msg = mavlink.MAVLink_command_long_message(1, 1, ARM, 0, float(arm), 0, 0, 0, 0, 0, 0)
        data = msg.pack(mav)
        mav.seq = (mav.seq + 1) % 256
        self.send_bytes(data)
        return data

    def obeyed(self, mav: mavlink.MAVLink, arm: bool) -> bool:
        """Send arm/disarm and wait for its ack: True if acknowledged ACCEPTED (as soon as it
        is), False after ACK_WAIT_S without that ack."""

        def accepted(acks: list) -> bool:
            return any(a.command == ARM and a.result == mavlink.MAV_RESULT_ACCEPTED for a in acks)

        self.command(mav, arm)
        return accepted(self.pump(ACK_WAIT_S, until=accepted))

    def setup_signing(self, mav: mavlink.MAVLink, key: bytes) -> None:
        msg = mavlink.MAVLink_setup_signing_message(
            1, 1, key, signing_timestamp(time.time()) + 1000
        )
        self.send_bytes(msg.pack(mav))
        self.pump(0.5)

    def close(self) -> None:
        self.sock.close()


@pytest.fixture
def station():
    gcs = Station()
    yield gcs
    gcs.close()


def start_sim(spawn, router, station: Station, *extra: str) -> None:
    argv = python_module(
        "dronewrapper_sim", "--scenario", "empty", "--no-cameras", "--connect", router,
        "--udp-onboard", f"{station.port}:0", "--udp-gcs", "off", *extra,
    )  # fmt: skip
    spawn(argv, "sim")
    wait_for(lambda: station.pump(0.2) is not None and station.peer, 30, what="sim HEARTBEAT")


def test_provisioned_key_rejects_unsigned_wrong_and_replayed(spawn, router, station, tmp_path):
    store = KeyStore(tmp_path / "keys")
    key = store.new_mavlink_key()
    start_sim(spawn, router, station, "--signing-key", str(store.mavlink_key))
    attempts = {"unsigned": 0, "wrong key": 0, "replayed": 0}
    obeyed = {name: 0 for name in attempts}
    for _ in range(3):
        attempts["unsigned"] += 1
        obeyed["unsigned"] += station.obeyed(station.encoder(None), arm=True)
        attempts["wrong key"] += 1
        obeyed["wrong key"] += station.obeyed(station.encoder(bytes(32 * [7])), arm=True)
    assert not station.armed
    good = station.encoder(key)
    captured = station.command(good, arm=True)  # the signed ARM an eavesdropper records
    wait_for(lambda: station.pump(0.1) is not None and station.armed, 5, what="signed arm")
    assert station.obeyed(good, arm=False)  # signed disarm, newer timestamp
    wait_for(lambda: station.pump(0.1) is not None and not station.armed, 5, what="disarm")
    for _ in range(3):
        attempts["replayed"] += 1
        station.send_bytes(captured)
        acks = station.pump(ACK_WAIT_S)
        obeyed["replayed"] += any(a.result == mavlink.MAV_RESULT_ACCEPTED for a in acks)
    station.pump(0.5)
    assert not station.armed, "a replayed ARM armed the vehicle"
    assert obeyed == {"unsigned": 0, "wrong key": 0, "replayed": 0}, (attempts, obeyed)
    assert station.heartbeats > 0


def test_setup_signing_first_time_only_and_never_while_armed(spawn, router, station):
    start_sim(spawn, router, station)
    unsigned = station.encoder(None)
    assert station.obeyed(unsigned, arm=False)  # no key yet: everything is accepted
    first, second, third = bytes(range(32)), bytes(range(1, 33)), bytes(range(2, 34))
    station.setup_signing(unsigned, first)  # provisioning over an unsigned link: accepted once
    assert not station.obeyed(unsigned, arm=False)
    assert station.obeyed(station.encoder(first), arm=False)
    station.setup_signing(unsigned, second)  # unsigned again: ignored, the first key stays
    assert not station.obeyed(station.encoder(second), arm=False)
    signer = station.encoder(first)
    assert station.obeyed(signer, arm=True)
    station.setup_signing(signer, third)  # signed, but armed: refused
    assert not station.obeyed(station.encoder(third), arm=False)
    assert station.obeyed(signer, arm=False)
    station.setup_signing(signer, second)  # signed and disarmed: the key changes
    assert not station.obeyed(signer, arm=False)
    assert station.obeyed(station.encoder(second), arm=False)


def test_provision_tool_keys_the_simulated_autopilot(spawn, router, station, tmp_path):
    store = KeyStore(tmp_path / "keys")
    key = store.new_mavlink_key()
    start_sim(spawn, router, station)
    assert station.obeyed(station.encoder(None), arm=False)  # no key yet
    host, port = station.peer  # the sim's port: the tool speaks first, the sim answers it
    tool = spawn(
        python_module(
            "dronewrapper_bridge_mavlink.provision", "--connection", f"udpout:{host}:{port}",
            "--key", str(store.mavlink_key), "--timeout", "20",
        ),
        "provision",
    )  # fmt: skip
    assert tool.proc.wait(60) == 0, tool.output()
    assert "now signs with the key" in tool.output()
    assert not station.obeyed(station.encoder(None), arm=False)
    assert station.obeyed(station.encoder(key), arm=False)
