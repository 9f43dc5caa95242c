"""The simulator's configuration, CLI flags and the PX4 instance rule for ports and ids."""

from __future__ import annotations

import argparse

import pytest

from dronewrapper.runtime.config import ConfigError, load_config
from dronewrapper.runtime.options import options_from_args
from dronewrapper.runtime.service import service_parser
from dronewrapper_sim.cli import add_args, configure
from dronewrapper_sim.config import SimConfig
from dronewrapper_sim.mavlink_io import UdpEndpoint, default_endpoints, parse_udp_spec
from dronewrapper_sim.runner import link_endpoints


def parse(argv: list[str]) -> tuple[argparse.Namespace, SimConfig]:
    parser = service_parser("sim", None)
    add_args(parser)
    args = parser.parse_args(argv)
    overrides = list(args.set)
    configure(args, overrides)
    return args, load_config(SimConfig, None, overrides)


def test_instance_zero_uses_px4_sitl_ports():
    eps = link_endpoints(SimConfig())
    assert eps["onboard"] == UdpEndpoint("127.0.0.1", 14540, 14580)
    assert eps["gcs"] == UdpEndpoint("127.0.0.1", 14550, 18570)


def test_instance_n_shifts_ports_sysid_and_namespace_like_px4_i(monkeypatch):
    monkeypatch.delenv("DRONEWRAPPER_NAMESPACE", raising=False)
    eps = default_endpoints(2)
    assert eps["onboard"] == UdpEndpoint("127.0.0.1", 14542, 14582)
    assert eps["gcs"] == UdpEndpoint("127.0.0.1", 14550, 18572)  # GCS listens on 14550
    args, config = parse(["--instance", "2", "--no-cameras"])
    assert config.instance == 2 and not config.cameras
    assert args.namespace == "drone2"
    args, _ = parse(["--instance", "2", "--namespace", "alpha"])
    assert args.namespace == "alpha"  # an explicit namespace wins
    args, _ = parse([])
    assert options_from_args(args).namespace == "drone"


def test_udp_specs():
    assert parse_udp_spec("15000:0", 14580) == UdpEndpoint("127.0.0.1", 15000, 0)
    assert parse_udp_spec("15000", 14580) == UdpEndpoint("127.0.0.1", 15000, 14580)
    assert parse_udp_spec("10.1.2.3:14550", 18570) == UdpEndpoint("10.1.2.3", 14550, 18570)
    assert parse_udp_spec("10.1.2.3:14550:0", 18570) == UdpEndpoint("10.1.2.3", 14550, 0)
    assert parse_udp_spec("off", 1) is None
    for bad in ("nope", "1:2:3:4", "70000", "127.0.0.1:x"):
        with pytest.raises(ValueError):
            parse_udp_spec(bad, 1)


def test_flags_become_config_and_port_strings_stay_strings():
    _, config = parse(
        ["--udp-onboard", "14540:0", "--udp-gcs", "off", "--scenario", "empty", "--seed", "4"]
    )
    assert config.udp_onboard == "14540:0"  # not YAML's base-60 integer
    assert config.udp_gcs == "off"
    assert config.scenario == "empty" and config.seed == 4
    eps = link_endpoints(config)
    assert eps["onboard"] == UdpEndpoint("127.0.0.1", 14540, 0) and eps["gcs"] is None
    _, config = parse(["--camera-rate", "15", "--width", "320", "--height", "240"])
    assert (config.camera_rate_hz, config.width, config.height) == (15.0, 320, 240)


@pytest.mark.parametrize(
    "override",
    [
        "instance=-1",
        "realtime_factor=0",
        "loop_rate_hz=0",
        "jpeg_quality=0",
        "width=4",
        "nonsense=1",
        'udp_onboard="14540:x"',
        'udp_gcs="a:b:c:d"',
    ],
)
def test_bad_config_is_refused_with_the_key_named(override):
    key = override.split("=")[0]
    with pytest.raises(ConfigError, match=key):
        load_config(SimConfig, None, [override])


def test_cli_exit_code_2_for_bad_flags():
    from dronewrapper_sim.cli import main

    assert main(["--udp-onboard", "not-a-port", "--no-cameras"]) == 2
    assert main(["--realtime-factor", "-1"]) == 2
