"""Reading and writing fracture networks as CSV or JSON, chosen by the file suffix.

CSV (``.csv``): the header line ``set,x0,y0,x1,y1``, then one line per fracture: the set
name and the two endpoints. Blank lines are ignored. Sets are numbered in the order
their names first appear, so a set without fractures is not stored.

JSON (``.json``)::

    {"format": "geofrac-dfn", "version": 1, "sets": ["set1", ...],
     "fractures": [[set_index, x0, y0, x1, y1], ...]}

Numbers are written with ``repr`` precision, so saving and loading gives back the same
floats. Loading checks everything and raises :class:`DfnError` naming the file and the
line (CSV) or the entry (JSON); other keys of the JSON object are ignored.
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import numpy as np

from geofrac.dfn.errors import DfnError
from geofrac.dfn.sampling import Network

__all__ = ["CSV_HEADER", "JSON_FORMAT", "JSON_VERSION", "load_network", "save_network"]

CSV_HEADER = "set,x0,y0,x1,y1"
JSON_FORMAT = "geofrac-dfn"
JSON_VERSION = 1
_COLUMNS = CSV_HEADER.split(",")


def _suffix(path: Path) -> str:
    suffix = path.suffix.lower()
    if suffix not in (".csv", ".json"):
        raise DfnError(f"{path}: unknown network file type {path.suffix!r}, use .csv or .json")
    return suffix


def save_network(network: Network, path: str | Path) -> None:
    """Write a network to ``path``, as CSV or JSON by its suffix.

    Args:
        network: the fractures.
        path: a ``.csv`` or ``.json`` file; overwritten.

    Raises:
        DfnError: another suffix, or the file cannot be written.
    """
    path = Path(path)
    suffix = _suffix(path)
    rows: list[tuple[int, *tuple[float, ...]]] = [
        (int(i), *(float(v) for v in seg.ravel()))
        for i, seg in zip(network.set_index, network.segments, strict=True)
    ]
    if suffix == ".csv":
        lines = [CSV_HEADER]
        lines += [
            ",".join([network.set_names[row[0]], *(repr(v) for v in row[1:])]) for row in rows
        ]
        text = "\n".join(lines) + "\n"
    else:
        head = json.dumps(
            {"format": JSON_FORMAT, "version": JSON_VERSION, "sets": list(network.set_names)}
        )
        body = ",\n".join("    " + json.dumps(list(row), allow_nan=False) for row in rows)
        text = head[:-1] + ', "fractures": [\n' + body + ("\n" if rows else "") + "]}\n"
    try:
        path.write_text(text, encoding="utf-8")
    except OSError as exc:
        raise DfnError(f"{path}: cannot write ({exc.strerror or exc})") from exc


def load_network(path: str | Path) -> Network:
    """Read a network written by :func:`save_network` (or by hand in the same format).

    Args:
        path: a ``.csv`` or ``.json`` file.

    Returns:
        The network; set order as first appearing (CSV) or as listed (JSON).

    Raises:
        DfnError: naming the file and the line or entry: unknown suffix, unreadable or
            empty file, wrong or missing header, wrong column count, a value that is not
            a finite number, a zero-length fracture, malformed JSON, unknown format or
            version, a bad set list, a set index out of range.
    """
    path = Path(path)
    suffix = _suffix(path)
    try:
        text = path.read_text(encoding="utf-8-sig")
    except OSError as exc:
        raise DfnError(f"{path}: cannot read ({exc.strerror or exc})") from exc
    except UnicodeDecodeError as exc:
        raise DfnError(f"{path}: cannot read, not UTF-8 text ({exc.reason})") from exc
    if not text.strip():
        raise DfnError(f"{path}: empty file")
    segments, index, names = _parse_csv(path, text) if suffix == ".csv" else _parse_json(path, text)
    try:
        return Network(
            segments=np.array(segments, dtype=float).reshape(-1, 2, 2),
            set_index=np.array(index, dtype=np.intp),
            set_names=tuple(names),
        )
    except DfnError as exc:
        raise DfnError(f"{path}: {exc}") from exc


def _coordinates(values: list[Any], where: str, json_types: bool = False) -> list[float]:
    """Four finite coordinates of a fracture of non-zero length.

    Args:
        values: x0, y0, x1, y1 as text (CSV) or JSON values, length 4.
        where: file and line or entry, for messages.
        json_types: accept only JSON numbers, not strings.
    """
    out = []
    for column, value in zip(_COLUMNS[1:], values, strict=True):
        if isinstance(value, bool) or (json_types and not isinstance(value, int | float)):
            raise DfnError(f"{where}: {column} = {value!r} is not a number")
        try:
            x = float(value)
        except (TypeError, ValueError):
            raise DfnError(f"{where}: {column} = {value!r} is not a number") from None
        if not math.isfinite(x):
            raise DfnError(f"{where}: {column} = {value!r} is not finite")
        out.append(x)
    if out[0] == out[2] and out[1] == out[3]:
        raise DfnError(f"{where}: zero-length fracture, both endpoints at ({out[0]}, {out[1]})")
    return out


def _parse_csv(path: Path, text: str) -> tuple[list[list[float]], list[int], list[str]]:
    lines = text.splitlines()
    first = next(i for i, line in enumerate(lines) if line.strip())
    header = lines[first].strip()
    if header != CSV_HEADER:
        raise DfnError(
            f"{path}: line {first + 1}: expected the header {CSV_HEADER!r}, got {header!r}"
        )
    segments: list[list[float]] = []
    index: list[int] = []
    names: dict[str, int] = {}
    for number, line in enumerate(lines[first + 1 :], start=first + 2):
        if not line.strip():
            continue
        where = f"{path}: line {number}"
        fields = line.strip().split(",")
        if len(fields) != len(_COLUMNS):
            raise DfnError(f"{where}: expected {len(_COLUMNS)} columns, got {len(fields)}")
        name = fields[0].strip()
        if not name:
            raise DfnError(f"{where}: empty set name")
        segments.append(_coordinates([f.strip() for f in fields[1:]], where))
        index.append(names.setdefault(name, len(names)))
    return segments, index, list(names)


def _parse_json(path: Path, text: str) -> tuple[list[list[float]], list[int], list[str]]:
    try:
        data = json.loads(text)
    except json.JSONDecodeError as exc:
        raise DfnError(
            f"{path}: malformed JSON at line {exc.lineno}, column {exc.colno}: {exc.msg}"
        ) from None
    if not isinstance(data, dict):
        raise DfnError(f"{path}: expected a JSON object, got {type(data).__name__}")
    if data.get("format") != JSON_FORMAT:
        raise DfnError(f"{path}: unknown format {data.get('format')!r}, expected {JSON_FORMAT!r}")
    version = data.get("version")
    if isinstance(version, bool) or version != JSON_VERSION:
        raise DfnError(f"{path}: unsupported version {version!r}, expected {JSON_VERSION}")
    names = data.get("sets")
    if not isinstance(names, list) or not all(isinstance(n, str) for n in names):
        raise DfnError(f"{path}: 'sets' must be a list of set names, got {names!r}")
    fractures = data.get("fractures")
    if not isinstance(fractures, list):
        raise DfnError(f"{path}: 'fractures' must be a list, got {type(fractures).__name__}")
    segments: list[list[float]] = []
    index: list[int] = []
    for k, entry in enumerate(fractures):
        where = f"{path}: fractures[{k}]"
        if not isinstance(entry, list) or len(entry) != len(_COLUMNS):
            raise DfnError(
                f"{where}: expected [set_index, x0, y0, x1, y1] ({len(_COLUMNS)} values), "
                f"got {entry!r}"
            )
        i = entry[0]
        if isinstance(i, bool) or not isinstance(i, int):
            raise DfnError(f"{where}: set index {i!r} is not an integer")
        if not 0 <= i < len(names):
            raise DfnError(
                f"{where}: set index {i} out of range, {len(names)} sets "
                f"(valid indices 0..{len(names) - 1})"
            )
        segments.append(_coordinates(entry[1:], where, json_types=True))
        index.append(i)
    return segments, index, names
