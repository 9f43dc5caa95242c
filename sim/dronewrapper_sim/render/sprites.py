"""Photo billboards of people: sprites cut from real photos, scaled to the person's true height.

A sprite folder holds PNG crops and ``sprites.json`` giving, for each file, the full-body person
box inside the crop (``person_box_xyxy_in_sprite``). At load the person is separated from the
crop's background once (GrabCut inside the box, feathered), so the billboard shows the person, not
a rectangle of someone else's street.
"""

from __future__ import annotations

import json
import math
from functools import lru_cache
from pathlib import Path

import cv2
import numpy as np

__all__ = ["Sprite", "SpriteBank", "draw_billboard", "sprite_bank"]


class Sprite:
    """A person image, the person box inside it (px) and its alpha (0..1, cut out on first use).

    Attributes:
        name: the file name.
        bgr: the image (H x W x 3 uint8).
        person_box_xyxy: the full-body box inside the image, px.
    """

    def __init__(self, name: str, bgr: np.ndarray, person_box_xyxy: tuple[int, ...]) -> None:
        self.name = name
        self.bgr = bgr
        self.person_box_xyxy = tuple(int(v) for v in person_box_xyxy)
        self._alpha: np.ndarray | None = None

    @property
    def alpha(self) -> np.ndarray:
        """Soft mask of the person (H x W float32, 1 = person)."""
        if self._alpha is None:
            self._alpha = _cut_out(self.bgr, self.person_box_xyxy)  # type: ignore[arg-type]
        return self._alpha


def _cut_out(bgr: np.ndarray, box: tuple[int, int, int, int]) -> np.ndarray:
    """Soft alpha of the person inside ``box`` (GrabCut; the whole box if that fails)."""
    h, w = bgr.shape[:2]
    x0, y0, x1, y1 = box
    rect = (max(0, x0), max(0, y0), max(1, min(w, x1) - max(0, x0)), max(1, min(h, y1) - y0))
    mask = np.zeros((h, w), np.uint8)
    try:
        bgd, fgd = np.zeros((1, 65)), np.zeros((1, 65))
        cv2.setRNGSeed(0)
        cv2.grabCut(bgr, mask, rect, bgd, fgd, 4, cv2.GC_INIT_WITH_RECT)
        fg: np.ndarray = np.isin(mask, (cv2.GC_FGD, cv2.GC_PR_FGD)).astype(np.float32)
    except cv2.error:
        fg = np.zeros((h, w), np.float32)
    if fg.sum() < 0.25 * rect[2] * rect[3]:  # GrabCut lost the person: an ellipse in the box
        fg = np.zeros((h, w), np.float32)
        centre = ((x0 + x1) // 2, (y0 + y1) // 2)
        cv2.ellipse(
            fg, centre, (max(1, (x1 - x0) // 2), max(1, (y1 - y0) // 2)), 0, 0, 360, 1.0, -1
        )
    fg = cv2.morphologyEx(fg, cv2.MORPH_CLOSE, np.ones((5, 5), np.uint8))
    return cv2.GaussianBlur(fg, (0, 0), 1.0)


def _is_grey(bgr: np.ndarray) -> bool:
    spread = bgr.max(axis=2).astype(int) - bgr.min(axis=2)
    return float(np.mean(spread)) < 4.0


class SpriteBank:
    """All sprites of a folder (use :func:`sprite_bank` to share one per folder)."""

    def __init__(self, folder: Path) -> None:
        folder = Path(folder)
        index = folder / "sprites.json"
        try:
            entries = json.loads(index.read_text())["sprites"]
        except (OSError, ValueError, KeyError) as exc:
            raise ValueError(f"{index}: cannot read the sprite index: {exc}") from exc
        sprites = []
        for entry in entries:
            path = folder / entry["file"]
            bgr = cv2.imread(str(path), cv2.IMREAD_COLOR)
            if bgr is None:
                raise ValueError(f"{path}: cannot read the sprite image")
            sprites.append(Sprite(entry["file"], bgr, entry["person_box_xyxy_in_sprite"]))
        if not sprites:
            raise ValueError(f"{index}: no sprites listed")
        self.sprites = sprites
        self._by_name = {s.name: s for s in sprites}
        # chosen by default: colour photos (a grey one is hardly a person to a COCO detector)
        self.default = [s for s in sprites if not _is_grey(s.bgr)] or sprites

    def choose(self, name: str | None, index: int) -> Sprite:
        """The sprite called ``name``, or the ``index``-th colour sprite (mod their count)."""
        if name is not None:
            try:
                return self._by_name[name]
            except KeyError:
                raise KeyError(f"no sprite {name!r} (have {', '.join(self._by_name)})") from None
        return self.default[index % len(self.default)]


@lru_cache(maxsize=8)
def _bank(folder: Path) -> SpriteBank:
    return SpriteBank(folder)


def sprite_bank(folder: Path) -> SpriteBank:
    """The sprites of ``folder``, loaded once per process (cut-outs made on first use)."""
    return _bank(Path(folder).resolve())


def draw_billboard(
    image: np.ndarray, sprite: Sprite, foot_px: np.ndarray, head_px: np.ndarray
) -> None:
    """Paste ``sprite`` so its person box runs from ``foot_px`` (bottom centre) to ``head_px``
    (top centre), image px: scaled and turned along the projected body axis (upright in a level
    frontal view, lying radially in a downward view), alpha-blended, clipped at the borders."""
    foot = np.asarray(foot_px, dtype=float)
    axis = np.asarray(head_px, dtype=float) - foot  # image vector foot -> head
    height_px = float(np.hypot(*axis))
    x0, y0, x1, y1 = sprite.person_box_xyxy
    scale = height_px / max(1, y1 - y0)
    if not math.isfinite(scale) or scale * max(sprite.bgr.shape[:2]) < 2:
        return
    up = axis / height_px  # image direction of the sprite's "up" (-y)
    right = np.array([-up[1], up[0]])  # sprite +x, 90 deg clockwise from up in the image
    # sprite px (x, y) -> image px: foot + scale * ((x - xc) * right - (y - y1) * up)
    xc = (x0 + x1) / 2.0
    lin = scale * np.column_stack((right, -up))
    offset = foot - lin @ np.array([xc, y1])
    sh, sw = sprite.bgr.shape[:2]
    corners = np.array([[0, 0], [sw, 0], [0, sh], [sw, sh]], dtype=float) @ lin.T + offset
    h, w = image.shape[:2]
    left, top = max(0, math.floor(corners[:, 0].min())), max(0, math.floor(corners[:, 1].min()))
    right_px = min(w, math.ceil(corners[:, 0].max()))
    bottom = min(h, math.ceil(corners[:, 1].max()))
    if right_px <= left or bottom <= top:
        return
    m = np.column_stack((lin, offset - np.array([left, top])))
    size = (right_px - left, bottom - top)
    patch = cv2.warpAffine(sprite.bgr, m, size, flags=cv2.INTER_LINEAR)
    alpha = cv2.warpAffine(sprite.alpha, m, size, flags=cv2.INTER_LINEAR)
    roi = image[top:bottom, left:right_px]
    roi[...] = cv2.blendLinear(patch, roi, alpha, 1.0 - alpha)
