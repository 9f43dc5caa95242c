"""Config files as strict schemas: YAML or JSON decoded into a msgspec Struct.

Unknown keys and wrong types fail with the file and the key named, e.g.
``controller.yaml: Object contains unknown field `kpp` - at `$.pid_vx```; a value outside the
range a schema declares (``Annotated[float, msgspec.Meta(gt=0)]``, :mod:`config_ranges`) with
the dotted key, the range and the value: ``controller.yaml: takeoff.height must be > 0, got -1``.
"""

from __future__ import annotations

import json
from collections.abc import Iterable, Mapping
from pathlib import Path
from typing import Any, TypeVar

import msgspec

from dronewrapper.runtime.config_ranges import explain

T = TypeVar("T")


class ConfigError(ValueError):
    """A config file or override is malformed; the message names the file and the key."""


def read_mapping(path: Path, what: str = "config") -> dict[str, Any]:
    """The top-level mapping of a YAML or JSON file (``.json``: JSON; empty: ``{}``), or
    ConfigError naming the file and, when it cannot be read, ``what`` it was to hold."""
    try:
        text = path.read_text()
    except OSError as exc:
        raise ConfigError(f"{path}: cannot read {what}: {exc.strerror}") from exc
    if path.suffix == ".json":
        data = json.loads(text) if text.strip() else {}
    else:
        import yaml  # services and tools depend on PyYAML; the bare SDK never reads YAML

        try:
            data = yaml.safe_load(text) or {}
        except yaml.YAMLError as exc:
            raise ConfigError(f"{path}: not valid YAML: {exc}") from exc
    if not isinstance(data, dict):
        raise ConfigError(f"{path}: top level must be a mapping, got {type(data).__name__}")
    return data


def _parse_scalar(text: str) -> Any:
    try:
        import yaml

        return yaml.safe_load(text)
    except Exception:
        return text


def apply_override(data: dict[str, Any], assignment: str) -> None:
    """Apply ``a.b.c=value`` to nested ``data`` (value parsed as a YAML scalar)."""
    if "=" not in assignment:
        raise ConfigError(f"override {assignment!r} is not KEY=VALUE")
    dotted, _, raw = assignment.partition("=")
    parts = [p for p in dotted.strip().split(".") if p]
    if not parts:
        raise ConfigError(f"override {assignment!r} has an empty key")
    node = data
    for part in parts[:-1]:
        child = node.setdefault(part, {})
        if not isinstance(child, dict):
            raise ConfigError(f"override {assignment!r}: {part} is not a mapping")
        node = child
    node[parts[-1]] = _parse_scalar(raw)


def merge(base: dict[str, Any], extra: Mapping[str, Any]) -> dict[str, Any]:
    """Deep-merge ``extra`` into a copy of ``base`` (mappings merge, other values replace)."""
    out = dict(base)
    for key, value in extra.items():
        if isinstance(value, Mapping) and isinstance(out.get(key), dict):
            out[key] = merge(out[key], value)
        else:
            out[key] = value
    return out


def load_config(
    schema: type[T],
    path: str | Path | None = None,
    overrides: Iterable[str] = (),
    *,
    data: Mapping[str, Any] | None = None,
) -> T:
    """Decode a config: defaults of ``schema``, then the file, then ``data``, then overrides.

    Raises:
        ConfigError: the file cannot be read, or a key is unknown, has the wrong type or a
            value outside its range.
    """
    raw: dict[str, Any] = {}
    source = "config"
    if path is not None:
        raw = read_mapping(Path(path))
        source = str(path)
    if data:
        raw = merge(raw, data)
    for assignment in overrides:
        apply_override(raw, assignment)
        source = f"{source} (with overrides)"
    try:
        return msgspec.convert(raw, schema, strict=False)
    except msgspec.ValidationError as exc:
        raise ConfigError(f"{source}: {explain(schema, raw, exc) or exc}") from exc
