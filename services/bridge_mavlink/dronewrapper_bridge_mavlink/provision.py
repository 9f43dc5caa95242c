"""Provision the MAVLink 2 signing key on an autopilot: ``python -m
dronewrapper_bridge_mavlink.provision --connection /dev/ttyACM0 [--key FILE]``.

Sends SETUP_SIGNING with the key from ``dronewrapper keys mavlink`` (unsigned: an autopilot
takes that only while it has no key; PX4 only on USB, so do this over USB, never over a radio,
where the key would cross in clear), then checks that the autopilot now signs its messages
with that key. The vehicle must be disarmed. Exit 0 when the autopilot signs with the key.
"""

from __future__ import annotations

import os
import sys
import time

os.environ.setdefault("MAVLINK20", "1")

from pymavlink import mavutil

from dronewrapper.runtime.arguments import CommandParser
from dronewrapper.security.keystore import KeyStore, read_mavlink_key
from dronewrapper.security.mavlink_signing import verify_signed_frame

SIGNING_EPOCH_S = 1420070400  # 2015-01-01T00:00:00Z


def _autopilot_heartbeat(conn, timeout: float):
    """The autopilot's first HEARTBEAT; ours go out meanwhile (a UDP autopilot answers the
    last peer that spoke to it)."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        conn.mav.heartbeat_send(
            mavutil.mavlink.MAV_TYPE_GCS,
            mavutil.mavlink.MAV_AUTOPILOT_INVALID,
            0,
            0,
            mavutil.mavlink.MAV_STATE_ACTIVE,
        )
        msg = conn.recv_match(type="HEARTBEAT", blocking=True, timeout=1.0)
        if msg is not None and msg.get_srcComponent() == 1:
            return msg
    raise TimeoutError(f"no HEARTBEAT from {conn.address} within {timeout:g} s")


def provision(url: str, key: bytes, *, baud: int = 57600, timeout: float = 10.0) -> str:
    """Send the key to the autopilot at ``url`` and confirm; returns what happened.

    Raises:
        TimeoutError: no heartbeat, or no message signed with the key, within ``timeout``.
    """
    conn = mavutil.mavlink_connection(url, baud=baud, source_system=255, source_component=190)
    try:
        heartbeat = _autopilot_heartbeat(conn, timeout)
        target = heartbeat.get_srcSystem()
        stamp = int((time.time() - SIGNING_EPOCH_S) * 100_000)
        conn.mav.setup_signing_send(target, 1, key, stamp)
        conn.setup_signing(key, sign_outgoing=True, allow_unsigned_callback=lambda _m, _i: False)
        signing = conn.mav.signing
        conn.mav.check_signature = lambda buf, s, c: verify_signed_frame(signing, buf, s, c)
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            msg = conn.recv_match(blocking=True, timeout=0.5)
            if msg is not None and msg.get_type() != "BAD_DATA" and msg.get_signed():
                return f"system {target} now signs with the key ({msg.get_type()} verified)"
        raise TimeoutError(
            f"system {target} sent nothing signed with the key within {timeout:g} s: is it armed, "
            "already keyed with another key, or is this not a USB link?"
        )
    finally:
        conn.close()


def main(argv: list[str] | None = None) -> int:
    parser = CommandParser(prog="python -m dronewrapper_bridge_mavlink.provision")
    parser.add_argument("--connection", required=True, help="pymavlink URL (USB: /dev/ttyACM0)")
    parser.add_argument("--baud", type=int, default=57600)
    parser.add_argument("--key", default=None, help="key file (default: the key store's)")
    parser.add_argument("--timeout", type=float, default=10.0)
    args = parser.parse_args(argv)
    try:
        key = read_mavlink_key(args.key or KeyStore().mavlink_key)
        print(provision(args.connection, key, baud=args.baud, timeout=args.timeout))
    except (OSError, TimeoutError, ValueError) as exc:
        print(f"provision: {exc}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
