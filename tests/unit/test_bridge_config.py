"""bridge_mavlink's strict config: defaults, shipped files, overrides, refusals."""

from __future__ import annotations

from pathlib import Path

import pytest

from dronewrapper.runtime.config import ConfigError, load_config
from dronewrapper_bridge_mavlink.__main__ import _configure
from dronewrapper_bridge_mavlink.config import Config
from dronewrapper_bridge_mavlink.link import network_exposure

CONFIG_DIR = (
    Path(__file__).resolve().parents[2]
    / "services/bridge_mavlink/dronewrapper_bridge_mavlink"
    / "config"
)


def test_defaults_match_the_contract():
    c = Config()
    assert c.connection == "udpin:127.0.0.1:14540"
    assert (c.setpoint_timeout, c.commander_lost_timeout, c.commander_lost_action) == (
        0.5, 5.0, "land",
    )  # fmt: skip
    assert c.heartbeat_timeout == 3.0 and c.stream_rate_hz >= 20 and c.offboard_prime_s > 1.0
    assert c.heartbeat_type == 6  # GCS, so PX4 sends STATUSTEXT


@pytest.mark.parametrize("path", sorted(CONFIG_DIR.glob("*.yaml")), ids=lambda p: p.name)
def test_shipped_configs_load(path):
    assert isinstance(load_config(Config, path), Config)


def test_overrides_and_cli_flags():
    overrides: list[str] = []

    class Args:
        connection = "tcp:127.0.0.1:5760"
        baud = 921600

    _configure(Args(), overrides)
    c = load_config(Config, None, [*overrides, "limits.max_horizontal_speed=5"])
    assert (c.connection, c.baud, c.limits.max_horizontal_speed) == ("tcp:127.0.0.1:5760",
                                                                      921600, 5.0)  # fmt: skip


@pytest.mark.parametrize(
    ("override", "message"),
    [
        ("commander_lost_action=panic", "commander_lost_action"),
        ("setpoint_timeout=9", "setpoint_timeout"),
        ("stream_rate_hz=5", "stream_rate_hz"),
        ("command_attempts=0", "attempts"),
        ("no_such_key=1", "no_such_key"),
        ("limits.max_speed=3", "max_speed"),
        ("baud=fast", "baud"),
        ("final_ack_timeout=0", "final_ack_timeout"),
        ("mode_confirm_timeout=nan", "mode_confirm_timeout"),
    ],
)
def test_bad_config_refused_naming_the_key(override, message):
    with pytest.raises(ConfigError, match=message):
        load_config(Config, None, [override])


def test_the_default_autopilot_link_is_loopback():
    assert Config().connection == "udpin:127.0.0.1:14540"
    assert network_exposure(Config().connection) is None


@pytest.mark.parametrize(
    ("url", "exposed"),
    [
        ("udpin:127.0.0.1:14540", False),
        ("udpin:localhost:14540", False),
        ("tcp:[::1]:5760", False),
        ("/dev/ttyACM0", False),
        ("udpin:0.0.0.0:14540", True),
        ("udpout:192.168.1.20:14550", True),
        ("tcp:drone.local:5760", True),
    ],
)
def test_a_link_beyond_loopback_is_recognised(url, exposed):
    assert (network_exposure(url) is not None) == exposed
