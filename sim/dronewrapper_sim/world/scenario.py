"""Scenarios: the strict YAML schema of a simulated world, and loading by name or path.

A scenario fixes where the vehicle starts, the GPS home, the wind, the camera settings and the
objects (a red beacon, people) with their motion. Files live in
``sim/dronewrapper_sim/scenarios/NAME.yaml``.
Positions are local ENU (m, x east, y north, z up, origin at the take-off point); angles in rad
unless the field name says ``_deg``.
"""

from __future__ import annotations

from pathlib import Path
from typing import Literal

import msgspec

from dronewrapper.runtime.config import ConfigError, load_config

__all__ = [
    "SCENARIOS_DIR",
    "SCENARIO_NAMES",
    "CameraSettings",
    "CircleMotion",
    "ConfigError",
    "Home",
    "Motion",
    "ObjectSpec",
    "PersonLookSpec",
    "RandomWalkMotion",
    "Scenario",
    "SmoothMotion",
    "StaticMotion",
    "TeleopMotion",
    "VehicleStart",
    "WaypointsMotion",
    "Wind",
    "ZigZagMotion",
    "load_scenario",
    "scenario_path",
]

SCENARIOS_DIR = Path(__file__).resolve().parents[1] / "scenarios"
"""Where the named scenario files are (``sim/dronewrapper_sim/scenarios``)."""

SCENARIO_NAMES: tuple[str, ...] = (
    "beacon_static",
    "beacon_smooth",
    "beacon_abrupt",
    "person_static",
    "person_moving",
    "people_crossing_behind",
    "people_crossing_front",
    "empty",
)
"""The fixed scenario names (docs/design.md) plus ``empty`` (no objects, for bridge/SDK tests)."""

Vec3 = tuple[float, float, float]
Vec2 = tuple[float, float]
BGR = tuple[int, int, int]


class _Strict(msgspec.Struct, forbid_unknown_fields=True, frozen=True):
    """A scenario record: unknown keys refused, immutable (each subclass restates
    ``frozen=True`` so that type checkers see it too)."""


class VehicleStart(_Strict, frozen=True):
    """Where the vehicle starts, on the ground: ENU x, y (m) and yaw (rad, CCW from east)."""

    x: float = 0.0
    y: float = 0.0
    yaw: float = 0.0


class Home(_Strict, frozen=True):
    """The GPS position of the local origin (PX4 SITL's default home, Zurich, by default)."""

    latitude_deg: float = 47.397742
    longitude_deg: float = 8.545594
    altitude_m: float = 488.0


class Wind(_Strict, frozen=True):
    """Steady wind (m/s, the direction it blows towards) and gust amplitude (m/s)."""

    east_m_s: float = 0.0
    north_m_s: float = 0.0
    gust_m_s: float = 0.0


class CameraSettings(_Strict, frozen=True):
    """Both vehicle cameras: image size (px), frame rate (Hz), horizontal field of view (deg)."""

    width: int = 640
    height: int = 480
    rate_hz: float = 30.0
    hfov_deg: float = 60.0


def _positive(name: str, value: float) -> None:
    if not value > 0:  # also refuses NaN
        raise ValueError(f"{name} must be > 0, got {value}")


def _ordered(name: str, low: float, high: float, *, allow_zero: bool = False) -> None:
    if not ((low >= 0 if allow_zero else low > 0) and high >= low):
        raise ValueError(f"{name}: need 0 < min <= max, got min {low}, max {high}")


# ---- motion models (a tagged union on the key ``type``) ------------------------------------


class StaticMotion(_Strict, frozen=True, tag="static", tag_field="type"):
    """The object stays where it is."""


class WaypointsMotion(_Strict, frozen=True, tag="waypoints", tag_field="type"):
    """Straight lines through ``points`` (ENU m) at ``speed_m_s``.

    ``mode``: ``pingpong`` (back and forth), ``loop`` (back to the first point and again) or
    ``once`` (stop at the last point). The object starts at its ``position`` and heads for the
    first point.
    """

    points: list[Vec3]
    speed_m_s: float = 1.0
    mode: Literal["pingpong", "loop", "once"] = "pingpong"

    def __post_init__(self) -> None:
        _positive("speed_m_s", self.speed_m_s)
        if not self.points:
            raise ValueError("waypoints need at least one point")


class CircleMotion(_Strict, frozen=True, tag="circle", tag_field="type"):
    """A horizontal circle around ``center`` (ENU m; its z is the height of the path) at
    ``speed_m_s``, counter-clockwise unless ``clockwise``; starts at the angle of ``position``."""

    center: Vec3
    radius_m: float
    speed_m_s: float = 1.0
    clockwise: bool = False

    def __post_init__(self) -> None:
        _positive("radius_m", self.radius_m)
        _positive("speed_m_s", self.speed_m_s)


class ZigZagMotion(_Strict, frozen=True, tag="zigzag", tag_field="type"):
    """The paper's abrupt zig-zag: up and down between ``z_min_m`` and ``z_max_m`` with a new
    random vertical speed in [``vertical_speed_min_m_s``, ``vertical_speed_max_m_s``] at each
    turn, while moving ``horizontal_speed_m_s`` along ``direction`` (ENU x, y), flipping sides at
    each vertical turn and never more than ``half_width_m`` from the start."""

    direction: Vec2 = (0.0, 1.0)
    horizontal_speed_m_s: float = 1.0
    vertical_speed_min_m_s: float = 0.5
    vertical_speed_max_m_s: float = 1.5
    z_min_m: float = 0.5
    z_max_m: float = 8.0
    half_width_m: float = 4.0

    def __post_init__(self) -> None:
        _positive("horizontal_speed_m_s", self.horizontal_speed_m_s)
        _positive("half_width_m", self.half_width_m)
        _ordered("vertical_speed", self.vertical_speed_min_m_s, self.vertical_speed_max_m_s)
        _ordered("z", self.z_min_m, self.z_max_m)
        if self.direction[0] ** 2 + self.direction[1] ** 2 < 1e-12:
            raise ValueError("direction must not be (0, 0)")


class SmoothMotion(_Strict, frozen=True, tag="smooth", tag_field="type"):
    """Smooth oscillation about the start: per ENU axis ``amplitude_m * sin(2 pi t / period_s +
    phase)``, phases drawn from the seed. An axis with amplitude 0 stays put."""

    amplitude_m: Vec3 = (0.0, 2.0, 1.0)
    period_s: Vec3 = (20.0, 16.0, 12.0)

    def __post_init__(self) -> None:
        for period in self.period_s:
            _positive("period_s", period)


class RandomWalkMotion(_Strict, frozen=True, tag="random_walk", tag_field="type"):
    """Random straight walks (as the paper's Gazebo person plugin): to a random point inside the
    circle (``center`` ENU x, y; ``radius_m``) at a random speed in [``speed_min_m_s``,
    ``speed_max_m_s``], then a pause of [``pause_min_s``, ``pause_max_s``], and again."""

    center: Vec2
    radius_m: float = 3.0
    speed_min_m_s: float = 0.5
    speed_max_m_s: float = 1.5
    min_leg_m: float = 1.0
    pause_min_s: float = 0.0
    pause_max_s: float = 0.0

    def __post_init__(self) -> None:
        _positive("radius_m", self.radius_m)
        _ordered("speed", self.speed_min_m_s, self.speed_max_m_s)
        _ordered("pause", self.pause_min_s, self.pause_max_s, allow_zero=True)
        if self.min_leg_m < 0 or self.min_leg_m > self.radius_m:
            raise ValueError("min_leg_m must be in [0, radius_m]")


class TeleopMotion(_Strict, frozen=True, tag="teleop", tag_field="type"):
    """Still until a command arrives on ``sim/objects/{name}/cmd_vel`` (then follows it)."""


Motion = (
    StaticMotion
    | WaypointsMotion
    | CircleMotion
    | ZigZagMotion
    | SmoothMotion
    | RandomWalkMotion
    | TeleopMotion
)


class PersonLookSpec(_Strict, frozen=True):
    """Clothing of a procedurally drawn person (BGR 0-255); what is left out is drawn at random
    from the seed."""

    shirt_bgr: BGR | None = None
    pants_bgr: BGR | None = None
    skin_bgr: BGR | None = None
    hair_bgr: BGR | None = None
    shoes_bgr: BGR | None = None
    long_sleeves: bool | None = None
    long_hair: bool | None = None
    shorts: bool | None = None


class ObjectSpec(_Strict, frozen=True):
    """One object of the world.

    Attributes:
        name: unique; the followed one is ``target``.
        kind: ``beacon`` (a red sphere) or ``person``.
        position: ENU m; a person's base point on the ground (z ignored), a beacon's centre.
        yaw: heading, rad (CCW from east); a walking person faces where they walk.
        motion: how it moves (``type``: static, waypoints, circle, zigzag, smooth,
            random_walk, teleop).
        radius_m: beacon radius, m.
        color_bgr: beacon colour.
        height_m: person height, m (None: drawn at random in 1.60-1.90 m).
        look: person clothing (None: at random).
        sprite: person sprite file name in the renderer's sprite folder (None: chosen from the
            seed); used only when the renderer has a sprite folder.
    """

    name: str
    kind: Literal["beacon", "person"]
    position: Vec3 = (0.0, 0.0, 0.0)
    yaw: float = 0.0
    motion: Motion = StaticMotion()
    radius_m: float = 0.3
    color_bgr: BGR = (20, 20, 215)
    height_m: float | None = None
    look: PersonLookSpec | None = None
    sprite: str | None = None


class Scenario(_Strict, frozen=True):
    """A simulated world: vehicle start, GPS home, wind, cameras, objects."""

    name: str
    description: str = ""
    duration_s: float = 120.0
    seed: int = 0
    vehicle: VehicleStart = VehicleStart()
    home: Home = Home()
    wind: Wind = Wind()
    camera: CameraSettings = CameraSettings()
    objects: list[ObjectSpec] = []

    def __post_init__(self) -> None:
        names = [obj.name for obj in self.objects]
        duplicates = sorted({n for n in names if names.count(n) > 1})
        if duplicates:
            raise ValueError(f"duplicate object names: {', '.join(duplicates)}")
        if self.camera.width < 16 or self.camera.height < 16:
            raise ValueError("camera width and height must be at least 16 px")
        if not 1.0 <= self.camera.hfov_deg <= 170.0:
            raise ValueError(f"camera.hfov_deg must be in [1, 170], got {self.camera.hfov_deg}")
        if self.camera.rate_hz <= 0:
            raise ValueError(f"camera.rate_hz must be > 0, got {self.camera.rate_hz}")


def scenario_path(name_or_path: str | Path) -> Path:
    """The file of a scenario: a fixed name (``beacon_static``) or a path to a YAML file."""
    text = str(name_or_path)
    if text in SCENARIO_NAMES or (
        "/" not in text and not text.endswith((".yaml", ".yml", ".json"))
    ):
        path = SCENARIOS_DIR / f"{text}.yaml"
        if not path.is_file():
            raise ConfigError(
                f"unknown scenario {text!r}; known scenarios: {', '.join(SCENARIO_NAMES)}"
            )
        return path
    return Path(text)


def load_scenario(name_or_path: str | Path, overrides: tuple[str, ...] = ()) -> Scenario:
    """Load a scenario by fixed name or file path (YAML or JSON), strictly.

    Args:
        name_or_path: ``beacon_static`` ... or a path to a scenario file.
        overrides: ``key.sub=value`` assignments applied on top (e.g. ``seed=3``).
    Raises:
        ConfigError: unknown name, unreadable file, unknown key or wrong type; the message names
            the file and the key (e.g. ``... unknown field `colour` - at `$.objects[0]```).
    """
    return load_config(Scenario, scenario_path(name_or_path), overrides)
