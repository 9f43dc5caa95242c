"""Strict config schemas: errors name the file and the key; overrides and zenoh options."""

from __future__ import annotations

import argparse

import msgspec
import pytest

from dronewrapper.runtime import ZenohOptions, add_zenoh_args, options_from_args, zenoh_config
from dronewrapper.runtime.config import ConfigError, load_config
from dronewrapper.runtime.node import Publisher
from dronewrapper.runtime.options import (
    LOW_LATENCY_MAX_BYTES,
    LOW_LATENCY_RUNTIME,
    zenoh_runtime_env,
)


class Pid(msgspec.Struct, forbid_unknown_fields=True):
    kp: float = 0.0
    ki: float = 0.0


class Cfg(msgspec.Struct, forbid_unknown_fields=True):
    rate_hz: float = 30.0
    detector: str = "color"
    pid: Pid = msgspec.field(default_factory=Pid)


def test_defaults_file_and_overrides(tmp_path):
    path = tmp_path / "c.yaml"
    path.write_text("rate_hz: 15\npid:\n  kp: 0.5\n")
    cfg = load_config(Cfg, path, ["pid.ki=0.25", "detector=yolox"])
    assert cfg == Cfg(rate_hz=15.0, detector="yolox", pid=Pid(kp=0.5, ki=0.25))
    assert load_config(Cfg) == Cfg()


def test_unknown_key_names_file_and_key(tmp_path):
    path = tmp_path / "bad.yaml"
    path.write_text("pid:\n  kpp: 1\n")
    with pytest.raises(ConfigError, match=r"bad\.yaml.*unknown field `kpp`.*\$\.pid"):
        load_config(Cfg, path)


def test_wrong_type_names_the_key(tmp_path):
    path = tmp_path / "bad.yaml"
    path.write_text("rate_hz: fast\n")
    with pytest.raises(ConfigError, match=r"bad\.yaml.*\$\.rate_hz"):
        load_config(Cfg, path)


@pytest.mark.parametrize(
    ("text", "message"),
    [("- a\n- b\n", "mapping"), ("a: [\n", "YAML")],
)
def test_malformed_files(tmp_path, text, message):
    path = tmp_path / "c.yaml"
    path.write_text(text)
    with pytest.raises(ConfigError, match=message):
        load_config(Cfg, path)


def test_missing_file_and_bad_override(tmp_path):
    with pytest.raises(ConfigError, match="cannot read"):
        load_config(Cfg, tmp_path / "nope.yaml")
    with pytest.raises(ConfigError, match="KEY=VALUE"):
        load_config(Cfg, None, ["rate_hz"])


def test_zenoh_flags_and_environment(monkeypatch):
    parser = argparse.ArgumentParser()
    add_zenoh_args(parser)
    monkeypatch.setenv("DRONEWRAPPER_CONNECT", "tcp/10.0.0.2:7447, tcp/127.0.0.1:7448")
    monkeypatch.setenv("DRONEWRAPPER_NAMESPACE", "drone3")
    args = parser.parse_args([])
    opts = options_from_args(args, name="perception")
    assert opts.connect == ["tcp/10.0.0.2:7447", "tcp/127.0.0.1:7448"]
    assert opts.namespace == "drone3" and opts.name == "perception" and opts.mode == "peer"
    args = parser.parse_args(["--connect", "tcp/127.0.0.1:9", "--mode", "client", "--ns", "d1"])
    opts = options_from_args(args)
    assert (opts.connect, opts.mode, opts.namespace) == (["tcp/127.0.0.1:9"], "client", "d1")


def test_session_config_is_explicit_and_loopback():
    conf = zenoh_config(ZenohOptions(mode="peer", connect=["tcp/127.0.0.1:7447"]))
    assert conf.get_json("scouting/multicast/enabled") == "false"
    assert conf.get_json("listen/endpoints") == '["tcp/127.0.0.1:0"]'
    assert conf.get_json("connect/endpoints") == '["tcp/127.0.0.1:7447"]'


def test_a_router_opens_without_waiting_to_scout():
    """Nothing to scout with multicast off: a router (every graph starts one) opens at once."""
    conf = zenoh_config(ZenohOptions(mode="router", listen=["tcp/127.0.0.1:7447"]))
    assert conf.get_json("scouting/delay") == "0"


@pytest.mark.parametrize(
    "kwargs", [{"mode": "mesh"}, {"namespace": "a/b"}, {"connect": ["localhost"]}]
)
def test_bad_zenoh_options(kwargs):
    with pytest.raises(ValueError):
        ZenohOptions(**kwargs)


def test_low_latency_asks_for_the_low_latency_transport_without_qos():
    plain = zenoh_config(ZenohOptions(mode="peer"))
    assert plain.get_json("transport/unicast/lowlatency") == "false"
    assert plain.get_json("transport/unicast/qos/enabled") == "true"
    fast = zenoh_config(ZenohOptions(mode="peer", low_latency=True))
    assert fast.get_json("transport/unicast/lowlatency") == "true"
    assert fast.get_json("transport/unicast/qos/enabled") == "false"


def test_low_latency_is_refused_on_a_session_that_leaves_the_machine():
    """A slow link needs priorities (control before camera frames), which it turns off."""
    with pytest.raises(ValueError, match=r"low_latency.*tls/192\.168\.1\.50:7447"):
        ZenohOptions(connect=["tls/192.168.1.50:7447"], low_latency=True)
    with pytest.raises(ValueError, match="low_latency"):
        ZenohOptions(connect=[], listen=["tcp/0.0.0.0:7448"], low_latency=True)


def test_low_latency_flag_and_environment(monkeypatch):
    parser = argparse.ArgumentParser()
    add_zenoh_args(parser)
    assert not options_from_args(parser.parse_args([])).low_latency
    assert options_from_args(parser.parse_args(["--low-latency"])).low_latency
    monkeypatch.setenv("DRONEWRAPPER_LOW_LATENCY", "1")
    assert options_from_args(parser.parse_args([])).low_latency


def test_a_low_latency_peer_takes_one_receive_thread_unless_told_otherwise():
    fast = ZenohOptions(mode="peer", low_latency=True)
    assert zenoh_runtime_env(fast, {}) == {"ZENOH_RUNTIME": LOW_LATENCY_RUNTIME}
    assert zenoh_runtime_env(fast, {"ZENOH_RUNTIME": "(rx: (worker_threads: 3))"}) == {}
    assert zenoh_runtime_env(ZenohOptions(mode="peer"), {}) == {}
    router = ZenohOptions(mode="router", listen=["tcp/127.0.0.1:7447"], low_latency=True)
    assert zenoh_runtime_env(router, {}) == {}


class _Declared:
    """What a Zenoh session's publisher is to Publisher: a ``put`` (recorded)."""

    def __init__(self) -> None:
        self.puts: list[bytes] = []

    def put(self, payload: bytes, **_kw: object) -> None:
        self.puts.append(payload)


class _Session:
    def __init__(self) -> None:
        self.declared = _Declared()

    def declare_publisher(self, _key: str, **_kw: object) -> _Declared:
        return self.declared


def test_a_low_latency_publisher_refuses_what_the_transport_would_drop():
    """The low-latency transport does not fragment: a payload over one batch outside shared
    memory would vanish without a word, so it is refused; a small one goes."""
    from dronewrapper.msgs import CompressedImage, Header

    session = _Session()
    pub = Publisher(session, "drone/cam", CompressedImage, max_bytes=LOW_LATENCY_MAX_BYTES)
    pub.put(CompressedImage(header=Header(), format="jpeg", data=bytes(1000)))
    with pytest.raises(ValueError, match="over the 64000 bytes a low-latency session carries"):
        pub.put(CompressedImage(header=Header(), format="jpeg", data=bytes(70_000)))
    assert len(session.declared.puts) == 1 and pub.count == 1
    unlimited = Publisher(_Session(), "drone/cam", CompressedImage)
    unlimited.put(CompressedImage(header=Header(), format="jpeg", data=bytes(70_000)))
