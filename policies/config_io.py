"""Frozen config dataclasses to and from plain data (YAML, `--set` values), with errors that name the field."""

from __future__ import annotations

import dataclasses
import types
import typing
from typing import Literal


class ConfigError(ValueError):
    """A configuration value or override is unusable; the message names the field."""


def to_dict(obj) -> dict:
    """A (nested) dataclass as plain dicts and lists, for YAML."""
    def plain(v):
        if dataclasses.is_dataclass(v):
            return {f.name: plain(getattr(v, f.name)) for f in dataclasses.fields(v)}
        if isinstance(v, (tuple, list)):
            return [plain(x) for x in v]
        if isinstance(v, dict):  # a copy: overrides must not reach the frozen config's mapping
            return {k: plain(x) for k, x in v.items()}
        return v
    return plain(obj)


def _convert(kind, value, path: str):
    """`value` (from YAML or the command line) as the annotated type `kind`."""
    origin = typing.get_origin(kind)
    if dataclasses.is_dataclass(kind):
        if not isinstance(value, dict):
            raise ConfigError(f"{path}: expected a mapping for {kind.__name__}, got {value!r}")
        return from_dict(kind, value, f"{path}.")
    if origin is tuple:
        item = typing.get_args(kind)[0]
        return tuple(_convert(item, v, path) for v in value)
    if origin is Literal:
        if value not in typing.get_args(kind):
            raise ConfigError(f"{path}: must be one of {typing.get_args(kind)}, got {value!r}")
        return value
    if origin in (typing.Union, types.UnionType):
        if value is None and type(None) in typing.get_args(kind):
            return None
        for option in typing.get_args(kind):
            if option is not type(None):
                return _convert(option, value, path)
    if origin is dict:
        if not isinstance(value, dict):
            raise ConfigError(f"{path}: expected a mapping such as {{ball: 4}}, got {value!r}")
        if any(v is None or isinstance(v, bool) for v in value.values()):
            raise ConfigError(f"{path}: expected numbers, got {value!r} (YAML needs a space after each colon: "
                              f"{{ball: 4}})")
        key, item = typing.get_args(kind)
        return {_convert(key, k, path): _convert(item, v, f"{path}.{k}") for k, v in value.items()}
    if kind is bool:
        if isinstance(value, str):
            if value.lower() not in ("true", "false", "1", "0"):
                raise ConfigError(f"{path}: expected true or false, got {value!r}")
            return value.lower() in ("true", "1")
        return bool(value)
    if kind in (int, float, str):
        try:
            return kind(value)
        except (TypeError, ValueError):
            raise ConfigError(f"{path}: expected {kind.__name__}, got {value!r}") from None
    return value


def from_dict(cls, data: dict, path: str = ""):
    """Rebuild a (nested) frozen dataclass from `to_dict` output; unknown keys are errors."""
    hints = typing.get_type_hints(cls)
    names = {f.name for f in dataclasses.fields(cls)}
    unknown = set(data) - names
    if unknown:
        raise ConfigError(f"unknown config field(s) {sorted(unknown)} in {path.rstrip('.') or cls.__name__}")
    return cls(**{k: _convert(hints[k], v, f"{path}{k}") for k, v in data.items()})
