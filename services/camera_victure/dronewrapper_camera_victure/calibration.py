"""Camera intrinsics: read a ``camera_info`` YAML and carry it over to the published frame.

The file is the one ROS's ``camera_calibration`` writes (``image_width``, ``image_height``,
``camera_matrix``, ``distortion_model``, ``distortion_coefficients``, ``rectification_matrix``,
``projection_matrix``; matrices as ``{rows, cols, data}``). It describes the frame as captured;
:func:`transformed` gives the intrinsics of the frame after flip/rotate/crop/resize, so that
what is published matches what the pixels are.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from dronewrapper.runtime.config import ConfigError, read_mapping
from dronewrapper_camera_victure.transform import Transform

MODELS = ("plumb_bob", "rational_polynomial", "equidistant")


class CalibrationError(ValueError):
    """A calibration file is missing, malformed, or does not fit the captured frames."""


@dataclass(frozen=True)
class Intrinsics:
    """A pinhole camera with lens distortion, in pixels of a ``width x height`` frame.

    ``k`` (3x3), ``r`` (3x3) and ``p`` (3x4) are row-major as in ROS ``CameraInfo``;
    ``d`` the distortion coefficients of ``distortion_model`` (plumb_bob: k1 k2 p1 p2 k3).
    """

    width: int
    height: int
    distortion_model: str
    d: tuple[float, ...]
    k: tuple[float, ...]
    r: tuple[float, ...]
    p: tuple[float, ...]


def _matrix(data: dict, name: str, rows: int, cols: int) -> tuple[float, ...]:
    node = data.get(name)
    if node is None:
        raise CalibrationError(f"{name} missing")
    values = node.get("data") if isinstance(node, dict) else node
    if not isinstance(values, list) or len(values) != rows * cols:
        raise CalibrationError(f"{name} must hold {rows}x{cols} = {rows * cols} numbers")
    try:
        out = tuple(float(v) for v in values)
    except (TypeError, ValueError) as exc:
        raise CalibrationError(f"{name}: not numbers") from exc
    if not all(math.isfinite(v) for v in out):
        raise CalibrationError(f"{name}: numbers must be finite")
    return out


def load_calibration(path: str | Path) -> Intrinsics:
    """Read a ``camera_info`` YAML file.

    Raises:
        CalibrationError: the file is missing, not YAML, or a field is absent or wrong (the
            message names the file and the field).
    """
    file = Path(path)
    try:
        data = read_mapping(file, "calibration")
    except ConfigError as exc:
        raise CalibrationError(str(exc)) from exc
    try:
        width, height = int(data["image_width"]), int(data["image_height"])
        model = str(data.get("distortion_model", "plumb_bob"))
        coefficients = data.get("distortion_coefficients", {"data": []})
        n = len(coefficients.get("data", []) if isinstance(coefficients, dict) else coefficients)
        intrinsics = Intrinsics(
            width=width,
            height=height,
            distortion_model=model,
            d=_matrix(data, "distortion_coefficients", 1, n) if n else (),
            k=_matrix(data, "camera_matrix", 3, 3),
            r=_matrix(data, "rectification_matrix", 3, 3)
            if "rectification_matrix" in data
            else (1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0),
            p=_matrix(data, "projection_matrix", 3, 4) if "projection_matrix" in data else (),
        )
    except KeyError as exc:
        raise CalibrationError(f"{file}: {exc.args[0]} missing") from exc
    except CalibrationError as exc:
        raise CalibrationError(f"{file}: {exc}") from exc
    if width <= 0 or height <= 0:
        raise CalibrationError(f"{file}: image_width and image_height must be > 0")
    if model not in MODELS:
        raise CalibrationError(f"{file}: distortion_model {model!r} not one of {MODELS}")
    k = intrinsics.k
    if not (k[0] > 0 and k[4] > 0):
        raise CalibrationError(f"{file}: camera_matrix fx and fy must be > 0")
    if not intrinsics.p:  # a monocular camera: P = [K | 0]
        intrinsics = replace(intrinsics, p=(*k[0:3], 0.0, *k[3:6], 0.0, *k[6:9], 0.0))
    return intrinsics


def _distortion(model: str, d: tuple[float, ...], axes: np.ndarray) -> tuple[float, ...]:
    """Distortion coefficients seen through a signed permutation ``axes`` of (x, y)."""
    if model == "equidistant" or len(d) < 4 or np.array_equal(axes, np.eye(2)):
        return d  # radial terms only, or nothing changes
    p1, p2 = d[2], d[3]
    if axes[0, 1] == 0:  # x' = a x, y' = b y
        a, b = axes[0, 0], axes[1, 1]
        p1, p2 = b * p1, a * p2
    else:  # x' = a y, y' = b x
        a, b = axes[0, 1], axes[1, 0]
        p1, p2 = b * d[3], a * d[2]
    return (d[0], d[1], float(p1), float(p2), *d[4:])


def transformed(intrinsics: Intrinsics, transform: Transform) -> Intrinsics:
    """The intrinsics of the frame after ``transform`` (see the module doc).

    Raises:
        CalibrationError: the transform's crop does not fit the calibrated frame.
    """
    width, height = intrinsics.width, intrinsics.height
    try:
        transform.check(width, height)
    except ValueError as exc:
        raise CalibrationError(str(exc)) from exc
    k = np.array(intrinsics.k, dtype=float).reshape(3, 3)
    r = np.array(intrinsics.r, dtype=float).reshape(3, 3)
    p = np.array(intrinsics.p, dtype=float).reshape(3, 4)
    d = intrinsics.d
    for step in transform.steps(width, height):
        axes3 = np.eye(3)
        axes3[:2, :2] = step.axes
        inverse = axes3.T  # a signed permutation's inverse is its transpose
        k = step.pixels @ k @ inverse
        r = axes3 @ r @ inverse
        p_inverse = np.eye(4)
        p_inverse[:3, :3] = inverse
        p = step.pixels @ p @ p_inverse
        d = _distortion(intrinsics.distortion_model, d, step.axes)
    out_w, out_h = transform.output_size(width, height)
    return Intrinsics(
        width=out_w,
        height=out_h,
        distortion_model=intrinsics.distortion_model,
        d=tuple(float(v) for v in d),
        k=tuple(float(v) for v in k.ravel()),
        r=tuple(float(v) for v in r.ravel()),
        p=tuple(float(v) for v in p.ravel()),
    )
