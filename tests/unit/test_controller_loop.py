"""When the node sends a command, what its status says, and the per-aircraft config files."""

from __future__ import annotations

from pathlib import Path

import pytest

from dronewrapper.msgs.control import (
    CONTROLLER_HOVER,
    CONTROLLER_SEARCH,
    CONTROLLER_TAKEOFF,
    CONTROLLER_TRACKING,
)
from dronewrapper.msgs.std import Header
from dronewrapper.msgs.vision import BoundingBox2D, Detection2D, Detections
from dronewrapper.runtime.config import ConfigError, load_config
from dronewrapper_controller.config import Config, ServoConfig
from dronewrapper_controller.loop import ControlLoop

CONFIG_DIR = (
    Path(__file__).resolve().parents[2] / "services/controller/dronewrapper_controller" / "config"
)


def frame(stamp, *xs):
    dets = [
        Detection2D(
            bbox=BoundingBox2D.at(x, 120, 20, 20),
            circle_radius=8,
        )
        for x in xs
    ]
    return Detections(
        header=Header(stamp=stamp), detections=dets, image_width=320, image_height=240
    )


def test_one_command_per_new_frame_with_its_stamp():
    loop = ControlLoop(ServoConfig())
    first = loop.tick(0.0, frame(1000.0, 100), age=0.0)
    assert first is not None and first.state == CONTROLLER_TRACKING
    assert first.source_stamp == 1000.0
    assert loop.tick(0.03, frame(1000.0, 100), age=0.03) is None  # same frame: nothing new
    second = loop.tick(0.05, frame(1000.05, 110), age=0.0)
    assert second is not None and second.source_stamp == 1000.05
    assert loop.sent_count == 2


def test_hover_and_search_are_sent_once_on_change():
    loop = ControlLoop(ServoConfig(search_delay=1.5, lost_hold=0.3))
    loop.tick(0.0, frame(1.0, 10), age=0.0)  # last seen at the left border: it left the view
    assert loop.tick(0.1, frame(1.1), age=0.0) is None  # a short dropout: the command holds
    hover = loop.tick(0.4, frame(1.4), age=0.0)
    assert hover is not None and hover.state == CONTROLLER_HOVER
    assert loop.tick(0.5, frame(1.5), age=0.0) is None
    search = loop.tick(1.6, frame(2.6), age=0.0)
    assert search is not None and search.state == CONTROLLER_SEARCH
    assert loop.tick(1.7, frame(2.7), age=0.0) is None


def test_status_reports_state_errors_and_last_command():
    loop = ControlLoop(ServoConfig(mode="follow_color"))
    loop.tick(0.0, frame(1000.0, 60), age=0.01)
    st = loop.status(2000.0, seq=4)
    assert st.header.stamp == 2000.0 and st.header.seq == 4
    assert st.mode == "follow_color" and st.state == CONTROLLER_TRACKING and st.target_visible
    assert st.source_stamp == 1000.0 and st.detection_age == pytest.approx(0.01)
    assert st.error_yaw == pytest.approx(100.0) and st.cmd_yaw_rate > 0
    assert st.error_x == pytest.approx(-0.2)


def test_status_phase_override_reports_no_command():
    loop = ControlLoop(ServoConfig())
    st = loop.status(5.0, state=CONTROLLER_TAKEOFF)
    assert st.state == CONTROLLER_TAKEOFF and st.cmd_vx == 0.0 and not st.target_visible


@pytest.mark.parametrize("name", ["iris_sim", "tello", "px4_real"])
def test_aircraft_config_files_load_and_have_sane_signs(name):
    cfg = load_config(Config, CONFIG_DIR / f"{name}.yaml")
    assert cfg.aircraft == name
    assert cfg.follow_color.vx.kp < 0 < cfg.follow_person.vx.kp
    assert cfg.vz.kp > 0 and cfg.yaw_rate.kp > 0
    assert cfg.follow_person.max_forward_error * cfg.follow_person.vx.kp < 2.0
    for gains in (cfg.follow_color.vx, cfg.follow_person.vx, cfg.vz, cfg.yaw_rate):
        assert 0 < gains.out_limit <= 2.0


def test_config_unknown_key_and_bad_values_are_errors():
    with pytest.raises(ConfigError, match="kpp"):
        load_config(Config, None, ["vz.kpp=1"])
    with pytest.raises(ConfigError, match="on_exit"):
        load_config(Config, None, ["on_exit=crash"])
    with pytest.raises(ConfigError, match="status_rate_hz"):
        load_config(Config, None, ["status_rate_hz=1"])
    with pytest.raises(ConfigError, match="max_forward_error"):
        load_config(Config, None, ["follow_person.max_forward_error=0"])
