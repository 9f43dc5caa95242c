"""The perception service's configuration (strict: unknown keys are errors).

Every field can be set in a YAML/JSON file (``--config``) or on the command line
(``--set detector=yolox --set model_path=/models/yolox_nano.onnx``).
"""

from __future__ import annotations

import sys
from typing import Annotated, Literal, get_args

import msgspec

from dronewrapper.runtime.config_ranges import Share, check_ranges
from dronewrapper_perception.color_filter import PRESETS, ColorRange
from dronewrapper_perception.providers import check_names
from dronewrapper_perception.tracking import TRACKERS
from dronewrapper_perception.yolox import class_ids_for

Detector = Literal["color", "yolox", "hog", "person"]
DETECTORS: tuple[str, ...] = get_args(Detector)


class ColorRangeConfig(msgspec.Struct, forbid_unknown_fields=True, kw_only=True):
    """One HSV range. Hue in OpenCV units 0..179 (``hue_unit: opencv``) or degrees 0..360
    (``hue_unit: degrees``, as the paper's tables); ``h_min > h_max`` wraps through 0."""

    h_min: float
    h_max: float
    s_min: int = 70
    s_max: int = 255
    v_min: int = 50
    v_max: int = 255
    hue_unit: Literal["opencv", "degrees"] = "opencv"

    def __post_init__(self) -> None:
        check_ranges(self)

    def to_range(self) -> ColorRange:
        if self.hue_unit == "degrees":
            return ColorRange.from_degrees(
                self.h_min, self.h_max, self.s_min, self.s_max, self.v_min, self.v_max
            )
        return ColorRange(
            int(self.h_min), int(self.h_max), self.s_min, self.s_max, self.v_min, self.v_max
        )


class Config(msgspec.Struct, forbid_unknown_fields=True, kw_only=True):
    """Perception settings.

    Attributes:
        camera: camera name in the image key (``cam_frontal`` or ``cam_ventral``).
        compressed: subscribe to the JPEG key instead of the raw bgr8 one.
        detector: ``color`` | ``yolox`` | ``hog`` | ``person`` (= yolox when ``model_path`` is
            set, else the zero-download HOG).
        color_preset: named colour (``red``, ``green``, ``blue``, ``yellow``).
        color_ranges: custom HSV ranges; when given they replace the preset.
        blur_px: Gaussian blur kernel of the colour filter (odd px, 0 = none).
        min_area_px: smallest colour blob kept (px²).
        color_scale: the colour filter works on the frame shrunk by this factor, in (0, 1]
            (0.5: a quarter of the work, about a pixel of precision; 1: full resolution).
        model_path: the YOLOX ``.onnx`` file (no default: obtain it, see README).
        checksum: expected sha256 of ``model_path``, verified at start when set.
        input_size: YOLOX network input side (px), if the model does not fix it.
        score_threshold: minimum detection score 0..1 (YOLOX obj*cls; HOG mapped margin).
        nms_threshold: IoU for non-maximum suppression 0..1.
        classes: COCO class names kept by YOLOX (``person``, ``car``, ``horse``...).
        threads: CPU threads for one YOLOX inference.
        thread_spinning: let onnxruntime threads busy-wait (faster only on idle, dedicated cores).
        providers: onnxruntime execution providers in order (``cpu``, ``cuda``, ``tensorrt``,
            ``auto`` or full names); a list or one comma-separated string; empty = CPU. One that
            cannot be had is skipped with a warning saying why (the CPU runs the model).
        providers_strict: refuse to start instead of falling back to the CPU when a requested
            GPU provider cannot be had (``auto``: when none can).
        tracker: ``kalman`` (motion + appearance) | ``paper`` (the paper's FIFO) | ``none``.
        max_coast_s: seconds a Kalman track survives without detections.
        paper_fifo_length: centroids in the paper tracker's FIFO.
        paper_gate_px: the paper tracker ignores detections farther than this from its mean.
        max_detections: detections kept per frame (best first).
        max_rate_hz: detect on at most this many frames per second of camera time (frame
            stamps), skipping the frames in between (0 = every frame the loop can take). A
            slower detection rate leaves CPU to the rest of the graph; the tracker reasons in
            seconds, so identity holds at any rate (see the README's figures).
        debug_image: publish an annotated JPEG for people to watch.
        debug_jpeg_quality: JPEG quality 1..100 of the debug image.
        stats_period_s: how often counters are logged (s; 0 = never).
    """

    camera: str = "cam_frontal"
    compressed: bool = False
    detector: Detector = "color"
    color_preset: str = "red"
    color_ranges: list[ColorRangeConfig] = msgspec.field(default_factory=list)
    blur_px: Annotated[int, msgspec.Meta(ge=0)] = 11
    min_area_px: float = 20.0
    color_scale: Annotated[float, msgspec.Meta(gt=0, le=1)] = 0.5
    model_path: str = ""
    checksum: str = ""
    input_size: Annotated[int, msgspec.Meta(ge=32, multiple_of=32)] = 416
    score_threshold: Share = 0.3
    nms_threshold: Share = 0.45
    classes: list[str] = msgspec.field(default_factory=lambda: ["person"])
    threads: Annotated[int, msgspec.Meta(ge=1)] = 2
    thread_spinning: bool = False
    providers: list[str] | str = msgspec.field(default_factory=list)
    providers_strict: bool = False
    tracker: str = "kalman"
    max_coast_s: float = 2.0
    paper_fifo_length: Annotated[int, msgspec.Meta(ge=1)] = 5
    paper_gate_px: float = 120.0
    max_detections: Annotated[int, msgspec.Meta(ge=1)] = 50
    max_rate_hz: Annotated[float, msgspec.Meta(ge=0, le=sys.float_info.max)] = 0.0
    debug_image: bool = False
    debug_jpeg_quality: Annotated[int, msgspec.Meta(ge=1, le=100)] = 80
    stats_period_s: float = 10.0

    def __post_init__(self) -> None:
        check_ranges(self)
        if self.tracker not in TRACKERS:
            raise ValueError(f"tracker must be one of {', '.join(TRACKERS)}, not {self.tracker!r}")
        if not self.color_ranges and self.color_preset not in PRESETS:
            raise ValueError(
                f"color_preset {self.color_preset!r} unknown (known: {', '.join(sorted(PRESETS))})"
            )
        for colour_range in self.color_ranges:
            colour_range.to_range()  # raises ValueError with the bad field named
        if self.blur_px > 1 and self.blur_px % 2 == 0:  # 0, 1 or odd: beyond a Meta's words
            raise ValueError(f"blur_px={self.blur_px} must be 0 or an odd number of px")
        class_ids_for(self.classes)  # unknown class names fail here
        try:
            check_names(self.provider_list())
        except ValueError as exc:
            raise ValueError(f"providers: {exc}") from exc

    def provider_list(self) -> list[str]:
        """``providers`` as a list of names (a string is split at commas)."""
        if isinstance(self.providers, str):
            return [p.strip() for p in self.providers.split(",") if p.strip()]
        return list(self.providers)

    def color_ranges_resolved(self) -> tuple[ColorRange, ...]:
        """The HSV ranges to use: the custom ones, else the preset's."""
        if self.color_ranges:
            return tuple(r.to_range() for r in self.color_ranges)
        return PRESETS[self.color_preset]

    def color_label(self) -> str:
        """The class name reported for colour blobs."""
        return "custom" if self.color_ranges else self.color_preset

    def detector_kind(self) -> str:
        """The concrete detector: ``person`` resolves to yolox (model set) or hog."""
        if self.detector == "person":
            return "yolox" if self.model_path else "hog"
        return self.detector
