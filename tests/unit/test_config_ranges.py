"""Ranges declared on a config's type (``msgspec.Meta``): the error names the key as the user wrote
it, the allowed range and the value; a config built in code is held to the same range; ``--help``
shows it."""

from __future__ import annotations

from typing import Annotated, Literal

import msgspec
import pytest

from dronewrapper.runtime.config import ConfigError, load_config
from dronewrapper.runtime.config_help import config_help
from dronewrapper.runtime.config_ranges import Positive, check_ranges


class Gains(msgspec.Struct, kw_only=True, forbid_unknown_fields=True):
    kp: float = 0.0
    out_limit: Positive = 1.0

    def __post_init__(self) -> None:
        check_ranges(self, "PID ")


class Band(msgspec.Struct, kw_only=True, forbid_unknown_fields=True):
    low: Annotated[int, msgspec.Meta(ge=0, le=255)] = 0


class Cfg(msgspec.Struct, kw_only=True, forbid_unknown_fields=True):
    """A schema with ranges.

    Attributes:
        wait_ready: how long to wait (s).
    """

    wait_ready: Annotated[float, msgspec.Meta(ge=0, le=600)] = 0.0
    late_s: Annotated[float, msgspec.Meta(gt=0, le=5)] = 0.3
    attempts: Annotated[int, msgspec.Meta(ge=1)] = 3
    width: Annotated[int, msgspec.Meta(ge=16, multiple_of=2)] | None = None
    on_exit: Literal["stop", "land"] = "land"
    host: Annotated[str, msgspec.Meta(min_length=1)] = "127.0.0.1"
    gains: Gains = msgspec.field(default_factory=Gains)
    bands: list[Band] = msgspec.field(default_factory=list)
    rates: dict[str, Positive] = msgspec.field(default_factory=dict)

    def __post_init__(self) -> None:
        check_ranges(self)


@pytest.mark.parametrize(
    ("override", "words"),
    [
        ("wait_ready=700", "wait_ready must be in [0, 600], got 700"),
        ("late_s=0", "late_s must be in (0, 5], got 0"),
        ("attempts=0", "attempts must be >= 1, got 0"),
        ("width=17", "width must be >= 16 and a multiple of 2, got 17"),
        ("on_exit=crash", "on_exit must be one of land, stop, got 'crash'"),
        ("host=''", "host must be not empty, got ''"),
        ("gains.out_limit=-1", "gains.out_limit must be > 0, got -1"),  # a nested key
        ("bands=[{low: 1}, {low: 300}]", "bands[1].low must be in [0, 255], got 300"),
        ("rates={a: 1, b: 0}", "rates.b must be > 0, got 0"),  # msgspec names no mapping key
    ],
)
def test_a_value_out_of_range_names_the_key_the_range_and_the_value(override, words):
    with pytest.raises(ConfigError) as error:
        load_config(Cfg, None, [override])
    assert str(error.value) == f"config (with overrides): {words}"


def test_the_file_is_named_and_the_nested_key_is_dotted(tmp_path):
    path = tmp_path / "bad.yaml"
    path.write_text("gains:\n  out_limit: 0\n")
    with pytest.raises(ConfigError) as error:
        load_config(Cfg, path)
    assert str(error.value) == f"{path}: gains.out_limit must be > 0, got 0"
    assert "$." not in str(error.value)


def test_values_inside_the_range_and_the_other_errors_keep_their_words():
    cfg = load_config(Cfg, None, ["wait_ready=600", "late_s=5", "width=16", "gains.out_limit=2"])
    assert (cfg.wait_ready, cfg.late_s, cfg.width, cfg.gains.out_limit) == (600, 5, 16, 2)
    with pytest.raises(ConfigError, match=r"unknown field `kpp` - at `\$\.gains`"):
        load_config(Cfg, None, ["gains.kpp=1"])
    with pytest.raises(ConfigError, match=r"Expected `float`, got `str` - at `\$\.wait_ready`"):
        load_config(Cfg, None, ["wait_ready=soon"])


@pytest.mark.parametrize("bad", [float("nan"), -1.0, 0.0])
def test_a_config_built_in_code_is_held_to_the_same_range(bad):
    with pytest.raises(ValueError, match=r"^PID out_limit must be > 0, got "):
        Gains(out_limit=bad)
    with pytest.raises(ValueError, match=r"^wait_ready must be in \[0, 600\], got "):
        Cfg(wait_ready=bad - 1)
    with pytest.raises(ValueError, match="on_exit must be one of land, stop"):
        Cfg(on_exit="crash")  # type: ignore[arg-type]
    assert Cfg(width=None).width is None  # an optional value may be absent


def test_help_shows_the_range_after_what_the_key_is():
    text = config_help(Cfg)
    assert "  wait_ready = 0.0\n      how long to wait (s). Must be in [0, 600].\n" in text
    assert "  gains.out_limit = 1.0\n      Must be > 0.\n" in text
    assert "  gains.kp = 0.0\n  " in text  # no range, no words


def test_the_services_ranges_read_as_the_user_wrote_them():
    from dronewrapper_bridge_tello.config import Config as TelloBridgeConfig
    from dronewrapper_controller.config import Config as ControllerConfig
    from dronewrapper_sim.config import SimConfig

    with pytest.raises(ConfigError, match=r"takeoff\.wait_ready must be in \[0, 600\], got 700$"):
        load_config(ControllerConfig, None, ["takeoff.wait_ready=700"])
    with pytest.raises(ConfigError, match=r"vz\.out_limit must be > 0, got 0$"):
        load_config(ControllerConfig, None, ["vz.out_limit=0"])
    with pytest.raises(ConfigError, match=r"tello\.auto_land_s must be in \[1, 3600\], got 0\.5$"):
        load_config(SimConfig, None, ["tello.auto_land_s=0.5"])
    with pytest.raises(ConfigError, match=r"scale\.max_stick must be in \[1, 100\], got 300$"):
        load_config(TelloBridgeConfig, None, ["scale.max_stick=300"])


def test_a_graph_file_names_the_process_key(tmp_path):
    from dronewrapper_compose.graph import GraphError, load_graph

    path = tmp_path / "g.yaml"
    path.write_text("version: 1\nprocesses:\n  - {name: a, module: m, ready: maybe}\n")
    with pytest.raises(GraphError) as error:
        load_graph(path)
    assert str(error.value) == f"{path}: processes[0].ready must be one of alive, none, got 'maybe'"


def test_help_reads_a_base_schemas_words_and_an_attributes_section_with_a_note():
    from dronewrapper_controller.config import Config as ControllerConfig

    text = config_help(ControllerConfig)
    assert '  mode = "follow_color"\n      follow_color or follow_person. Must be one of' in text
    assert "  status_rate_hz = 10.0\n      ControllerStatus publishing rate (Hz, >= 5)." in text
