"""Typed access to one TOML table of a scene, with errors naming the file and key."""

from __future__ import annotations

import math
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from geofrac.scene.errors import SceneError, did_you_mean

__all__ = [
    "MAX_CHECKPOINT_EVERY",
    "MAX_CHECKPOINT_MINUTES",
    "Table",
    "checkpoint_keys",
    "is_number",
]

#: Upper limits of ``output.checkpoint_every`` (events or steps) and ``checkpoint_minutes``.
MAX_CHECKPOINT_EVERY = 10**9
MAX_CHECKPOINT_MINUTES = 1e6


def _short(value: Any, limit: int = 80) -> str:
    """``repr(value)`` cut to ``limit`` characters (a huge list makes no readable error)."""
    text = repr(value)
    return text if len(text) <= limit else text[: limit - 3] + "..."


def checkpoint_keys(t: Table) -> tuple[int, float]:
    """``checkpoint_every`` (default 0: off), ``checkpoint_minutes`` (default 10) of ``t``."""
    every = t.number("checkpoint_every", default=0, integer=True, minimum=0)
    if every is not None and every > MAX_CHECKPOINT_EVERY:
        raise t.error("checkpoint_every", f"must be <= {MAX_CHECKPOINT_EVERY}, got {every!r}")
    minutes = t.number(
        "checkpoint_minutes", default=10.0, minimum=0.0, maximum=MAX_CHECKPOINT_MINUTES
    )
    return int(every), float(minutes)  # type: ignore[arg-type]


def is_number(value: Any) -> bool:
    """A TOML number (int or float, not a boolean)."""
    return isinstance(value, int | float) and not isinstance(value, bool)


class Table:
    """One TOML table under validation: typed getters that name ``file`` and ``key``."""

    def __init__(self, file: Path, key: str, data: Any, allowed: Sequence[str]) -> None:
        if not isinstance(data, dict):
            raise SceneError(file, key, f"must be a table, got {type(data).__name__}")
        self.file, self.key, self.data = file, key, data
        for name in data:
            if name not in allowed:
                raise SceneError(file, self.path(name), "unknown key" + did_you_mean(name, allowed))

    def path(self, name: str) -> str:
        """The dotted key of entry ``name``."""
        return f"{self.key}.{name}" if self.key else name

    def error(self, name: str, message: str) -> SceneError:
        """A SceneError naming entry ``name``."""
        return SceneError(self.file, self.path(name), message)

    def has(self, name: str) -> bool:
        """Whether the table has entry ``name``."""
        return name in self.data

    def number(
        self,
        name: str,
        *,
        default: float | None = None,
        required: bool = False,
        positive: bool = False,
        integer: bool = False,
        minimum: float | None = None,
        maximum: float | None = None,
    ) -> float | None:
        """A finite number (optionally > 0, >= minimum, <= maximum, an integer), or ``default``."""
        if name not in self.data:
            if required:
                raise self.error(name, "missing (required)")
            return default
        value = self.data[name]
        if not is_number(value) or (integer and not isinstance(value, int)):
            kind = "an integer" if integer else "a number"
            raise self.error(name, f"must be {kind}, got {value!r}")
        if not math.isfinite(value):
            raise self.error(name, f"must be finite, got {value!r}")
        if positive and value <= 0:
            raise self.error(name, f"must be > 0, got {value!r}")
        if minimum is not None and value < minimum:
            raise self.error(name, f"must be >= {minimum:g}, got {value!r}")
        if maximum is not None and value > maximum:
            raise self.error(name, f"must be <= {maximum:g}, got {value!r}")
        return value

    def string(
        self, name: str, *, default: str | None = None, choices: Sequence[str] | None = None
    ) -> str:
        """A string (optionally one of ``choices``); required when ``default`` is None."""
        if name not in self.data:
            if default is None:
                raise self.error(name, "missing (required)")
            return default
        value = self.data[name]
        if not isinstance(value, str):
            raise self.error(name, f"must be a string, got {value!r}")
        if choices is not None and value not in choices:
            raise self.error(name, f"unknown value '{value}'" + did_you_mean(value, choices))
        return value

    def vector(self, name: str, length: int, value: Any = None) -> tuple[float, ...]:
        """A list of ``length`` numbers (``value`` if given, else the entry)."""
        value = self.data[name] if value is None else value
        if not isinstance(value, list) or len(value) != length or not all(map(is_number, value)):
            raise self.error(name, f"must be a list of {length} numbers, got {_short(value)}")
        for i, c in enumerate(value):
            if not math.isfinite(c):
                raise self.error(name, f"entry {i} must be finite, got {c!r}")
        return tuple(float(c) for c in value)

    def boolean(self, name: str, default: bool) -> bool:
        """True or false, ``default`` when absent."""
        value = self.data.get(name, default)
        if not isinstance(value, bool):
            raise self.error(name, f"must be true or false, got {value!r}")
        return value
