"""``doctor --hardware``'s judgements on given facts (pure): each says what to fix."""

from pymavlink.dialects.v20 import common as mavlink2

from dronewrapper.hardware import (
    EARLIEST_SANE_S,
    CameraFacts,
    HeardLine,
    SerialFacts,
    check_baud,
    check_cameras,
    check_clock,
    check_disk,
    check_serial,
    check_units,
    scan_heartbeats,
    x25_crc,
)
from dronewrapper.health import FAIL, OK, WARN


def heartbeats(count: int, autopilot: int = 12, signed: bool = False) -> bytes:
    mav = mavlink2.MAVLink(None, srcSystem=1, srcComponent=1)
    if signed:
        mav.signing.secret_key = bytes(range(32))
        mav.signing.sign_outgoing = True
    return b"".join(
        mavlink2.MAVLink_heartbeat_message(2, autopilot, 0, 0, 3, 3).pack(mav) for _ in range(count)
    )


def test_x25_crc_is_mavlinks():
    assert x25_crc(b"123456789") == 0x6F91  # CRC-16/MCRF4XX check value


def test_heartbeats_are_found_among_other_bytes_signed_or_not():
    other = mavlink2.MAVLink(None, srcSystem=1, srcComponent=1)
    noise = mavlink2.MAVLink_local_position_ned_message(1, 1.0, 2.0, 3.0, 0, 0, 0).pack(other)
    data = noise + heartbeats(2) + b"\xfd\x09garbage" + heartbeats(1, autopilot=3, signed=True)
    heard = scan_heartbeats(data, 2.0)
    assert (heard.heartbeats, heard.autopilot, heard.system) == (3, 12, 1)


def test_bytes_at_the_wrong_baud_hold_no_heartbeat():
    garbled = bytes((b * 7 + 3) & 0xFF for b in heartbeats(5))  # what another baud reads
    assert scan_heartbeats(garbled, 2.0).heartbeats == 0


def test_baud_verdicts_say_what_to_change():
    ok = check_baud("/dev/ttyTHS1", 921600, HeardLine(2.0, 400, 2, 12, 1))
    assert ok[0] == OK and "PX4 (system 1)" in ok[1] and "1.0 Hz" in ok[1]
    wrong = check_baud("/dev/ttyTHS1", 57600, HeardLine(2.0, 900))
    assert wrong[0] == FAIL and "another baud" in wrong[1] and "SER_TEL2_BAUD" in wrong[1]
    silent = check_baud("/dev/ttyTHS1", 57600, HeardLine(2.0, 0))
    assert silent[0] == FAIL and "nothing arrived" in silent[1] and "TX" in silent[1]


def test_a_missing_device_lists_the_ones_there():
    [(verdict, text)] = check_serial(
        SerialFacts("/dev/ttyTHS1", False, user="j", candidates=["/dev/ttyUSB0"])
    )
    assert verdict == FAIL and "/dev/ttyUSB0" in text and "--serial" in text


def test_permission_fixes_depend_on_the_group_and_the_login():
    never = SerialFacts("/dev/ttyUSB0", True, False, "dialout", "j", ["j"], [])
    [(verdict, text)] = check_serial(never)
    assert verdict == FAIL and "sudo usermod -aG dialout j" in text
    stale = SerialFacts("/dev/ttyUSB0", True, False, "dialout", "j", ["j"], ["dialout"])
    assert "log out and in again" in check_serial(stale)[0][1]
    assert "usermod" not in check_serial(stale)[0][1]


def test_an_openable_device_is_then_listened_to():
    facts = SerialFacts("/dev/ttyUSB0", True, True, "dialout", "j", heard=HeardLine(2, 0))
    verdicts = [v for v, _ in check_serial(facts)]
    assert verdicts == [OK, FAIL]


def test_cameras_and_their_formats():
    assert check_cameras(CameraFacts([]))[0][0] == WARN
    found = check_cameras(
        CameraFacts(
            ["/dev/video0", "/dev/video1", "/dev/video2"],
            {"/dev/video0": ["MJPG", "YUYV"], "/dev/video1": [], "/dev/video2": ["YUYV"]},
        )
    )
    assert found[0] == (OK, "camera: /dev/video0 gives MJPG, YUYV")
    assert found[1][0] == OK and "metadata" in found[1][1]
    assert found[2][0] == WARN and "MJPG" in found[2][1]
    unknown = check_cameras(CameraFacts(["/dev/video0"], {"/dev/video0": None}))
    assert "v4l-utils" in unknown[0][1]


def test_clock_disk_and_units():
    assert check_clock(0.0, None)[0] == FAIL  # 1970: never set
    assert check_clock(EARLIEST_SANE_S + 1, False)[0] == WARN
    assert check_clock(EARLIEST_SANE_S + 1, True)[0] == OK
    assert check_disk("/rec", 500_000_000)[0] == FAIL
    assert check_disk("/rec", 3_000_000_000)[0] == WARN
    assert check_disk("/rec", 50_000_000_000) == (OK, "disk: 50 GB free at /rec")
    assert check_units({})[0][0] == OK
    units = {"dronewrapper-a.service": "failed", "dronewrapper-b.service": "active"}
    states = dict(check_units(units))
    assert "journalctl -u dronewrapper-a.service" in states[FAIL]
    assert check_units({"dronewrapper-a.service": "inactive"})[0][0] == WARN
