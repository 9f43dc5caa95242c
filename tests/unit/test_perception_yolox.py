"""YOLOX: pure letterbox/grid-decode/NMS helpers on arrays, and the real model on real images."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from dronewrapper_perception.model_file import ModelFileError, sha256_of
from dronewrapper_perception.yolox import (
    COCO_CLASSES,
    YoloxDetector,
    class_ids_for,
    grid_decode,
    letterbox,
    nms,
    postprocess,
    resolve_providers,
)
from support import ASSETS, YOLOX_NANO

IMAGES = ASSETS / "images"
YOLOX_NANO_SHA256 = "3bb7c7746256eca568b2d3f4f934c486f6345bc24154a85bc2bb3f3bbabcf1b1"


@pytest.fixture(scope="module")
def detector() -> YoloxDetector:
    return YoloxDetector(YOLOX_NANO, threads=2)


def test_letterbox_top_left_with_114_fill():
    img = np.full((480, 640, 3), 7, np.uint8)
    canvas, r = letterbox(img, 416)
    assert canvas.shape == (416, 416, 3)
    assert r == pytest.approx(0.65)
    assert (canvas[:312, :416] == 7).all()
    assert (canvas[312:, :] == 114).all()
    tall = np.zeros((800, 200, 3), np.uint8)
    canvas, r = letterbox(tall, 416)
    assert r == pytest.approx(0.52)
    assert (canvas[:, :104] == 0).all() and (canvas[:, 104:] == 114).all()


def test_grid_decode_positions_and_sizes():
    size = 64  # grids 8x8, 4x4, 2x2 = 84 rows
    raw = np.zeros((84, 6), np.float32)
    # stride 8, grid (x=3, y=2): row 2*8+3
    raw[19, :4] = [0.5, 0.25, 0.0, np.log(2.0)]
    # stride 16, grid (x=1, y=3): row 64 + 3*4 + 1
    raw[77, :4] = [0.0, 0.0, np.log(3.0), 0.0]
    # stride 32, grid (x=1, y=0): row 80 + 1
    raw[81, :4] = [0.5, 0.5, 0.0, 0.0]
    out = grid_decode(raw, size)
    assert out[19, :4] == pytest.approx([3.5 * 8, 2.25 * 8, 8, 16])
    assert out[77, :4] == pytest.approx([16, 48, 48, 16])
    assert out[81, :4] == pytest.approx([48, 16, 32, 32])
    with pytest.raises(ValueError):
        grid_decode(np.zeros((83, 6), np.float32), size)


def test_nms_keeps_best_of_overlaps():
    boxes = np.array([[0, 0, 10, 10], [1, 1, 11, 11], [20, 20, 30, 30], [0, 0, 10, 9]], float)
    scores = np.array([0.6, 0.9, 0.5, 0.3])
    assert nms(boxes, scores, 0.45) == [1, 2]
    assert nms(boxes, scores, 0.99) == [1, 0, 2, 3]
    assert nms(np.zeros((0, 4)), np.zeros(0), 0.5) == []


def test_postprocess_scores_classes_and_scaling():
    # two rows at input-px boxes; ratio 0.5 -> source px doubled
    rows = np.zeros((3, 5 + 3), np.float32)
    rows[0, :5] = [100, 100, 40, 80, 0.9]
    rows[0, 5:] = [0.9, 0.1, 0.0]  # person 0.81
    rows[1, :5] = [102, 100, 40, 80, 0.9]
    rows[1, 5:] = [0.5, 0.0, 0.0]  # overlapping person 0.45 -> suppressed
    rows[2, :5] = [101, 100, 40, 80, 0.8]
    rows[2, 5:] = [0.0, 0.0, 0.9]  # another class at the same place: kept class-wise
    names = ("person", "bike", "car")
    dets = postprocess(
        rows, 0.5, (1000, 1000), class_ids=[0, 2], score_threshold=0.3, nms_threshold=0.45,
        class_names=names,
    )  # fmt: skip
    assert [(d.class_name, round(d.score, 2)) for d in dets] == [("person", 0.81), ("car", 0.72)]
    assert dets[0].box_xyxy == pytest.approx((160, 120, 240, 280))
    only_people = postprocess(
        rows, 0.5, (1000, 1000), class_ids=[0], score_threshold=0.3, nms_threshold=0.45,
        class_names=names,
    )  # fmt: skip
    assert [d.class_name for d in only_people] == ["person"]
    # clipped to the image
    clipped = postprocess(
        rows, 0.5, (200, 200), class_ids=[0], score_threshold=0.3, nms_threshold=0.45,
        class_names=names,
    )  # fmt: skip
    assert clipped[0].box_xyxy == pytest.approx((160, 120, 200, 200))


def test_class_names_and_providers():
    assert len(COCO_CLASSES) == 80 and COCO_CLASSES[0] == "person"
    assert class_ids_for(["person", "car", "horse"]) == [0, 2, 17]
    assert class_ids_for([]) == list(range(80))
    with pytest.raises(ValueError, match="unknown class"):
        class_ids_for(["unicorn"])
    available = ["CPUExecutionProvider"]
    assert resolve_providers(None, available) == ["CPUExecutionProvider"]
    assert resolve_providers(["cuda"], available) == ["CPUExecutionProvider"]
    assert resolve_providers(["auto"], [*available, "CUDAExecutionProvider"]) == [
        "CUDAExecutionProvider",
        "CPUExecutionProvider",
    ]


def test_people_on_basketball(detector):
    dets = detector.detect(cv2.imread(str(IMAGES / "basketball1.png")))
    assert len(dets) == 2
    assert all(d.class_name == "person" and d.score > 0.7 for d in dets)
    centres = sorted(d.center_xy[0] for d in dets)
    assert centres[0] < 200 < 400 < centres[1]  # one player on each side


def test_person_jpg_and_other_classes(detector):
    img = cv2.imread(str(IMAGES / "person.jpg"))
    dets = detector.detect(img)
    assert len(dets) == 1 and dets[0].score > 0.7
    x1, y1, x2, y2 = dets[0].box_xyxy
    assert 150 < x1 < x2 < 320 and y2 - y1 > 200  # the standing woman
    animals = YoloxDetector(YOLOX_NANO, classes=("horse", "dog")).detect(img)
    assert {d.class_name for d in animals} == {"horse", "dog"}


def test_several_people_on_vtest(detector):
    dets = detector.detect(cv2.imread(str(IMAGES / "vtest_f0550.png")))
    assert len([d for d in dets if d.score > 0.5]) >= 5
    assert all(d.class_id == 0 for d in dets)


def test_nothing_on_blank_frames(detector):
    assert detector.detect(np.zeros((480, 640, 3), np.uint8)) == []
    assert detector.detect(np.full((480, 640, 3), 200, np.uint8)) == []
    with pytest.raises(ValueError):
        detector.detect(np.zeros((480, 640), np.uint8))


def test_model_checksum_and_missing_file(tmp_path):
    assert sha256_of(YOLOX_NANO) == YOLOX_NANO_SHA256
    YoloxDetector(YOLOX_NANO, checksum=YOLOX_NANO_SHA256)
    with pytest.raises(ModelFileError, match="sha256"):
        YoloxDetector(YOLOX_NANO, checksum="0" * 64)
    with pytest.raises(ModelFileError, match="does not exist"):
        YoloxDetector(tmp_path / "missing.onnx")


def test_a_file_that_is_not_onnx_says_so(tmp_path):
    corrupt = tmp_path / "detector.onnx"
    corrupt.write_bytes(b"<html>404 Not Found</html>" * 40)
    with pytest.raises(ModelFileError, match="is not an ONNX model"):
        YoloxDetector(corrupt)
