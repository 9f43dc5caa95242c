"""``dronewrapper detect FILE``: run perception offline on an image or a video.

    dronewrapper detect photo.jpg                         # YOLOX-Nano, the model that ships
    dronewrapper detect clip.avi --detector color --json --max-frames 100
    dronewrapper detect photo.jpg --model m.onnx --classes person horse
    dronewrapper detect photo.jpg --detector hog          # OpenCV's HOG people detector

The detector is YOLOX unless ``--detector`` names another (``person`` is YOLOX too), with the
model that ships in the assets (``assets/models/yolox_nano.onnx``, or ``$DRONEWRAPPER_ASSETS``)
unless ``--model`` names one. Which detector and model ran is said first, on stderr. Prints one
line per frame (with ``--json``: one JSON object per frame, the Detections message as plain
data). Video frames are stamped with their position in the video (s), so tracking behaves as
it would live. Exit status 0, or 2 for a bad file, model or option.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
from collections.abc import Iterator, Sequence
from pathlib import Path

import cv2
import numpy as np

from dronewrapper.msgs import to_builtins
from dronewrapper.runtime.arguments import CommandParser
from dronewrapper.runtime.config import ConfigError, load_config
from dronewrapper_perception.config import DETECTORS, Config
from dronewrapper_perception.model_file import ModelFileError
from dronewrapper_perception.pipeline import Pipeline, annotate, to_message
from dronewrapper_perception.tracking import TRACKERS

SHIPPED_MODEL = "yolox_nano.onnx"
"""The YOLOX model in the assets' ``models/`` (see model_file.BUNDLED_YOLOX_NANO_SHA256)."""
YOLOX_DETECTORS = ("yolox", "person")  # ``person`` here is YOLOX's person class, with a model


def shipped_model() -> Path:
    """The model that ships: ``$DRONEWRAPPER_ASSETS/models/``, else the repository's assets."""
    assets = os.environ.get("DRONEWRAPPER_ASSETS") or Path(__file__).resolve().parents[3] / "assets"
    return Path(assets) / "models" / SHIPPED_MODEL


IMAGE_SUFFIXES = {".png", ".jpg", ".jpeg", ".bmp", ".tif", ".tiff", ".webp", ".ppm", ".pgm"}


def parse_args(argv: Sequence[str] | None) -> argparse.Namespace:
    parser = CommandParser(
        prog="dronewrapper detect", description="run perception on an image or video file"
    )
    parser.add_argument("file", help="image (png, jpg...) or video (avi, mp4...)")
    parser.add_argument(
        "--detector", choices=DETECTORS, help="default yolox (person: yolox's person class)"
    )
    parser.add_argument(
        "--model",
        metavar="PATH",
        help=f"YOLOX .onnx model file (default: the shipped {SHIPPED_MODEL})",
    )
    parser.add_argument("--checksum", metavar="SHA256", help="expected sha256 of the model")
    parser.add_argument("--classes", nargs="+", metavar="NAME", help="COCO classes (yolox)")
    parser.add_argument("--score-threshold", type=float, help="minimum score 0..1")
    parser.add_argument("--color", metavar="PRESET", help="colour preset (red, green, ...)")
    parser.add_argument("--tracker", choices=TRACKERS, help="default kalman")
    parser.add_argument("--config", metavar="FILE", help="perception config file (YAML/JSON)")
    parser.add_argument("--json", action="store_true", help="one JSON object per frame")
    parser.add_argument("--max-frames", type=int, default=0, help="stop after N frames")
    parser.add_argument("--every", type=int, default=1, help="process every Nth video frame")
    parser.add_argument("--save", metavar="DIR", help="write annotated frames to DIR")
    return parser.parse_args(argv)


def config_from_args(args: argparse.Namespace) -> Config:
    data: dict = {}
    detector = args.detector or "yolox"
    data["detector"] = "yolox" if detector in YOLOX_DETECTORS else detector
    if detector in YOLOX_DETECTORS:
        data["model_path"] = args.model or str(shipped_model())
    elif args.model:
        raise ValueError(f"--model is for the yolox detector, not {detector}")
    for key, value in (
        ("checksum", args.checksum),
        ("classes", args.classes),
        ("score_threshold", args.score_threshold),
        ("color_preset", args.color),
        ("tracker", args.tracker),
    ):
        if value is not None:
            data[key] = value
    return load_config(Config, args.config, data=data)


def frames_of(path: Path, every: int = 1) -> Iterator[tuple[int, float, np.ndarray]]:
    """(index, time s, BGR frame) of an image (one frame, t = 0) or of a video's frames.

    Raises:
        ValueError: the file does not exist or cannot be read as an image or a video.
    """
    if not path.is_file():
        raise ValueError(f"{path}: no such file")
    if path.suffix.lower() in IMAGE_SUFFIXES:
        image = cv2.imread(str(path), cv2.IMREAD_COLOR)
        if image is None:
            raise ValueError(f"{path}: cannot read as an image")
        yield 0, 0.0, image
        return
    capture = cv2.VideoCapture(str(path))
    if not capture.isOpened():
        raise ValueError(f"{path}: cannot open as a video")
    fps = capture.get(cv2.CAP_PROP_FPS) or 30.0
    try:
        index = 0
        got_any = False
        while True:
            ok, frame = capture.read()
            if not ok:
                break
            got_any = True
            if index % max(1, every) == 0:
                yield index, index / fps, frame
            index += 1
        if not got_any:
            raise ValueError(f"{path}: no decodable video frames")
    finally:
        capture.release()


def summary_line(index: int, t: float, message) -> str:
    parts = []
    for det in message.detections:
        hyp = det.results[0].hypothesis if det.results else None
        name = hyp.class_id if hyp else "?"
        score = hyp.score if hyp else 0.0
        box = det.bbox
        mark = "*" if det.id and det.id == message.target_id else ""
        parts.append(
            f"{mark}{det.id or '-'} {name} {score:.2f} "
            f"c=({box.center.position.x:.0f},{box.center.position.y:.0f}) "
            f"{box.size_x:.0f}x{box.size_y:.0f}"
        )
    found = "; ".join(parts) if parts else "nothing"
    ms = message.processing_time * 1000
    return f"frame {index} t={t:.2f}s {len(message.detections)} found ({ms:.1f} ms): {found}"


def detector_line(config: Config, name: str) -> str:
    """Which detector ran, and on what: the model file, the colour, or OpenCV's HOG."""
    if name == "yolox":
        classes = ", ".join(config.classes)
        return f"detector: yolox, model {config.model_path} (classes: {classes})"
    if name == "color":
        colour = "custom HSV ranges" if config.color_ranges else f"preset {config.color_preset}"
        return f"detector: color, {colour}"
    if name == "hog":
        return "detector: hog, OpenCV's default people detector (no model file)"
    return f"detector: {name}"


def main(argv: Sequence[str] | None = None) -> int:
    args = parse_args(argv)
    try:
        config = config_from_args(args)
        pipeline = Pipeline(config)
    except (ConfigError, ModelFileError, ValueError) as exc:
        print(f"dronewrapper detect: {exc}", file=sys.stderr)
        return 2
    print(detector_line(config, pipeline.detector_name), file=sys.stderr, flush=True)
    path = Path(args.file)
    save_dir = Path(args.save) if args.save else None
    if save_dir:
        save_dir.mkdir(parents=True, exist_ok=True)
    count = 0
    try:
        for index, t, frame in frames_of(path, args.every):
            result = pipeline.process(frame, t)
            message = to_message(
                result, stamp=t, frame_id=path.name, detector=pipeline.detector_name, seq=index
            )
            if args.json:
                record = {"file": str(path), "frame": index, "t": t, **to_builtins(message)}
                print(json.dumps(record), flush=True)
            else:
                print(summary_line(index, t, message), flush=True)
            if save_dir:
                cv2.imwrite(str(save_dir / f"frame_{index:06d}.jpg"), annotate(frame, result))
            count += 1
            if args.max_frames and count >= args.max_frames:
                break
    except ValueError as exc:
        print(f"dronewrapper detect: {exc}", file=sys.stderr)
        return 2
    except BrokenPipeError:
        return 0
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
