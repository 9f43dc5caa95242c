"""The simulated Tello's state datagram (field order, format, units and signs), its H.264
encoder and packetiser (decoded back with PyAV), and its settings."""

from __future__ import annotations

import math
import re

import av
import msgspec
import numpy as np
import pytest

from dronewrapper_sim.config import SimConfig
from dronewrapper_sim.tello.config import (
    TelloConfig,
    default_address,
    default_netns_subnet,
    netns_addresses,
)
from dronewrapper_sim.tello.flight import TelloFlight
from dronewrapper_sim.tello.params import camera_hfov_rad
from dronewrapper_sim.tello.protocol import TelloProtocol
from dronewrapper_sim.tello.state_string import FIELD_ORDER, format_state, parse_state
from dronewrapper_sim.tello.video import H264Encoder, packetise

STATE_LINE = re.compile(
    r"mid:-1;x:-100;y:-100;z:-100;mpry:-1,-1,-1;pitch:-?\d+;roll:-?\d+;yaw:-?\d+;"
    r"vgx:-?\d+;vgy:-?\d+;vgz:-?\d+;templ:\d+;temph:\d+;tof:\d+;h:\d+;bat:\d+;"
    r"baro:-?\d+\.\d\d;time:\d+;agx:-?\d+\.\d\d;agy:-?\d+\.\d\d;agz:-?\d+\.\d\d;\r\n"
)


def fly(flight: TelloFlight, protocol: TelloProtocol, seconds: float) -> None:
    for i in range(round(seconds / 0.01)):
        protocol.tick(0.01, i * 0.01)


def state_of(protocol: TelloProtocol) -> dict:
    text = format_state(protocol)
    assert STATE_LINE.fullmatch(text), text
    fields = parse_state(text)
    assert tuple(fields) == FIELD_ORDER
    return fields


def airborne(yaw_deg: float = 0.0) -> tuple[TelloFlight, TelloProtocol]:
    flight = TelloFlight(start=(0.0, 0.0, math.radians(yaw_deg)))
    protocol = TelloProtocol(flight, baro_origin_m=120.0)
    protocol.handle(b"command", ("127.0.0.1", 1), 0.0)
    flight.takeoff()
    fly(flight, protocol, 5.0)
    return flight, protocol


def test_state_on_the_ground():
    flight = TelloFlight()
    protocol = TelloProtocol(flight, baro_origin_m=120.0)
    s = state_of(protocol)
    assert (s["pitch"], s["roll"], s["yaw"]) == (0, 0, 0)
    assert (s["vgx"], s["vgy"], s["vgz"]) == (0, 0, 0)
    assert s["tof"] == 10  # the range finder's reading on the ground, cm
    assert s["h"] == 0
    assert s["bat"] == 100
    assert s["baro"] == pytest.approx(120.0)
    assert s["agz"] == pytest.approx(-1000.0, abs=1.0)  # 0.001 g, z down
    assert s["templ"] < s["temph"]
    assert s["mpry"] == "-1,-1,-1"


def test_state_units_and_signs_in_flight():
    flight, protocol = airborne(yaw_deg=90.0)  # power-on heading north
    s = state_of(protocol)
    assert 80 <= s["h"] <= 120  # cm
    assert s["tof"] == pytest.approx(s["h"] + 10, abs=2)
    assert s["baro"] == pytest.approx(120.0 + s["h"] / 100.0, abs=0.02)  # m
    assert s["time"] >= 3  # motors-on time, s
    flight.set_rc(0.0, 0.0, 1.0, 0.0)  # climb
    fly(flight, protocol, 1.0)
    assert state_of(protocol)["vgz"] <= -8  # dm/s, z down
    flight.set_rc(0.0, 1.0, 0.0, 0.0)  # forward (north): speeding up
    fly(flight, protocol, 0.3)
    s = state_of(protocol)
    assert s["pitch"] < -3  # nose down: pitch < 0
    assert -1300 < s["agz"] < -700  # mostly thrust along body z (z down)
    fly(flight, protocol, 3.0)
    s = state_of(protocol)
    assert s["vgx"] == pytest.approx(10, abs=1)  # 1 m/s forward of the power-on heading
    assert abs(s["vgy"]) <= 1
    flight.set_rc(1.0, 0.0, 0.0, 0.0)  # right (east)
    fly(flight, protocol, 0.3)
    assert state_of(protocol)["roll"] > 3  # right side down: roll > 0
    fly(flight, protocol, 3.0)
    assert state_of(protocol)["vgy"] == pytest.approx(10, abs=1)  # right of power-on heading
    flight.set_rc(0.0, 0.0, 0.0, 0.5)  # clockwise
    fly(flight, protocol, 1.0)
    s = state_of(protocol)
    assert 20 < s["yaw"] < 70  # clockwise > 0, relative to the power-on heading
    assert math.degrees(flight.state.yaw) < 90.0  # ENU yaw went down (CW)


def test_parse_state_rejects_malformed_fields():
    with pytest.raises(ValueError):
        parse_state("pitch:0;roll;")
    with pytest.raises(ValueError):
        parse_state("pitch:zero;")
    assert parse_state("bat:87;baro:1.50;\r\n") == {"bat": 87, "baro": 1.5}


def test_packetise_cuts_in_order():
    data = bytes(range(256)) * 20
    packets = packetise(data, 1460)
    assert [len(p) for p in packets] == [1460, 1460, 1460, 740]
    assert b"".join(packets) == data
    assert packetise(b"", 1460) == []
    with pytest.raises(ValueError):
        packetise(data, 0)


def test_h264_annex_b_decodes_back():
    encoder = H264Encoder(320, 240, 30.0, 800, keyframe_interval=10)
    decoder = av.CodecContext.create("h264", "r")
    rng = np.random.default_rng(0)
    decoded = []
    first = b""
    for i in range(12):
        image = np.full((240, 320, 3), (40 + 10 * i, 120, 200), np.uint8)
        image[100:140, 100 + 5 * i : 160 + 5 * i] = rng.integers(0, 255, (40, 60, 3))
        unit = encoder.encode(image)
        first = first or unit
        for datagram in packetise(unit, 1460):  # as received from the network
            for packet in decoder.parse(datagram):
                decoded += decoder.decode(packet)
    for packet in decoder.parse(b""):
        decoded += decoder.decode(packet)
    assert first.startswith(b"\x00\x00\x00\x01")  # Annex-B start code
    nal_types = {first[m.end()] & 0x1F for m in re.finditer(b"\x00\x00\x01", first)}
    assert {7, 8, 5} <= nal_types  # SPS, PPS and an IDR slice in the first access unit
    assert len(decoded) >= 10  # zero latency: (almost) every frame out at once
    assert (decoded[0].width, decoded[0].height) == (320, 240)
    with pytest.raises(ValueError):
        encoder.encode(np.zeros((10, 10, 3), np.uint8))
    encoder.close()


def test_camera_field_of_view():
    assert math.degrees(camera_hfov_rad()) == pytest.approx(70.3, abs=0.5)  # of 82.6 diagonal


def test_config_defaults_and_errors_name_the_key():
    assert default_address(0) == "127.0.0.1"
    assert default_address(2) == "127.0.0.3"
    assert default_netns_subnet(0) == "192.168.10.0/24"
    assert netns_addresses("192.168.10.0/24") == ("192.168.10.1", "192.168.10.2", 24)
    assert netns_addresses("10.9.0.0/30") == ("10.9.0.1", "10.9.0.2", 30)
    for bad in ("192.168.10.0/31", "192.168.10.1/24", "nonsense"):
        with pytest.raises(ValueError, match="netns_subnet"):
            netns_addresses(bad)
    for field, value in (("battery_percent", 0), ("width", 961), ("fps", 0), ("bitrate_kbps", 1)):
        with pytest.raises(msgspec.ValidationError, match=field):
            msgspec.convert({field: value}, TelloConfig)
    with pytest.raises(msgspec.ValidationError, match="aircraft"):
        msgspec.convert({"aircraft": "bebop"}, SimConfig)
    with pytest.raises(msgspec.ValidationError, match="address"):
        msgspec.convert({"address": "127.0.0.2"}, SimConfig)  # a Tello setting on the Iris
    with pytest.raises(msgspec.ValidationError, match="tello"):
        msgspec.convert({"aircraft": "tello", "tello": {"colour": "red"}}, SimConfig)
    with pytest.raises(msgspec.ValidationError, match="address"):
        msgspec.convert({"aircraft": "tello", "address": "localhost:8889"}, SimConfig)
    config = msgspec.convert({"aircraft": "tello", "tello": {"battery_percent": 50}}, SimConfig)
    assert config.tello.battery_percent == 50
