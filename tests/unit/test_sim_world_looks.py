"""People's looks: seeded, overridable field by field, never beacon-red."""

from __future__ import annotations

import cv2
import numpy as np

from dronewrapper_sim.world.looks import HAIRS, PANTS, SHIRTS, SHOES, SKINS, random_look
from dronewrapper_sim.world.scenario import PersonLookSpec


def test_a_seed_fixes_the_look_and_a_given_colour_changes_nothing_else():
    a = random_look(np.random.default_rng(4))
    b = random_look(np.random.default_rng(4), PersonLookSpec(shirt_bgr=(1, 2, 3), shorts=True))
    assert a == random_look(np.random.default_rng(4))
    assert b.shirt_bgr == (1, 2, 3) and b.shorts
    assert (b.pants_bgr, b.skin_bgr, b.hair_bgr, b.shoes_bgr) == (
        a.pants_bgr,
        a.skin_bgr,
        a.hair_bgr,
        a.shoes_bgr,
    )
    looks = {random_look(np.random.default_rng(s)) for s in range(30)}
    assert len(looks) > 20  # varied


def test_no_palette_colour_passes_the_papers_red_filter():
    colours = np.array([SHIRTS + PANTS + SKINS + HAIRS + SHOES], dtype=np.uint8)
    hsv = cv2.cvtColor(colours, cv2.COLOR_BGR2HSV)[0]
    red_hue = (hsv[:, 0] <= 10) | (hsv[:, 0] >= 170)  # even a wide 0-20 deg / 340-360 deg mask
    assert not np.any(red_hue & (hsv[:, 1] >= 70) & (hsv[:, 2] >= 50))
