"""A service's config keys as ``--help`` lists them: key, default and what it is.

The text comes from the config schema itself (a msgspec Struct): its fields and defaults, and
the ``Attributes:`` section of its docstring (``name: what it is``, continued on deeper-indented
lines). A nested Struct's keys are listed under their dotted path (``gains.kp``), as
``--set`` takes them.
"""

from __future__ import annotations

import inspect
import re
import textwrap
from typing import Any

import msgspec
from msgspec import inspect as mi

from dronewrapper.runtime.arguments import plain_text
from dronewrapper.runtime.config_ranges import range_text

_ATTRIBUTE = re.compile(r"^(\s*)([A-Za-z_][A-Za-z0-9_]*)(?: \([^)]*\))?: (.*)$")
_SECTION = re.compile(r"^Attributes(?: \([^)]*\))?:$")  # "Attributes (beyond ...):" too
WIDTH = 100


def attribute_docs(doc: str | None) -> dict[str, str]:
    """``{name: text}`` from a docstring's ``Attributes:`` section (Google style)."""
    lines = inspect.cleandoc(doc or "").splitlines()
    try:
        start = next(i for i, line in enumerate(lines) if _SECTION.match(line.strip()))
    except StopIteration:
        return {}
    docs: dict[str, str] = {}
    name, indent = "", None
    for line in lines[start + 1 :]:
        if not line.strip():
            continue
        match = _ATTRIBUTE.match(line)
        depth = len(line) - len(line.lstrip())
        if match and (indent is None or depth == indent):
            indent, name = depth, match.group(2)
            docs[name] = match.group(3).strip()
        elif indent is not None and depth > indent and name:
            docs[name] += " " + line.strip()
        else:
            break
    return docs


def _default(field: Any) -> Any:
    if field.default is not msgspec.NODEFAULT:
        return field.default
    if field.default_factory is not msgspec.NODEFAULT:
        return field.default_factory()
    return msgspec.NODEFAULT


def config_keys(config_type: type, prefix: str = "") -> list[tuple[str, str, str]]:
    """``(dotted key, default as JSON, what it is)`` for every key of ``config_type``."""
    docs: dict[str, str] = {}
    for cls in reversed(config_type.__mro__):  # a subclass's words win over its base's
        docs.update(attribute_docs(cls.__doc__) if "__doc__" in vars(cls) else {})
    info = mi.type_info(config_type)
    types = {f.name: f.type for f in info.fields} if isinstance(info, mi.StructType) else {}
    keys: list[tuple[str, str, str]] = []
    for field in msgspec.structs.fields(config_type):
        key = f"{prefix}{field.encode_name}"
        default = _default(field)
        if isinstance(default, msgspec.Struct):
            keys += config_keys(type(default), f"{key}.")
            continue
        shown = "required" if default is msgspec.NODEFAULT else _json(default)
        text = plain_text(docs.get(field.name, ""))
        allowed = range_text(types.get(field.name))
        if allowed:
            text = f"{text} Must be {allowed}.".strip()
        keys.append((key, shown, text))
    return keys


def _json(value: Any) -> str:
    try:
        return msgspec.json.encode(value).decode()
    except (TypeError, msgspec.EncodeError):
        return repr(value)


def config_help(config_type: type) -> str:
    """The ``--help`` epilog listing ``config_type``'s keys."""
    lines = ["config keys (--set KEY=VALUE, or a --config FILE of them), with their defaults:"]
    for key, default, text in config_keys(config_type):
        lines.append(f"  {key} = {default}")
        if text:
            lines += textwrap.wrap(text, WIDTH, initial_indent="      ", subsequent_indent="      ")
    return "\n".join(lines)
