"""YOLOX object detection with onnxruntime: letterbox, grid decode, NMS (pure helpers + runner).

The model layout (Megvii's ``yolox_nano.onnx`` export, see the shared assets' SOURCES.md):
input ``[1, 3, S, S]`` float32, BGR, raw 0..255 (no normalisation), the frame letterboxed at
the top-left of an SxS canvas filled with 114; output ``[1, N, 5 + C]`` rows
``[x, y, w, h, obj, cls_0..cls_C-1]`` for the grid points of strides 8, 16, 32 (row-major),
boxes raw (``cx = (x + gx) * s``, ``w = exp(w) * s``), ``obj``/``cls`` already sigmoid-ed.
Score = ``obj * cls``. Boxes come back in source-image pixels.
"""

from __future__ import annotations

import logging
from collections.abc import Iterable, Sequence
from functools import cache
from pathlib import Path

import cv2
import numpy as np

from dronewrapper_perception.detection import Detection
from dronewrapper_perception.model_file import ModelFileError, check_model_file
from dronewrapper_perception.providers import (
    ALIASES,
    ProviderError,
    choose_providers,
    dropped_at_start,
    refusal,
)

__all__ = [
    "COCO_CLASSES",
    "Detection",
    "YoloxDetector",
    "class_ids_for",
    "decode_outputs",
    "grid_decode",
    "letterbox",
    "nms",
    "postprocess",
]

log = logging.getLogger("dronewrapper_perception.yolox")

COCO_CLASSES: tuple[str, ...] = (
    "person", "bicycle", "car", "motorcycle", "airplane", "bus", "train", "truck", "boat",
    "traffic light", "fire hydrant", "stop sign", "parking meter", "bench", "bird", "cat", "dog",
    "horse", "sheep", "cow", "elephant", "bear", "zebra", "giraffe", "backpack", "umbrella",
    "handbag", "tie", "suitcase", "frisbee", "skis", "snowboard", "sports ball", "kite",
    "baseball bat", "baseball glove", "skateboard", "surfboard", "tennis racket", "bottle",
    "wine glass", "cup", "fork", "knife", "spoon", "bowl", "banana", "apple", "sandwich", "orange",
    "broccoli", "carrot", "hot dog", "pizza", "donut", "cake", "chair", "couch", "potted plant",
    "bed", "dining table", "toilet", "tv", "laptop", "mouse", "remote", "keyboard", "cell phone",
    "microwave", "oven", "toaster", "sink", "refrigerator", "book", "clock", "vase", "scissors",
    "teddy bear", "hair drier", "toothbrush",
)  # fmt: skip
"""The 80 COCO class names in YOLOX's order (index = class id; 0 = person)."""

STRIDES = (8, 16, 32)
LETTERBOX_FILL = 114

PROVIDER_ALIASES = ALIASES


def class_ids_for(names: Iterable[str], all_names: Sequence[str] = COCO_CLASSES) -> list[int]:
    """Class ids of ``names`` (empty = every class); ValueError for an unknown name."""
    ids = []
    for name in names:
        if name not in all_names:
            raise ValueError(f"unknown class {name!r}; known classes: {', '.join(all_names)}")
        ids.append(all_names.index(name))
    return ids or list(range(len(all_names)))


def letterbox(bgr: np.ndarray, size: int) -> tuple[np.ndarray, float]:
    """Resize keeping the aspect ratio and paste at the top-left of a ``size``x``size`` canvas.

    Returns:
        (canvas uint8 [size, size, 3] filled with 114, ratio r): a source pixel (x, y) lands at
        (x * r, y * r) on the canvas.
    """
    if bgr.ndim != 3 or bgr.shape[2] != 3 or bgr.shape[0] == 0 or bgr.shape[1] == 0:
        raise ValueError(f"image must be HxWx3 BGR, got shape {bgr.shape}")
    h, w = bgr.shape[:2]
    r = min(size / h, size / w)
    new_w, new_h = min(size, round(w * r)), min(size, round(h * r))
    canvas = np.full((size, size, 3), LETTERBOX_FILL, np.uint8)
    resized = cv2.resize(bgr, (new_w, new_h), interpolation=cv2.INTER_LINEAR)
    canvas[:new_h, :new_w] = resized
    return canvas, r


@cache
def _grids(size: int, strides: tuple[int, ...]) -> tuple[np.ndarray, np.ndarray]:
    grids, expanded = [], []
    for stride in strides:
        n = size // stride
        ys, xs = np.meshgrid(np.arange(n), np.arange(n), indexing="ij")
        grids.append(np.stack((xs, ys), axis=-1).reshape(-1, 2))
        expanded.append(np.full((n * n, 1), stride))
    return (
        np.concatenate(grids).astype(np.float32),
        np.concatenate(expanded).astype(np.float32),
    )


def grid_decode(raw: np.ndarray, size: int, strides: tuple[int, ...] = STRIDES) -> np.ndarray:
    """Decode raw YOLOX rows ``[N, 5+C]`` into centre/size boxes in network-input pixels.

    Row order: strides in order, each row-major over its (size/stride)² grid. Columns 0..3
    become ``cx, cy, w, h`` (input px); the score columns are copied unchanged.
    """
    grid, stride = _grids(size, tuple(strides))
    if raw.ndim != 2 or raw.shape[0] != grid.shape[0]:
        raise ValueError(
            f"expected {grid.shape[0]} rows for input {size} and strides {strides}, "
            f"got shape {raw.shape}"
        )
    out = raw.astype(np.float32, copy=True)
    out[:, :2] = (raw[:, :2] + grid) * stride
    out[:, 2:4] = np.exp(np.minimum(raw[:, 2:4], 20.0)) * stride
    return out


def nms(boxes_xyxy: np.ndarray, scores: np.ndarray, iou_threshold: float) -> list[int]:
    """Greedy non-maximum suppression; indices of the kept boxes, highest score first."""
    if len(boxes_xyxy) == 0:
        return []
    x1, y1, x2, y2 = (boxes_xyxy[:, i] for i in range(4))
    areas = np.maximum(0.0, x2 - x1) * np.maximum(0.0, y2 - y1)
    order = np.argsort(-scores, kind="stable")
    keep: list[int] = []
    while order.size:
        best = int(order[0])
        keep.append(best)
        rest = order[1:]
        ix1 = np.maximum(x1[best], x1[rest])
        iy1 = np.maximum(y1[best], y1[rest])
        ix2 = np.minimum(x2[best], x2[rest])
        iy2 = np.minimum(y2[best], y2[rest])
        inter = np.maximum(0.0, ix2 - ix1) * np.maximum(0.0, iy2 - iy1)
        union = areas[best] + areas[rest] - inter
        iou = np.where(union > 0, inter / np.maximum(union, 1e-12), 0.0)
        order = rest[iou <= iou_threshold]
    return keep


def postprocess(
    decoded: np.ndarray,
    ratio: float,
    image_wh: tuple[int, int],
    *,
    class_ids: Sequence[int],
    score_threshold: float,
    nms_threshold: float,
    class_names: Sequence[str] = COCO_CLASSES,
) -> list[Detection]:
    """Score, filter, class-wise NMS and scale decoded rows back to source pixels.

    Args:
        decoded: ``[N, 5+C]`` rows from :func:`grid_decode` (boxes in input px).
        ratio: the letterbox ratio r (source px * r = input px).
        image_wh: source image (width, height) in px; boxes are clipped to it.
        class_ids: classes to keep.
    Returns:
        detections sorted by score, highest first.
    """
    ids = np.asarray(list(class_ids), dtype=np.int64)
    cls_scores = decoded[:, 5:][:, ids] * decoded[:, 4:5]
    best = np.argmax(cls_scores, axis=1)
    scores = cls_scores[np.arange(len(best)), best]
    mask = scores >= score_threshold
    if not np.any(mask):
        return []
    rows, scores, classes = decoded[mask], scores[mask], ids[best[mask]]
    cx, cy, w, h = (rows[:, i] / ratio for i in range(4))
    boxes = np.stack((cx - w / 2, cy - h / 2, cx + w / 2, cy + h / 2), axis=1)
    width, height = image_wh
    boxes[:, [0, 2]] = np.clip(boxes[:, [0, 2]], 0, width)
    boxes[:, [1, 3]] = np.clip(boxes[:, [1, 3]], 0, height)
    # class-wise NMS in one pass: shift each class's boxes far apart
    offset = classes[:, None].astype(np.float32) * (max(width, height) + 1.0) * 2.0
    keep = nms(boxes + offset, scores, nms_threshold)
    return [
        Detection(
            box_xyxy=tuple(float(v) for v in boxes[i]),  # type: ignore[arg-type]
            score=float(scores[i]),
            class_id=int(classes[i]),
            class_name=class_names[int(classes[i])]
            if int(classes[i]) < len(class_names)
            else str(int(classes[i])),
        )
        for i in keep
    ]


def decode_outputs(
    output: np.ndarray,
    input_size: int,
    ratio: float,
    image_wh: tuple[int, int],
    *,
    class_ids: Sequence[int],
    score_threshold: float,
    nms_threshold: float,
) -> list[Detection]:
    """From the raw model output ``[1, N, 5+C]`` to detections in source pixels."""
    rows = output[0] if output.ndim == 3 else output
    return postprocess(
        grid_decode(rows, input_size),
        ratio,
        image_wh,
        class_ids=class_ids,
        score_threshold=score_threshold,
        nms_threshold=nms_threshold,
    )


def resolve_providers(requested: Sequence[str] | None, available: Sequence[str]) -> list[str]:
    """onnxruntime execution providers to use, always ending with the CPU one (see
    :mod:`dronewrapper_perception.providers`; the ones not in this build are left out)."""
    return list(choose_providers(requested, available).providers)


class YoloxDetector:
    """A YOLOX ONNX model run with onnxruntime.

    Args:
        model_path: the ``.onnx`` file (e.g. Megvii's ``yolox_nano.onnx``).
        input_size: network input side in px (416 for nano/tiny); taken from the model when
            its input shape is static.
        score_threshold: minimum ``obj * cls`` score, 0..1.
        nms_threshold: IoU above which a lower-scored box of the same class is dropped.
        classes: COCO class names to keep (empty = all); default people only.
        providers: onnxruntime execution providers (``cpu``, ``cuda``, ``tensorrt``, ``auto``
            or full names); None = CPU. One that cannot be had is left out with a warning
            saying why, and the model runs on the CPU.
        strict_providers: refuse (ProviderError) instead of falling back to the CPU when a
            requested GPU provider cannot be had (``auto``: when none can).
        threads: CPU threads for one inference.
        checksum: expected sha256 of the model file; verified when given.
        spinning: let onnxruntime's worker threads busy-wait between operators. Off by
            default: on a few shared cores (the simulator, controller and bridge run beside us)
            spinning threads steal CPU from each other and inference gets several times slower.
    """

    name = "yolox"

    def __init__(
        self,
        model_path: str | Path,
        *,
        input_size: int = 416,
        score_threshold: float = 0.3,
        nms_threshold: float = 0.45,
        classes: Sequence[str] = ("person",),
        providers: Sequence[str] | None = None,
        threads: int = 2,
        checksum: str = "",
        spinning: bool = False,
        strict_providers: bool = False,
    ) -> None:
        import onnxruntime as ort

        path = check_model_file(model_path, checksum, what="YOLOX model")
        if not 0.0 <= score_threshold <= 1.0 or not 0.0 <= nms_threshold <= 1.0:
            raise ValueError("score_threshold and nms_threshold must be in 0..1")
        self.class_ids = class_ids_for(classes)
        self.score_threshold = score_threshold
        self.nms_threshold = nms_threshold
        options = ort.SessionOptions()
        options.intra_op_num_threads = max(1, int(threads))
        options.inter_op_num_threads = 1
        options.log_severity_level = 3
        options.add_session_config_entry(
            "session.intra_op.allow_spinning", "1" if spinning else "0"
        )
        available = ort.get_available_providers()
        choice = choose_providers(providers, available)
        if choice.missing and strict_providers and not choice.auto:
            raise ProviderError(refusal(choice, [], available))
        if choice.missing:
            log.warning("%s; running YOLOX without it", choice.fallback_reason(available))
        try:
            self.session = ort.InferenceSession(str(path), options, providers=choice.providers)
        except (
            ort.capi.onnxruntime_pybind11_state.InvalidProtobuf,
            ort.capi.onnxruntime_pybind11_state.InvalidGraph,
            ort.capi.onnxruntime_pybind11_state.Fail,
        ) as exc:
            reason = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
            raise ModelFileError(f"{path} is not an ONNX model (ONNX Runtime: {reason})") from exc
        self.providers = list(self.session.get_providers())
        """The providers the session really runs on, best first (the CPU last)."""
        for provider in dropped_at_start(choice, self.providers):
            log.warning(
                "execution provider %s is in this onnxruntime build but could not start "
                "(no GPU, driver or CUDA/TensorRT libraries?); running YOLOX without it",
                provider,
            )
        if strict_providers and (reason := refusal(choice, self.providers, available)):
            raise ProviderError(reason)
        log.info("YOLOX runs on %s", ", ".join(self.providers))
        model_input = self.session.get_inputs()[0]
        self.input_name = model_input.name
        shape = model_input.shape
        static = [d for d in shape[2:] if isinstance(d, int)]
        self.input_size = static[0] if len(static) == 2 and static[0] == static[1] else input_size

    def detect(self, bgr: np.ndarray) -> list[Detection]:
        """Detections in a BGR uint8 image, highest score first, boxes in source px."""
        if bgr.ndim != 3 or bgr.shape[2] != 3 or bgr.dtype != np.uint8:
            raise ValueError(f"image must be HxWx3 uint8 BGR, got {bgr.dtype} {bgr.shape}")
        canvas, ratio = letterbox(bgr, self.input_size)
        blob = np.ascontiguousarray(canvas.transpose(2, 0, 1)[None], dtype=np.float32)
        (output,) = self.session.run(None, {self.input_name: blob})[:1]
        return decode_outputs(
            output,
            self.input_size,
            ratio,
            (bgr.shape[1], bgr.shape[0]),
            class_ids=self.class_ids,
            score_threshold=self.score_threshold,
            nms_threshold=self.nms_threshold,
        )
