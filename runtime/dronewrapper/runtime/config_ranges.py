"""Ranges of config keys declared on the schema: ``Annotated[float, msgspec.Meta(ge=0, le=600)]``.

msgspec checks a ``Meta`` constraint when a config is decoded (``load_config``), and says where in
its own words (``Expected `float` <= 600.0 - at `$.takeoff.wait_ready```). This module gives the
words a user reads instead: the dotted key as ``--set`` takes it, the allowed range and the value
(``takeoff.wait_ready must be in [0, 600], got 700``); :func:`check_ranges` holds the same ranges
when a config Struct is built in code, where msgspec checks nothing; :func:`range_text` is what
``--help`` shows beside a key.
"""

from __future__ import annotations

import functools
import re
import sys
from typing import Annotated, Any

import msgspec
from msgspec import inspect as mi

Positive = Annotated[float, msgspec.Meta(gt=0)]
"""A number > 0 (a rate, a timeout, a size)."""
NonNegative = Annotated[float, msgspec.Meta(ge=0)]
"""A number >= 0 (a delay that may be none)."""
FinitePositive = Annotated[float, msgspec.Meta(gt=0, le=sys.float_info.max)]
"""A finite number > 0 (inf is refused too)."""
Share = Annotated[float, msgspec.Meta(ge=0, le=1)]
"""A share in [0, 1]."""

# msgspec's words for a failed constraint and where: "Expected `float` >= 0.0 - at `$.a.b[1]`"
_CONSTRAINT = re.compile(r"^Expected `[^`]+` (?:[<>]=?|of|that|matching|length).* - at `\$(.*)`$")
_ENUM = re.compile(r"^Invalid enum value .* - at `\$(.*)`$")
_PATH_PART = re.compile(r"\.([^.\[]+)|\[(\d+|\.\.\.)\]")  # [...]: a key of a mapping
_ANY_KEY = "[...]"


def _number(value: float) -> str:
    """``0`` for 0.0, ``0.5`` for 0.5: the figure as a user would write it."""
    return f"{value:g}"


def _unwrap(info: Any) -> Any:
    """``int | None`` -> ``int``: the one type of an optional value (else ``info`` itself)."""
    if isinstance(info, mi.UnionType):
        kinds = [t for t in info.types if not isinstance(t, mi.NoneType)]
        if len(kinds) == 1:
            return kinds[0]
    return info


def range_text(info: Any) -> str:
    """The allowed values of a constrained msgspec type: ``> 0``, ``in [0, 600]``, ``in (0, 5]``,
    ``not empty``, ``1 to 16 characters``, ``a string matching ^[a-z]+$``, ``one of stop, land``
    (a Literal); "" when it has no constraint."""
    info = _unwrap(info)
    words: list[str] = []
    if isinstance(info, mi.LiteralType):
        return "one of " + ", ".join(str(value) for value in info.values)
    if isinstance(info, (mi.IntType, mi.FloatType)):
        low = ("[", info.ge) if info.ge is not None else ("(", info.gt)
        high = ("]", info.le) if info.le is not None else (")", info.lt)
        finite = high[1] == sys.float_info.max  # the largest float: "finite", not a figure
        if finite:
            high = (")", None)
        if low[1] is not None and high[1] is not None:
            words.append(f"in {low[0]}{_number(low[1])}, {_number(high[1])}{high[0]}")
        elif low[1] is not None:
            words.append(f"{'>=' if low[0] == '[' else '>'} {_number(low[1])}")
        elif high[1] is not None:
            words.append(f"{'<=' if high[0] == ']' else '<'} {_number(high[1])}")
        if finite:
            words.append("finite")
        if info.multiple_of is not None:
            words.append(f"a multiple of {_number(info.multiple_of)}")
    if isinstance(info, (mi.StrType, mi.ListType, mi.DictType)):
        unit = " characters" if isinstance(info, mi.StrType) else " items"
        if info.min_length == 1 and info.max_length is None:
            words.append("not empty")
        elif info.min_length is not None and info.max_length is not None:
            words.append(f"{info.min_length} to {info.max_length}{unit}")
        elif info.min_length is not None:
            words.append(f"at least {info.min_length}{unit}")
        elif info.max_length is not None:
            words.append(f"at most {info.max_length}{unit}")
    if isinstance(info, mi.StrType) and info.pattern is not None:
        words.append(f"a string matching {info.pattern}")
    return " and ".join(words)


def _parts(path: str) -> list[str | int]:
    return [
        name or (_ANY_KEY if index == "..." else int(index))
        for name, index in _PATH_PART.findall(path)
    ]


def dotted(parts: list[str | int]) -> str:
    """``follow_color.id_switch_confirm``, ``color_ranges[1].h_min``: a path as a user writes it."""
    text = ""
    for part in parts:
        text += f"[{part}]" if isinstance(part, int) else (f".{part}" if text else str(part))
    return text


def _step(info: Any, part: str | int) -> Any:
    """The type one step down ``part`` from ``info`` (None where the path cannot be followed)."""
    info = _unwrap(info)
    if isinstance(info, mi.StructType) and isinstance(part, str):
        return next((f.type for f in info.fields if f.encode_name == part), None)
    if isinstance(info, (mi.ListType, mi.SetType, mi.VarTupleType)) and isinstance(part, int):
        return info.item_type
    if isinstance(info, mi.DictType):
        return info.value_type
    return None


def _value(data: Any, parts: list[str | int]) -> Any:
    for part in parts:
        try:
            data = data[part]
        except (KeyError, IndexError, TypeError):
            return msgspec.NODEFAULT
    return data


def _name_keys(data: Any, parts: list[str | int], leaf: Any) -> list[str | int]:
    """``parts`` with each ``[...]`` (msgspec does not say which key of a mapping failed) made
    the first key whose value is outside ``leaf``'s range."""
    if _ANY_KEY not in parts:
        return parts
    at = parts.index(_ANY_KEY)
    mapping = _value(data, parts[:at])
    for key in mapping if isinstance(mapping, dict) else ():
        named = [*parts[:at], key, *parts[at + 1 :]]
        value = _value(data, _name_keys(data, named, leaf))
        if value is not msgspec.NODEFAULT and not _inside(_unwrap(leaf), value):
            return _name_keys(data, named, leaf)
    return parts


def explain(schema: type, data: Any, error: msgspec.ValidationError) -> str | None:
    """A failed ``Meta`` constraint in a user's words: ``takeoff.wait_ready must be in [0, 600],
    got 700``; None when ``error`` is not one (an unknown key, a wrong type, a rule of
    ``__post_init__``: msgspec's own words name those)."""
    match = _CONSTRAINT.match(str(error)) or _ENUM.match(str(error))
    if match is None:
        return None
    parts = _parts(match.group(1))
    info: Any = mi.type_info(schema)
    for part in parts:
        info = _step(info, part)
    allowed = range_text(info) if info is not None else ""
    if not allowed:
        return None
    parts = _name_keys(data, parts, info)
    value = _value(data, parts)
    got = "" if value is msgspec.NODEFAULT else f", got {value!r}"
    return f"{dotted(parts)} must be {allowed}{got}"


@functools.cache
def _constrained(struct_type: type) -> tuple[tuple[str, str, Any], ...]:
    """``(attribute, key, type info)`` of each field of ``struct_type`` that has a range."""
    info = mi.type_info(struct_type)
    assert isinstance(info, mi.StructType)
    return tuple((f.name, f.encode_name, f.type) for f in info.fields if range_text(f.type))


def _inside(info: Any, value: Any) -> bool:
    """Whether ``value`` meets every constraint of ``info`` (a number, string or list's, or is
    one of a Literal's values)."""
    if isinstance(info, mi.LiteralType):
        return value in info.values
    checks = (
        ("gt", lambda bound: value > bound),
        ("ge", lambda bound: value >= bound),
        ("lt", lambda bound: value < bound),
        ("le", lambda bound: value <= bound),
        ("multiple_of", lambda bound: value % bound == 0),
        ("min_length", lambda bound: len(value) >= bound),
        ("max_length", lambda bound: len(value) <= bound),
        ("pattern", lambda bound: re.search(bound, value) is not None),
    )
    return all(getattr(info, name, None) is None or ok(getattr(info, name)) for name, ok in checks)


def check_ranges(config: msgspec.Struct, prefix: str = "") -> None:
    """Hold the ``Meta`` ranges of ``config``'s own fields (not its nested Structs', which hold
    theirs): call it from ``__post_init__`` so that a config built in code is checked as a
    decoded one is (msgspec checks ranges only when it decodes).

    Raises:
        ValueError: ``{prefix}{key} must be {range}, got {value}`` for the first value outside.
    """
    for name, key, info in _constrained(type(config)):
        value = getattr(config, name)
        if value is not None and not _inside(_unwrap(info), value):
            raise ValueError(f"{prefix}{key} must be {range_text(info)}, got {value!r}")
