"""The serial link's budget: frame sizes, stream cost, and rates that fit the line (pure)."""

import pytest

from dronewrapper_bridge_mavlink.config import DEFAULT_MESSAGE_RATES, Config
from dronewrapper_bridge_mavlink.core import BridgeCore
from dronewrapper_bridge_mavlink.link_budget import (
    MIN_RATE_HZ,
    fit_rates,
    frame_bytes,
    is_serial_url,
    line_capacity,
    stream_cost,
)


def test_frame_bytes_are_header_payload_checksum_and_signature():
    assert frame_bytes("HEARTBEAT", signed=False) == 10 + 9 + 2
    assert frame_bytes("LOCAL_POSITION_NED", signed=False) == 10 + 28 + 2
    assert frame_bytes("LOCAL_POSITION_NED", signed=True) == 10 + 28 + 2 + 13
    with pytest.raises(KeyError, match="NOT_A_MESSAGE"):
        frame_bytes("NOT_A_MESSAGE", signed=False)


def test_serial_urls_and_network_urls():
    assert is_serial_url("/dev/ttyACM0") and is_serial_url("/dev/pts/3") and is_serial_url("COM3")
    for url in ("udpin:127.0.0.1:14540", "udpout:1.2.3.4:5", "tcp:127.0.0.1:5760", "tcpin:x:1"):
        assert not is_serial_url(url)


def test_default_rates_overflow_57600_and_are_scaled_to_the_share():
    full = stream_cost(DEFAULT_MESSAGE_RATES, signed=False)
    assert full > line_capacity(57600)  # the defaults would ask more than the whole line
    budget = fit_rates(DEFAULT_MESSAGE_RATES, 57600, signed=False, share=0.6)
    assert budget.scale < 1.0
    assert budget.cost <= 0.6 * 5760 + 1e-6
    pose = budget.rates["LOCAL_POSITION_NED"]
    assert pose == pytest.approx(50.0 * budget.scale)
    assert pose >= 20.0  # the controller's pose still arrives at 20 Hz or more
    assert budget.rates["HOME_POSITION"] == 0.5  # never raised, never below its asked rate
    assert "scaled" in budget.describe()


def test_signing_costs_13_bytes_a_frame_and_scales_further():
    plain = fit_rates(DEFAULT_MESSAGE_RATES, 57600, signed=False)
    signed = fit_rates(DEFAULT_MESSAGE_RATES, 57600, signed=True)
    assert signed.scale < plain.scale


def test_a_fast_line_keeps_the_configured_rates():
    budget = fit_rates(DEFAULT_MESSAGE_RATES, 921600, signed=True)
    assert budget.scale == 1.0 and budget.rates == DEFAULT_MESSAGE_RATES
    assert "fit" in budget.describe()


def test_a_network_link_has_no_budget():
    budget = fit_rates(DEFAULT_MESSAGE_RATES, None, signed=False)
    assert (budget.scale, budget.capacity) == (1.0, 0.0)
    assert budget.rates == DEFAULT_MESSAGE_RATES


def test_a_line_too_slow_keeps_a_floor_rate():
    budget = fit_rates({"LOCAL_POSITION_NED": 50.0}, 600, signed=False, share=0.5)
    assert budget.rates["LOCAL_POSITION_NED"] == MIN_RATE_HZ
    assert budget.cost > 0.5 * 60  # said honestly: over the share
    assert budget.scale == pytest.approx(1 / 50)
    with pytest.raises(ValueError, match="share"):
        fit_rates({}, 57600, signed=False, share=0.0)


def test_the_bridge_asks_for_the_fitted_rates_on_a_serial_line():
    serial = BridgeCore(Config(connection="/dev/ttyUSB0", baud=57600))
    network = BridgeCore(Config(connection="udpin:127.0.0.1:14540", baud=57600))
    pose_id = 32  # LOCAL_POSITION_NED
    asked = {i: us for i, us in serial.streams.round(0.0) if i == pose_id}
    assert asked[pose_id] == pytest.approx(1e6 / serial.budget.rates["LOCAL_POSITION_NED"])
    assert serial.budget.scale < 1.0 and network.budget.scale == 1.0
    assert dict(network.streams.round(0.0))[pose_id] == pytest.approx(1e6 / 50.0)


@pytest.mark.parametrize(("key", "value"), [("link_share", 0.0), ("link_warn_load", 1.5)])
def test_bad_link_settings_are_refused_by_name(key, value):
    with pytest.raises(ValueError, match=key):
        Config(**{key: value})
    with pytest.raises(ValueError, match="baud"):
        Config(baud=0)
