"""How a procedurally drawn person looks: clothing, skin and hair colours (BGR), drawn from a seed.

Palettes avoid saturated reds so that people never look like the red beacon to a colour filter.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from dronewrapper_sim.world.scenario import PersonLookSpec

__all__ = ["PersonLook", "random_look"]

BGR = tuple[int, int, int]

SHIRTS: tuple[BGR, ...] = (
    (110, 50, 25),  # navy
    (225, 225, 225),  # white
    (210, 160, 110),  # light blue
    (125, 125, 125),  # grey
    (40, 40, 40),  # black
    (60, 125, 50),  # green
    (45, 185, 225),  # yellow
    (150, 180, 200),  # beige
    (120, 60, 95),  # purple
    (140, 130, 30),  # teal
    (170, 110, 60),  # mid blue
    (80, 100, 90),  # olive
)
PANTS: tuple[BGR, ...] = (
    (120, 75, 45),  # jeans
    (75, 45, 30),  # dark jeans
    (40, 40, 40),  # black
    (120, 160, 180),  # khaki
    (95, 95, 95),  # grey
    (65, 35, 25),  # navy
)
SKINS: tuple[BGR, ...] = (
    (185, 200, 235),
    (150, 180, 225),
    (115, 150, 200),
    (85, 120, 170),
    (60, 90, 135),
    (45, 65, 100),
)
HAIRS: tuple[BGR, ...] = (
    (25, 25, 28),
    (30, 45, 70),
    (40, 70, 110),
    (100, 165, 205),
    (150, 150, 150),
)
SHOES: tuple[BGR, ...] = ((30, 30, 30), (220, 220, 220), (40, 60, 90), (90, 90, 90))


@dataclass(frozen=True)
class PersonLook:
    """Colours (BGR 0-255) of a drawn person, sleeves, a pony tail and shorts."""

    shirt_bgr: BGR
    pants_bgr: BGR
    skin_bgr: BGR
    hair_bgr: BGR
    shoes_bgr: BGR
    long_sleeves: bool
    long_hair: bool = False
    shorts: bool = False


def _pick(rng: np.random.Generator, palette: tuple[BGR, ...]) -> BGR:
    return palette[int(rng.integers(len(palette)))]


def random_look(rng: np.random.Generator, spec: PersonLookSpec | None = None) -> PersonLook:
    """A look drawn from ``rng``; colours given in ``spec`` win. Always draws every choice, so
    giving one colour does not change the others."""
    drawn = PersonLook(
        shirt_bgr=_pick(rng, SHIRTS),
        pants_bgr=_pick(rng, PANTS),
        skin_bgr=_pick(rng, SKINS),
        hair_bgr=_pick(rng, HAIRS),
        shoes_bgr=_pick(rng, SHOES),
        long_sleeves=bool(rng.uniform() < 0.5),
        long_hair=bool(rng.uniform() < 0.35),
        shorts=bool(rng.uniform() < 0.2),
    )
    if spec is None:
        return drawn
    return PersonLook(
        shirt_bgr=spec.shirt_bgr or drawn.shirt_bgr,
        pants_bgr=spec.pants_bgr or drawn.pants_bgr,
        skin_bgr=spec.skin_bgr or drawn.skin_bgr,
        hair_bgr=spec.hair_bgr or drawn.hair_bgr,
        shoes_bgr=spec.shoes_bgr or drawn.shoes_bgr,
        long_sleeves=drawn.long_sleeves if spec.long_sleeves is None else spec.long_sleeves,
        long_hair=drawn.long_hair if spec.long_hair is None else spec.long_hair,
        shorts=drawn.shorts if spec.shorts is None else spec.shorts,
    )
