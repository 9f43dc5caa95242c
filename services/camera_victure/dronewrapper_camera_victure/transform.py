"""Frame geometry: flip, rotate, crop and resize, and what they do to pixel coordinates.

Order: flip, then rotate (clockwise), then crop (in the rotated frame), then resize. Each step
also gives the affine map of pixel coordinates (3x3, pixel centres at integers) and the signed
permutation of normalised camera coordinates, which :mod:`calibration` uses to carry the
intrinsics over to the published frame.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

_FLIP_CODES = {"horizontal": 1, "vertical": 0, "both": -1}
_ROTATE_CODES = {
    90: cv2.ROTATE_90_CLOCKWISE,
    180: cv2.ROTATE_180,
    270: cv2.ROTATE_90_COUNTERCLOCKWISE,
}


@dataclass(frozen=True)
class Step:
    """One geometric step: ``pixels`` maps homogeneous (u, v, 1) of the input frame to the
    output frame; ``axes`` maps normalised (x, y) camera coordinates (a signed permutation)."""

    pixels: np.ndarray
    axes: np.ndarray


def _flip_step(kind: str, width: int, height: int) -> Step:
    sx = -1.0 if kind in ("horizontal", "both") else 1.0
    sy = -1.0 if kind in ("vertical", "both") else 1.0
    pixels = np.array(
        [
            [sx, 0, (width - 1) if sx < 0 else 0],
            [0, sy, (height - 1) if sy < 0 else 0],
            [0, 0, 1],
        ],
        dtype=float,
    )
    return Step(pixels, np.diag([sx, sy]))


def _rotate_step(degrees: int, width: int, height: int) -> Step:
    if degrees == 90:  # u' = H-1-v, v' = u
        return Step(
            np.array([[0, -1, height - 1], [1, 0, 0], [0, 0, 1]], dtype=float),
            np.array([[0.0, -1.0], [1.0, 0.0]]),
        )
    if degrees == 180:
        return _flip_step("both", width, height)
    # 270: u' = v, v' = W-1-u
    return Step(
        np.array([[0, 1, 0], [-1, 0, width - 1], [0, 0, 1]], dtype=float),
        np.array([[0.0, 1.0], [-1.0, 0.0]]),
    )


@dataclass(frozen=True)
class Transform:
    """The configured geometry (see the module doc).

    Attributes:
        flip: ``none``, ``horizontal``, ``vertical`` or ``both``.
        rotate: clockwise degrees, 0/90/180/270.
        crop: (x, y, width, height) in the rotated frame (px), or None.
        resize: (width, height) of the output (px), or None.
    """

    flip: str = "none"
    rotate: int = 0
    crop: tuple[int, int, int, int] | None = None
    resize: tuple[int, int] | None = None

    @property
    def identity(self) -> bool:
        return self.flip == "none" and self.rotate == 0 and not self.crop and not self.resize

    def rotated_size(self, width: int, height: int) -> tuple[int, int]:
        return (height, width) if self.rotate in (90, 270) else (width, height)

    def check(self, width: int, height: int) -> None:
        """Raises ValueError when the crop does not fit a ``width x height`` input."""
        if self.crop:
            rw, rh = self.rotated_size(width, height)
            x, y, w, h = self.crop
            if x + w > rw or y + h > rh:
                raise ValueError(
                    f"crop {list(self.crop)} does not fit the {rw}x{rh} frame (after rotate)"
                )

    def output_size(self, width: int, height: int) -> tuple[int, int]:
        """(width, height) of the output for a ``width x height`` input (px)."""
        if self.resize:
            return self.resize
        if self.crop:
            return self.crop[2], self.crop[3]
        return self.rotated_size(width, height)

    def apply(self, frame: np.ndarray) -> np.ndarray:
        """The transformed frame (the input itself when there is nothing to do).

        Raises:
            ValueError: the crop does not fit the frame.
        """
        if self.identity:
            return frame
        height, width = frame.shape[:2]
        self.check(width, height)
        if self.flip != "none":
            frame = cv2.flip(frame, _FLIP_CODES[self.flip])
        if self.rotate:
            frame = cv2.rotate(frame, _ROTATE_CODES[self.rotate])
        if self.crop:
            x, y, w, h = self.crop
            frame = frame[y : y + h, x : x + w]
        if self.resize and (frame.shape[1], frame.shape[0]) != self.resize:
            shrinking = self.resize[0] < frame.shape[1]
            interpolation = cv2.INTER_AREA if shrinking else cv2.INTER_LINEAR
            frame = cv2.resize(frame, self.resize, interpolation=interpolation)
        return np.ascontiguousarray(frame)

    def steps(self, width: int, height: int) -> list[Step]:
        """The geometric steps for a ``width x height`` input, in order."""
        out: list[Step] = []
        if self.flip != "none":
            out.append(_flip_step(self.flip, width, height))
        if self.rotate:
            out.append(_rotate_step(self.rotate, width, height))
        w, h = self.rotated_size(width, height)
        if self.crop:
            x, y, w, h = self.crop
            shift = np.array([[1, 0, -x], [0, 1, -y], [0, 0, 1]], dtype=float)
            out.append(Step(shift, np.eye(2)))
        if self.resize and (w, h) != self.resize:
            sx, sy = self.resize[0] / w, self.resize[1] / h
            # pixel centres: u' + 0.5 = (u + 0.5) * sx
            scale = np.array([[sx, 0, 0.5 * sx - 0.5], [0, sy, 0.5 * sy - 0.5], [0, 0, 1]])
            out.append(Step(scale, np.eye(2)))
        return out
