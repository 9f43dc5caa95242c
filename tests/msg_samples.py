"""Build message instances with every field set to a non-default value, from the type hints."""

from __future__ import annotations

import math
import random
import typing

import msgspec

from dronewrapper.msgs.mission import NAV_RALLY_POINT, Waypoint


def _value(tp, rng: random.Random):
    origin = typing.get_origin(tp)
    if origin is list:
        (item,) = typing.get_args(tp)
        return [_value(item, rng) for _ in range(rng.randint(1, 3))]
    if origin is tuple:
        return tuple(_value(item, rng) for item in typing.get_args(tp))
    if origin in (typing.Union, __import__("types").UnionType):
        args = [a for a in typing.get_args(tp) if a is not type(None)]
        return _value(args[0], rng)
    if isinstance(tp, type) and issubclass(tp, msgspec.Struct):
        return sample(tp, rng=rng)
    if tp is bool:
        return rng.random() < 0.5
    if tp is int:
        return rng.randint(-1000, 1000)
    if tp is float:
        return rng.uniform(-1e3, 1e3)
    if tp is str:
        return "".join(rng.choice("abcXYZ_./ é") for _ in range(rng.randint(1, 12)))
    if tp is bytes:
        return rng.randbytes(rng.randint(1, 64))
    if tp is memoryview:
        return memoryview(rng.randbytes(rng.randint(1, 64)))
    raise TypeError(f"no sample for {tp!r}")


_ENVELOPE_LIMITS = ("max_altitude", "max_distance", "max_horizontal_speed", "max_vertical_speed")


def _polygon(rng: random.Random) -> list[tuple[float, float]]:
    return [(rng.uniform(-50, 50), rng.uniform(-50, 50)) for _ in range(rng.randint(3, 5))]


def _rally_point(rng: random.Random) -> Waypoint:
    lat, lon = rng.uniform(-90.0, 90.0), rng.uniform(-180.0, 180.0)
    return Waypoint(command=NAV_RALLY_POINT, x_lat=lat, y_long=lon, z_alt=rng.uniform(0, 50))


_WATCHING = ("GotoRequest", "ReturnRequest", "MissionRequest")

# Fields whose messages check their range (requests): a random value within it.
_RANGED = {
    ("CommandTOL", "min_pitch"): lambda rng: rng.uniform(-90.0, 90.0),
    ("CommandTOL", "yaw"): lambda rng: rng.uniform(-3.0, 3.0),
    ("CommandTOL", "latitude"): lambda rng: rng.uniform(-90.0, 90.0),
    ("CommandTOL", "longitude"): lambda rng: rng.uniform(-180.0, 180.0),
    ("CommandTOL", "altitude"): lambda rng: rng.uniform(0.5, 100.0),
    ("SetMode", "base_mode"): lambda rng: 0,
    **{("Envelope", name): lambda rng: rng.uniform(1.0, 50.0) for name in _ENVELOPE_LIMITS},
    ("Envelope", "margin"): lambda rng: rng.uniform(0.0, 5.0),
    ("Envelope", "breach_action"): lambda rng: rng.choice(("hold", "return", "land")),
    ("Envelope", "fence"): lambda rng: _polygon(rng),
    ("Envelope", "exclusions"): lambda rng: [_polygon(rng)],
    ("Waypoint", "x_lat"): lambda rng: rng.uniform(-90.0, 90.0),
    ("Waypoint", "y_long"): lambda rng: rng.uniform(-180.0, 180.0),
    ("Waypoint", "z_alt"): lambda rng: rng.uniform(0.0, 100.0),
    ("Waypoint", "frame"): lambda rng: 3,
    ("Waypoint", "command"): lambda rng: 16,
    ("WaypointPush", "start_index"): lambda rng: 0,
    ("WaypointPush", "rally"): lambda rng: [_rally_point(rng)],
    ("WaypointSetCurrent", "wp_seq"): lambda rng: rng.randint(0, 100),
    ("MissionControl", "action"): lambda rng: rng.choice(("start", "pause", "return")),
    ("GotoRequest", "latitude"): lambda rng: math.nan,  # x and y give the point
    ("GotoRequest", "longitude"): lambda rng: math.nan,
    **{(kind, "watch"): lambda rng: "drone/alive/app" for kind in _WATCHING},
    ("MissionRequest", "action"): lambda rng: rng.choice(("start", "pause", "resume")),
}


def sample(msg_type, seed: int = 0, rng: random.Random | None = None):
    """An instance of ``msg_type`` with random non-default values in every field."""
    rng = rng or random.Random(seed)
    hints = typing.get_type_hints(msg_type)
    return msg_type(
        **{
            name: _RANGED.get((msg_type.__name__, name), lambda r, n=name: _value(hints[n], r))(rng)
            for name in msg_type.__struct_fields__
        }
    )
