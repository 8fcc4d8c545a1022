"""Typed access to one TOML table of a scene, with errors naming the file and key."""

from __future__ import annotations

import math
import re
from collections.abc import Sequence
from pathlib import Path
from typing import Any, overload

from geofrac.model.errors import SceneError, did_you_mean

__all__ = [
    "MAX_CHECKPOINT_EVERY",
    "MAX_CHECKPOINT_MINUTES",
    "MAX_DEPTH",
    "MAX_INTEGER",
    "MAX_NAME_LENGTH",
    "Table",
    "check_name",
    "checkpoint_keys",
    "finite",
    "first_too_deep",
    "is_name",
    "is_number",
    "output_directory",
    "short",
]

#: Upper limits of ``output.checkpoint_every`` (events or steps) and ``checkpoint_minutes``.
MAX_CHECKPOINT_EVERY = 10**9
MAX_CHECKPOINT_MINUTES = 1e6
#: Largest magnitude of a TOML integer (TOML's own range: signed 64 bits).
MAX_INTEGER = 2**63 - 1
#: Deepest nesting of tables and lists a scene may have (the deepest valid key,
#: ``blocks.terrain.zones[i].centre[j]``, is 5 levels down).
MAX_DEPTH = 16
#: Longest scene name.
MAX_NAME_LENGTH = 100
_NAME = re.compile(r"[A-Za-z0-9_-][A-Za-z0-9._-]*")


def short(value: Any, limit: int = 80) -> str:
    """``repr(value)`` cut to ``limit`` characters (a huge list makes no readable error)."""
    if isinstance(value, list | dict) and len(value) > limit:
        return f"a {type(value).__name__} of {len(value)} entries"
    try:
        text = repr(value)
    except (RecursionError, ValueError):  # nested too deeply; int too long to print
        return f"a {type(value).__name__} nested too deeply"
    return text if len(text) <= limit else text[: limit - 3] + "..."


def finite(value: Any) -> bool:
    """Whether a TOML number is finite and within TOML's integer range (no NaN, no inf)."""
    if isinstance(value, int):
        return abs(value) <= MAX_INTEGER
    return math.isfinite(value)


def first_too_deep(data: Any, limit: int = MAX_DEPTH) -> str | None:
    """The dotted key of the first entry nested deeper than ``limit``, or None.

    Iterative, so a TOML file of 10,000 nested lists does not exhaust Python's stack.
    """
    stack: list[tuple[str, Any, int]] = [("", data, 0)]
    while stack:
        key, node, depth = stack.pop()
        if depth > limit:
            return key or "(top level)"
        if isinstance(node, dict):
            items = [(f"{key}.{k}" if key else str(k), v) for k, v in node.items()]
        elif isinstance(node, list):
            items = [(f"{key}[{i}]", v) for i, v in enumerate(node)]
        else:
            continue
        stack.extend((k, v, depth + 1) for k, v in reversed(items))
    return None


def checkpoint_keys(t: Table) -> tuple[int, float]:
    """``checkpoint_every`` (default 0: off), ``checkpoint_minutes`` (default 10) of ``t``."""
    every = t.number("checkpoint_every", default=0, integer=True, minimum=0)
    if every is not None and every > MAX_CHECKPOINT_EVERY:
        raise t.error("checkpoint_every", f"must be <= {MAX_CHECKPOINT_EVERY}, got {every!r}")
    minutes = t.number(
        "checkpoint_minutes", default=10.0, minimum=0.0, maximum=MAX_CHECKPOINT_MINUTES
    )
    return int(every), float(minutes)


def is_name(text: str) -> bool:
    """A safe file name: 1 to 100 letters, digits, ``-``, ``_``, ``.``, not starting with ``.``."""
    return len(text) <= MAX_NAME_LENGTH and _NAME.fullmatch(text) is not None


def check_name(file: Path, name: str, *, given: bool) -> str:
    """A scene name is a name, not a path: letters, digits, ``-``, ``_``, ``.``.

    No leading dot (so neither ``.`` nor ``..``), no ``/``, 1 to 100 characters.
    ``given``: the scene sets ``name`` (else it is the file's stem).
    """
    if is_name(name):
        return name
    what = f"{short(name)}" if given else f"the file stem {short(name)} (the default)"
    raise SceneError(
        file,
        "name",
        f"{what} is not a scene name: use 1 to {MAX_NAME_LENGTH} letters, digits, '-', '_' "
        "or '.', not starting with '.' (the name becomes results/<name>)",
    )


def output_directory(t: Table, name: str, out: Path | None, *, trusted: bool = False) -> Path:
    """The absolute output directory: ``out``, else ``[output] dir``, else ``results/<name>``.

    ``out`` is ``--out``. A ``dir`` from the scene file must be relative without ``..``
    (it stays inside the working directory tree: a scene cannot write over ``~/.ssh`` or
    ``/etc``); one set on the command line (``--set output.dir=...``, ``trusted``) may be
    anything.
    """
    if not t.has("dir"):
        return (out if out is not None else Path("results") / name).resolve()
    text = t.string("dir")  # checked even when --out replaces it: check and run agree
    if not text.strip() or "\0" in text:
        raise t.error("dir", f"must be a directory path, got {short(text)}")
    path = Path(text)
    if not trusted and (path.is_absolute() or ".." in path.parts or text.startswith("~")):
        raise t.error(
            "dir",
            f"{short(text)} leaves the working directory; a scene's output.dir must be "
            "relative without '..' (pass --out DIR for any other place)",
        )
    return (out if out is not None else path).resolve()


def is_number(value: Any) -> bool:
    """A TOML number (int or float, not a boolean)."""
    return isinstance(value, int | float) and not isinstance(value, bool)


class Table:
    """One TOML table under validation: typed getters that name ``file`` and ``key``."""

    def __init__(self, file: str | Path, key: str, data: Any, *, allowed: Sequence[str]) -> None:
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

    @overload
    def number(
        self,
        name: str,
        *,
        default: float,
        required: bool = ...,
        positive: bool = ...,
        integer: bool = ...,
        minimum: float | None = ...,
        maximum: float | None = ...,
    ) -> float: ...
    @overload
    def number(
        self,
        name: str,
        *,
        default: None = ...,
        required: bool = ...,
        positive: bool = ...,
        integer: bool = ...,
        minimum: float | None = ...,
        maximum: float | None = ...,
    ) -> float | None: ...
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
            raise self.error(name, f"must be {kind}, got {short(value)}")
        if not finite(value):
            raise self.error(name, f"must be finite, got {short(value)}")
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
            raise self.error(name, f"must be a string, got {short(value)}")
        if choices is not None and value not in choices:
            raise self.error(name, f"unknown value {short(value)}" + did_you_mean(value, choices))
        return value

    def vector(self, name: str, length: int, value: Any = None) -> tuple[float, ...]:
        """A list of ``length`` finite numbers (``value`` if given, else the entry).

        A NaN or infinite entry is an error naming the key and the entry's index.
        """
        value = self.data[name] if value is None else value
        if not isinstance(value, list) or len(value) != length or not all(map(is_number, value)):
            raise self.error(name, f"must be a list of {length} numbers, got {short(value)}")
        for i, c in enumerate(value):
            if not finite(c):
                raise self.error(name, f"entry {i} must be finite, got {short(c)}")
        return tuple(float(c) for c in value)

    def names(
        self,
        name: str,
        choices: Sequence[str],
        default: Sequence[str],
        *,
        kind: str = "field",
        empty: bool = True,
    ) -> tuple[str, ...]:
        """A list of distinct names from ``choices`` (``default`` when absent).

        ``kind`` names an entry in the error for an unknown one; ``empty``: whether the
        list may be empty.
        """
        value = self.data.get(name, list(default))
        if (
            not isinstance(value, list)
            or (not empty and not value)
            or not all(isinstance(f, str) for f in value)
            or len(set(value)) != len(value)
        ):
            raise self.error(name, f"must be a list of distinct names from {list(choices)}")
        for f in value:
            if f not in choices:
                raise self.error(name, f"unknown {kind} {f!r}" + did_you_mean(f, choices))
        return tuple(value)

    def boolean(self, name: str, *, default: bool) -> bool:
        """True or false, ``default`` when absent."""
        value = self.data.get(name, default)
        if not isinstance(value, bool):
            raise self.error(name, f"must be true or false, got {short(value)}")
        return value
