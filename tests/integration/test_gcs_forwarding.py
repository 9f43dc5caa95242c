"""QGroundControl beside the bridge: the autopilot's MAVLink forwarded to a UDP ground station
and over Zenoh (``dronewrapper mavlink-forward``), its commands forwarded back, and their
acknowledgements never taken for the bridge's own."""

from __future__ import annotations

import time

import pytest
from bridge_rig import bridge_rig
from pymavlink.dialects.v20 import common as mavlink

from dronewrapper.msgs import registry
from dronewrapper.msgs.mavlink import MavlinkFrames
from support import loopback_udp, python_module, wait_for

pytestmark = pytest.mark.integration

ARM = mavlink.MAV_CMD_COMPONENT_ARM_DISARM


class FakeQgc:
    """A UDP ground station: listens on its port, answers to whoever sent it frames."""

    def __init__(self) -> None:
        self.sock = loopback_udp(0.2)
        self.port = self.sock.getsockname()[1]
        self.mav = mavlink.MAVLink(None, srcSystem=255, srcComponent=190)
        self.mav.robust_parsing = True
        self.peer = None

    def heartbeat_from(self, sysid: int, timeout: float = 10.0):
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            try:
                data, self.peer = self.sock.recvfrom(4096)
            except TimeoutError:
                continue
            for msg in self.mav.parse_buffer(data) or []:
                if msg.get_type() == "HEARTBEAT" and msg.get_srcSystem() == sysid:
                    return msg
        return None

    def command(self, command: int, *params: float) -> None:
        msg = mavlink.MAVLink_command_long_message(
            1, 1, command, 0, *params, *[0.0] * (7 - len(params))
        )
        self.sock.sendto(msg.pack(self.mav), self.peer)

    def close(self) -> None:
        self.sock.close()


def commands_from_qgc(peer, command: int) -> list:
    return [
        m for _, m in list(peer.received)
        if m.get_type() == "COMMAND_LONG" and m.command == command and m.get_srcComponent() == 190
    ]  # fmt: skip


def test_ground_station_over_udp_and_zenoh_and_its_acks_are_not_ours(router, spawn):
    qgc, remote_qgc = FakeQgc(), FakeQgc()
    try:
        with bridge_rig(router, gcs_url=f"udp:127.0.0.1:{qgc.port}", gcs_over_zenoh=True) as rig:
            # UDP: QGC hears the autopilot, and its command reaches the autopilot unchanged
            assert qgc.heartbeat_from(1) is not None
            qgc.command(ARM, 1.0)
            wait_for(lambda: commands_from_qgc(rig.peer, ARM), 10, what="QGC's command")

            # an acknowledgement addressed to QGC (255/190) is not the bridge's (255/191)
            before = rig.bridge.core.commands.acks.unsolicited
            to_qgc = mavlink.MAVLink_command_ack_message(ARM, 0, 0, 0, 255, 190)
            rig.bridge._on_command_ack(to_qgc, time.time(), time.monotonic())
            assert rig.bridge.core.commands.acks.unsolicited == before
            ours = mavlink.MAVLink_command_ack_message(ARM, 0, 0, 0, 255, 191)
            rig.bridge._on_command_ack(ours, time.time(), time.monotonic())
            assert (
                rig.bridge.core.commands.acks.unsolicited == before + 1
            )  # ours, though nothing waited

            # Zenoh: frames arrive batched; frames sent back reach the autopilot
            batches: list[MavlinkFrames] = []
            rig.user.subscribe(registry.MAVLINK_FROM_AUTOPILOT, batches.append)
            wait_for(lambda: sum(len(b.frames) for b in batches) > 10, 10, what="frames")

            # the laptop side: dronewrapper mavlink-forward exposes them to a local QGC
            forwarder = spawn(
                python_module(
                    "dronewrapper", "mavlink-forward", "--connect", router,
                    "--udp", f"127.0.0.1:{remote_qgc.port}",
                ),
                "mavlink-forward",
            )  # fmt: skip
            assert remote_qgc.heartbeat_from(1, timeout=30) is not None, forwarder.output()
            remote_qgc.command(mavlink.MAV_CMD_DO_SET_MODE, 1.0, 4.0)
            wait_for(
                lambda: commands_from_qgc(rig.peer, mavlink.MAV_CMD_DO_SET_MODE),
                15,
                what="the remote QGC's command through Zenoh",
            )
            assert forwarder.stop() == 0
    finally:
        qgc.close()
        remote_qgc.close()
