"""Camera frames for the perception tests: a red disc on a green-grey background (BGR)."""

from __future__ import annotations

import cv2
import numpy as np

from dronewrapper.images import bgr_to_image
from dronewrapper.msgs import Image


def red_disc_frame(cx: int = 200, cy: int = 150, r: int = 30) -> np.ndarray:
    img = np.full((240, 320, 3), (80, 120, 70), np.uint8)
    cv2.circle(img, (cx, cy), r, (0, 0, 230), -1)
    return img


def disc_msg(stamp: float, cx: int = 200, cy: int = 150) -> Image:
    return bgr_to_image(red_disc_frame(cx, cy), stamp, "cam_frontal")
