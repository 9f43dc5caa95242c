"""Config validation, the Detections message, HOG, and the ``dronewrapper detect`` command."""

from __future__ import annotations

import json

import cv2
import numpy as np
import pytest

from dronewrapper.msgs import Detections
from dronewrapper.runtime.config import ConfigError, load_config
from dronewrapper_perception.color_filter import RED
from dronewrapper_perception.config import Config
from dronewrapper_perception.detect_cli import main as detect_main
from dronewrapper_perception.detectors import ColorDetector
from dronewrapper_perception.hog import HogDetector
from dronewrapper_perception.pipeline import Pipeline, annotate, encode_jpeg, to_message
from dronewrapper_perception.yolox import YoloxDetector
from dronewrapper_sim.evaluation.boxes import iou
from support import ASSETS, YOLOX_NANO

IMAGES = ASSETS / "images"


def test_config_defaults_and_errors(tmp_path):
    config = load_config(Config)
    assert (config.detector, config.tracker, config.camera) == ("color", "kalman", "cam_frontal")
    assert config.detector_kind() == "color"
    assert load_config(Config, overrides=["detector=person"]).detector_kind() == "hog"
    person = load_config(Config, overrides=["detector=person", "model_path=/m.onnx"])
    assert person.detector_kind() == "yolox"
    assert load_config(Config, overrides=["providers=cuda, cpu"]).provider_list() == ["cuda", "cpu"]
    as_list = load_config(Config, overrides=["providers=[TensorrtExecutionProvider, cuda]"])
    assert as_list.provider_list() == ["TensorrtExecutionProvider", "cuda"]
    assert load_config(Config).provider_list() == []
    bad = tmp_path / "perception.yaml"
    bad.write_text("detector: color\nthreshold: 0.5\n")
    with pytest.raises(ConfigError, match="threshold"):
        load_config(Config, bad)
    for override, words in [
        ("detector=sonar", "detector"),
        ("tracker=magic", "tracker"),
        ("classes=[unicorn]", "unknown class"),
        ("color_preset=mauve", "color_preset"),
        ("blur_px=4", "blur_px"),
        ("color_scale=0", "color_scale"),
        ("color_scale=1.5", "color_scale"),
        ("score_threshold=2", "score_threshold"),
    ]:
        with pytest.raises(ConfigError, match=words):
            load_config(Config, overrides=[override])


def test_custom_ranges_in_degrees_replace_the_preset():
    config = load_config(
        Config,
        data={"color_ranges": [{"h_min": 340, "h_max": 10, "hue_unit": "degrees"}]},
    )
    (colour_range,) = config.color_ranges_resolved()
    assert (colour_range.h_min, colour_range.h_max, colour_range.wraps) == (170, 5, True)
    assert config.color_label() == "custom"


def test_color_message_carries_stamp_size_centroid_and_radius():
    img = np.full((480, 640, 3), (80, 120, 70), np.uint8)
    cv2.circle(img, (200, 150), 30, (0, 0, 230), -1)
    cv2.circle(img, (500, 350), 12, (0, 0, 230), -1)
    pipeline = Pipeline(load_config(Config))
    result = pipeline.process(img, 100.0)
    msg = to_message(result, stamp=1234.5, frame_id="cam_frontal", detector="color", seq=7)
    assert isinstance(msg, Detections)
    assert msg.header.stamp == 1234.5 and msg.header.frame_id == "cam_frontal"
    assert (msg.image_width, msg.image_height, msg.detector) == (640, 480, "color")
    assert len(msg.detections) == 2
    first = msg.detections[0]
    assert first.bbox.center.position.x == pytest.approx(200, abs=1)
    assert first.bbox.center.position.y == pytest.approx(150, abs=1)
    assert first.circle_radius == pytest.approx(30, abs=2)
    assert first.results[0].hypothesis.class_id == "red"
    assert msg.target_id == first.id != ""
    assert msg.target() is first
    assert msg.processing_time > 0
    jpeg = encode_jpeg(annotate(img, result))
    assert cv2.imdecode(np.frombuffer(jpeg, np.uint8), cv2.IMREAD_COLOR).shape == img.shape


def test_empty_frame_message_has_no_target():
    pipeline = Pipeline(load_config(Config))
    msg = to_message(
        pipeline.process(np.zeros((240, 320, 3), np.uint8), 0.0),
        stamp=5.0,
        frame_id="cam_ventral",
        detector="color",
    )
    assert msg.detections == [] and msg.target_id == "" and msg.target() is None
    assert (msg.image_width, msg.image_height) == (320, 240)


def test_hog_finds_the_person_yolox_finds():
    img = cv2.imread(str(IMAGES / "person.jpg"))
    hog = HogDetector().detect(img)
    (reference,) = YoloxDetector(YOLOX_NANO).detect(img)
    assert hog and hog[0].class_name == "person"
    assert iou(hog[0].box_xyxy, reference.box_xyxy) > 0.3
    assert HogDetector().detect(np.full((480, 640, 3), 128, np.uint8)) == []


def test_detect_cli_image_json(capsys):
    code = detect_main([str(IMAGES / "basketball1.png"), "--model", str(YOLOX_NANO), "--json"])
    assert code == 0
    (line,) = capsys.readouterr().out.strip().splitlines()
    record = json.loads(line)
    assert record["detector"] == "yolox" and len(record["detections"]) == 2
    assert record["image_width"] == 640 and record["target_id"]


def test_detect_cli_video_tracks_across_frames(capsys):
    video = ASSETS / "video" / "vtest.avi"
    code = detect_main([str(video), "--model", str(YOLOX_NANO), "--max-frames", "4", "--json"])
    assert code == 0
    records = [json.loads(line) for line in capsys.readouterr().out.strip().splitlines()]
    assert [r["frame"] for r in records] == [0, 1, 2, 3]
    assert records[1]["t"] == pytest.approx(0.1, abs=0.01)  # 10 fps video
    targets = {r["target_id"] for r in records}
    assert len(targets) == 1 and targets != {""}  # the same person followed


def test_detect_cli_errors(tmp_path, capsys):
    assert detect_main([str(tmp_path / "missing.png")]) == 2
    missing = tmp_path / "yolox_nano.onnx"
    assert detect_main([str(IMAGES / "person.jpg"), "--model", str(missing)]) == 2
    err = capsys.readouterr().err
    assert str(missing) in err and "does not exist" in err  # says where to get the weights
    assert detect_main([str(IMAGES / "person.jpg"), "--detector", "hog", "--model", "m.onnx"]) == 2
    junk = tmp_path / "junk.png"
    junk.write_bytes(b"nope")
    assert detect_main([str(junk)]) == 2
    assert detect_main([str(IMAGES / "person.jpg"), "--detector", "hog", "--color", "mauve"]) == 2


@pytest.mark.parametrize("argv", [[], ["--detector", "yolox"], ["--detector", "person"]])
def test_detect_finds_the_person_with_the_shipped_model_and_says_so(argv, capsys):
    """No flags, ``yolox`` or ``person``: YOLOX with the model in the assets, named on stderr."""
    assert detect_main([str(IMAGES / "person.jpg"), *argv]) == 0
    out, err = capsys.readouterr()
    said = f"detector: yolox, model {ASSETS / 'models' / 'yolox_nano.onnx'} (classes: person)"
    assert said in err.splitlines()
    assert "1 found" in out and " person 0.8" in out


def test_detect_names_the_other_detectors(capsys):
    assert detect_main([str(IMAGES / "person.jpg"), "--detector", "color"]) == 0
    assert "detector: color, preset red" in capsys.readouterr().err.splitlines()
    assert detect_main([str(IMAGES / "person.jpg"), "--detector", "hog"]) == 0
    err = capsys.readouterr().err
    assert "detector: hog, OpenCV's default people detector (no model file)" in err.splitlines()


class CountingDetector(ColorDetector):
    """The real colour detector, counting its calls."""

    calls = 0

    def detect(self, bgr):
        self.calls += 1
        return super().detect(bgr)


def test_detector_runs_once_per_frame_even_with_the_debug_image():
    """The seed ran YOLO twice per frame (once to draw, once to steer)."""
    detector = CountingDetector(RED)
    pipeline = Pipeline(load_config(Config), detector=detector)
    img = np.full((240, 320, 3), 90, np.uint8)
    cv2.circle(img, (100, 100), 20, (0, 0, 230), -1)
    result = pipeline.process(img, 0.0)
    to_message(result, stamp=0.0, frame_id="c", detector="color")
    annotate(img, result)
    assert detector.calls == 1
