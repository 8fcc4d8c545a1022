"""Reading and writing disc networks: CSV, JSON and whitespace lists, by the file suffix.

CSV (``.csv``): the header ``x,y,z,nx,ny,nz,radius,set`` (or ``x,y,z,nx,ny,nz,radius``:
then every disc is in the set ``"file"``), then one line per disc. Blank lines are
skipped. Sets are numbered in the order their names first appear.

JSON (``.json``)::

    {"fractures": [{"centre": [x, y, z], "normal": [nx, ny, nz], "radius": r,
                    "set": "name"}, ...]}

``"set"`` is optional (default ``"file"``); an optional top-level ``"sets"`` list fixes
the order of the set names (and keeps sets without discs); other top-level keys are
ignored, other keys of a fracture are refused.

Whitespace lists (``.dat``, ``.txt``), as written by dfnWorks- and FracMan-style
tools: one disc per line ``x y z nx ny nz r`` separated by blanks or tabs; ``#`` starts
a comment; blank lines are skipped; every disc is in the set ``"file"``.

Normals need not be unit vectors: they are normalised (a normal within 1e-14 of unit
length is kept as written, so a file saved here reads back bit for bit) and given the
sign rule of :func:`~geofrac.dfn3d.network.canonical_normals`. Numbers are written with
``repr`` precision.

Files are untrusted input: they are parsed as text or JSON (never evaluated), files
larger than :data:`MAX_FILE_BYTES` and anything but a regular file are refused, and every
problem is a :class:`~geofrac.dfn.errors.DfnError` naming the file and the line (CSV,
lists) or the entry ``fractures[k]`` (JSON). Saving writes the given path and nothing else.
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import numpy as np

from geofrac.dfn.errors import DfnError
from geofrac.dfn.sampling import check_set_name
from geofrac.dfn3d.network import DiscNetwork, canonical_normals

__all__ = [
    "CSV_HEADER",
    "DEFAULT_SET",
    "LIST_SUFFIXES",
    "MAX_FILE_BYTES",
    "SUFFIXES",
    "load_discs",
    "save_discs",
]

CSV_HEADER = "x,y,z,nx,ny,nz,radius,set"
#: The set of discs read without a set name.
DEFAULT_SET = "file"
#: Suffixes of the whitespace-separated list format.
LIST_SUFFIXES = (".dat", ".txt")
SUFFIXES = (".csv", ".json", *LIST_SUFFIXES)
#: Files larger than this (50 MB) are refused.
MAX_FILE_BYTES = 50_000_000

_NUMBERS = CSV_HEADER.split(",")[:7]
_JSON_KEYS = ("centre", "normal", "radius", "set")
#: |‖n‖ − 1| up to which a normal is taken as already unit and not divided by its norm.
_UNIT_TOLERANCE = 1e-14

_Rows = tuple[list[list[float]], list[str]]


def _suffix(path: Path) -> str:
    suffix = path.suffix.lower()
    if suffix not in SUFFIXES:
        raise DfnError(
            f"{path}: unknown disc file type {path.suffix!r}, use one of {', '.join(SUFFIXES)}"
        )
    return suffix


# ---------------------------------------------------------------------------- saving


def save_discs(network: DiscNetwork, path: str | Path) -> None:
    """Write a disc network to ``path``, as CSV, JSON or a whitespace list by its suffix.

    The list formats (``.dat``, ``.txt``) do not store set names.

    Args:
        network: the discs.
        path: a ``.csv``, ``.json``, ``.dat`` or ``.txt`` file; overwritten.

    Raises:
        DfnError: another suffix, a set name the CSV format cannot hold, or the file
            cannot be written.
    """
    path = Path(path)
    suffix = _suffix(path)
    if suffix not in LIST_SUFFIXES:  # the list formats do not store names
        for name in network.set_names:
            check_set_name(name, f"{path}: network")
    rows = [
        [*map(float, c), *map(float, n), float(r)]
        for c, n, r in zip(network.centre, network.normal, network.radius, strict=True)
    ]
    names = [network.set_names[i] for i in network.set_index]
    if suffix == ".csv":
        lines = [CSV_HEADER]
        lines += [",".join([*map(repr, row), name]) for row, name in zip(rows, names, strict=True)]
        text = "\n".join(lines) + "\n"
    elif suffix == ".json":
        entries = [
            "    "
            + json.dumps(
                {"centre": row[:3], "normal": row[3:6], "radius": row[6], "set": name},
                allow_nan=False,
            )
            for row, name in zip(rows, names, strict=True)
        ]
        head = json.dumps({"sets": list(network.set_names)})[:-1]
        text = head + ', "fractures": [\n' + ",\n".join(entries) + ("\n" if rows else "")
        text += "]}\n"
    else:
        lines = ["# x y z nx ny nz r  (one disc per line; set names are not stored)"]
        lines += [" ".join(map(repr, row)) for row in rows]
        text = "\n".join(lines) + "\n"
    try:
        path.write_text(text, encoding="utf-8")
    except OSError as exc:
        raise DfnError(f"{path}: cannot write ({exc.strerror or exc})") from exc


# --------------------------------------------------------------------------- loading


def load_discs(path: str | Path) -> DiscNetwork:
    """Read a disc network from a ``.csv``, ``.json``, ``.dat`` or ``.txt`` file.

    Args:
        path: the file.

    Returns:
        The network; sets in the order of first appearance (CSV, JSON without
        ``"sets"``), as listed in ``"sets"`` (JSON), or the one set ``"file"`` (lists).

    Raises:
        DfnError: naming the file and the line or entry: unknown suffix; missing, not a
            regular file, over :data:`MAX_FILE_BYTES`, not UTF-8 or empty (only white
            space); wrong CSV header; wrong column count; a value that is not a number or
            not finite; a zero normal; a radius <= 0; malformed JSON or a wrong JSON
            structure; a bad set name.
    """
    path = Path(path)
    suffix = _suffix(path)
    text = _read_text(path)
    if suffix == ".csv":
        rows, names = _parse_csv(path, text)
        order: list[str] | None = None
    elif suffix == ".json":
        rows, names, order = _parse_json(path, text)
    else:
        rows, names = _parse_list(path, text)
        order = None
    set_names = order if order is not None else list(dict.fromkeys(names))
    lookup = {name: i for i, name in enumerate(set_names)}
    data = np.array(rows, dtype=float).reshape(-1, 7)
    try:
        return DiscNetwork(
            centre=data[:, :3],
            normal=_normals(data[:, 3:6]),
            radius=data[:, 6].copy(),
            set_index=np.array([lookup[name] for name in names], dtype=np.intp),
            set_names=tuple(set_names),
        )
    except ValueError as exc:  # checked row by row already; kept as a guard
        raise DfnError(f"{path}: {exc}") from exc


def _read_text(path: Path) -> str:
    """The file's text, refusing non-regular, oversized, non-UTF-8 and blank files."""
    try:
        if not path.is_file():
            what = "no such file" if not path.exists() else "not a regular file"
            raise DfnError(f"{path}: cannot read ({what})")
        size = path.stat().st_size
        if size > MAX_FILE_BYTES:
            raise DfnError(
                f"{path}: file too large ({size} bytes), the limit is {MAX_FILE_BYTES} bytes "
                "(50 MB)"
            )
        with path.open("rb") as stream:
            raw = stream.read(MAX_FILE_BYTES + 1)
    except OSError as exc:
        raise DfnError(f"{path}: cannot read ({exc.strerror or exc})") from exc
    if len(raw) > MAX_FILE_BYTES:
        raise DfnError(f"{path}: file too large, the limit is {MAX_FILE_BYTES} bytes (50 MB)")
    try:
        text = raw.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        raise DfnError(f"{path}: cannot read, not UTF-8 text ({exc.reason})") from None
    if not text.strip():
        raise DfnError(f"{path}: empty file")
    return text


def _normals(raw: np.ndarray) -> np.ndarray:
    """Unit normals with the sign rule; near-unit ones only flipped, shape=(n, 3)."""
    if not len(raw):
        return raw.copy()
    big = np.max(np.abs(raw), axis=1)
    rescale = (big > 1e100) | (big < 1e-100)  # scaled first: no overflow or underflow
    scaled = raw / np.where(rescale, big, 1.0)[:, None]
    canon = canonical_normals(scaled)
    flipped = np.where((np.sum(canon * scaled, axis=1) < 0.0)[:, None], -raw, raw)
    keep = ~rescale & (np.abs(np.linalg.norm(scaled, axis=1) - 1.0) <= _UNIT_TOLERANCE)
    return np.where(keep[:, None], flipped, canon)


def _disc(values: list[Any], where: str, *, json_types: bool = False) -> list[float]:
    """Seven finite numbers x y z nx ny nz r with a nonzero normal and r > 0.

    Args:
        values: the values as text (CSV, lists) or JSON values, length 7.
        where: file and line or entry, for messages.
        json_types: accept only JSON numbers, not strings.
    """
    out = []
    for column, value in zip(_NUMBERS, values, strict=True):
        if isinstance(value, bool) or (json_types and not isinstance(value, int | float)):
            raise DfnError(f"{where}: {column} = {value!r} is not a number")
        try:
            x = float(value)
        except (TypeError, ValueError, OverflowError):
            raise DfnError(f"{where}: {column} = {value!r} is not a number") from None
        if not math.isfinite(x):
            raise DfnError(f"{where}: {column} = {value!r} is not finite")
        out.append(x)
    if out[3] == out[4] == out[5] == 0.0:
        raise DfnError(f"{where}: zero normal (nx = ny = nz = 0)")
    if out[6] <= 0.0:
        raise DfnError(f"{where}: radius = {values[6]!r} must be > 0")
    return out


def _parse_csv(path: Path, text: str) -> _Rows:
    lines = text.splitlines()
    first = next(i for i, line in enumerate(lines) if line.strip())
    header = [field.strip() for field in lines[first].split(",")]
    with_set = header == CSV_HEADER.split(",")
    if not with_set and header != _NUMBERS:
        raise DfnError(
            f"{path}: line {first + 1}: expected the header {CSV_HEADER!r} (or without "
            f"',set'), got {lines[first].strip()!r}"
        )
    rows: list[list[float]] = []
    names: list[str] = []
    for number, line in enumerate(lines[first + 1 :], start=first + 2):
        if not line.strip():
            continue
        where = f"{path}: line {number}"
        fields = [field.strip() for field in line.split(",")]
        if len(fields) != len(header):
            raise DfnError(f"{where}: expected {len(header)} columns, got {len(fields)}")
        rows.append(_disc(fields[:7], where))
        names.append(check_set_name(fields[7], where) if with_set else DEFAULT_SET)
    return rows, names


def _parse_list(path: Path, text: str) -> _Rows:
    rows: list[list[float]] = []
    for number, line in enumerate(text.splitlines(), start=1):
        fields = line.split("#", 1)[0].split()
        if not fields:
            continue
        where = f"{path}: line {number}"
        if len(fields) != len(_NUMBERS):
            raise DfnError(
                f"{where}: expected {len(_NUMBERS)} columns (x y z nx ny nz r), got {len(fields)}"
            )
        rows.append(_disc(fields, where))
    return rows, [DEFAULT_SET] * len(rows)


def _vector(entry: dict[str, Any], key: str, where: str) -> list[Any]:
    value = entry.get(key)
    if not isinstance(value, list) or len(value) != 3:
        raise DfnError(f"{where}: {key!r} must be a list of 3 numbers, got {value!r}")
    return value


def _parse_json(path: Path, text: str) -> tuple[list[list[float]], list[str], list[str] | None]:
    try:
        data = json.loads(text)
    except json.JSONDecodeError as exc:
        raise DfnError(
            f"{path}: malformed JSON at line {exc.lineno}, column {exc.colno}: {exc.msg}"
        ) from None
    except (ValueError, RecursionError) as exc:  # e.g. an integer of too many digits
        raise DfnError(f"{path}: malformed JSON ({type(exc).__name__}: {exc})") from None
    if not isinstance(data, dict):
        raise DfnError(f"{path}: expected a JSON object, got {type(data).__name__}")
    order = data.get("sets")
    if order is not None:
        if not isinstance(order, list):
            raise DfnError(f"{path}: 'sets' must be a list of set names, got {order!r}")
        for name in order:
            check_set_name(name, f"{path}: sets")
        if len(set(order)) != len(order):
            raise DfnError(f"{path}: set names in 'sets' must be distinct, got {order}")
    fractures = data.get("fractures")
    if not isinstance(fractures, list):
        raise DfnError(
            f"{path}: 'fractures' must be a list of discs, got {type(fractures).__name__}"
        )
    rows: list[list[float]] = []
    names: list[str] = []
    for k, entry in enumerate(fractures):
        where = f"{path}: fractures[{k}]"
        if not isinstance(entry, dict):
            raise DfnError(
                f"{where}: expected an object with centre, normal, radius, got {entry!r}"
            )
        unknown = sorted(set(entry) - set(_JSON_KEYS))
        if unknown:
            raise DfnError(f"{where}: unknown keys {unknown}, expected {list(_JSON_KEYS)}")
        if "radius" not in entry:
            raise DfnError(f"{where}: missing 'radius'")
        values = [*_vector(entry, "centre", where), *_vector(entry, "normal", where)]
        rows.append(_disc([*values, entry["radius"]], where, json_types=True))
        name = check_set_name(entry.get("set", DEFAULT_SET), where)
        if order is not None and name not in order:
            raise DfnError(f"{where}: set {name!r} is not in 'sets' {order}")
        names.append(name)
    return rows, names, order
