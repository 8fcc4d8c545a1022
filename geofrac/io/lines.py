"""Fields sampled along a segment: ``lines/<name>.csv`` and ``lines/<name>.png``.

A line (``[output.lines.NAME]``) is sampled at ``points`` equally spaced points, ends
included. Every sample must lie in the mesh: a point outside stops the run before the
solve (:func:`geofrac.fem.post.locate_line`), so a file never holds a NaN or a silently
shortened line.
The values are those of the probes (:func:`geofrac.fem.post.probe_fields`): the
element's own field in the cell holding the point.
"""

from __future__ import annotations

import csv
from pathlib import Path

import numpy as np
from mpi4py import MPI

from geofrac.errors import RunError
from geofrac.model.fields import field_columns
from geofrac.model.scene import Line, Units

__all__ = ["DIRECTORY", "columns", "sample_points", "write_line"]

#: The sub-directory of the output directory that holds the lines' files.
DIRECTORY = "lines"


def sample_points(line: Line) -> tuple[np.ndarray, np.ndarray]:
    """Distance along the line and coordinates of its samples.

    Returns:
        ``s`` shape=(points,) from 0 to the line's length, and the points padded to 3D,
        shape=(points, 3).
    """
    start, end = np.asarray(line.start, dtype=float), np.asarray(line.end, dtype=float)
    t = np.linspace(0.0, 1.0, line.points)
    xyz = np.zeros((line.points, 3))
    xyz[:, : len(start)] = start + t[:, None] * (end - start)
    return t * float(np.linalg.norm(end - start)), xyz


def columns(fields: tuple[str, ...], gdim: int) -> list[str]:
    """The CSV header: ``s``, the coordinates, then each field's components."""
    return ["s", *"xyz"[:gdim], *(c for f in fields for c in field_columns(f, gdim))]


def write_line(
    directory: Path,
    title: str,
    name: str,
    *,
    line: Line,
    s: np.ndarray,
    xyz: np.ndarray,
    values: dict[str, np.ndarray],
    comm: MPI.Comm,
    units: Units | None = None,
) -> dict[str, object]:
    """Write ``directory/lines/<name>.csv`` and ``.png`` (rank 0; collective errors).

    Args:
        directory: the (staged) output directory.
        title: the scene's name, for the plot's title.
        name: the line's name.
        line: the line.
        s: distance along the line, shape=(points,).
        xyz: sample coordinates, shape=(points, 3).
        values: field -> values, shape=(points, components) (every field of the line).
        comm: the communicator.
        units: the scene's units, for the plot's axes (default SI).

    Returns:
        the summary entry: ``csv``, ``png`` (paths relative to the output directory),
        ``points``, ``fields``, ``start``, ``end``.

    Raises:
        RunError: on every rank when the files cannot be written.
    """
    gdim = len(line.start)
    folder = directory / DIRECTORY
    error = None
    if comm.rank == 0:
        try:
            folder.mkdir(exist_ok=True)
            table = np.column_stack([s, xyz[:, :gdim], *(values[f] for f in line.fields)])
            with open(folder / f"{name}.csv", "w", newline="") as handle:
                writer = csv.writer(handle)
                writer.writerow(columns(line.fields, gdim))
                writer.writerows([repr(float(v)) for v in row] for row in table)
            _plot(
                folder / f"{name}.png",
                f"{title}: line {name}",
                line,
                s,
                values,
                gdim,
                units or Units(),
            )
        except OSError as exc:
            error = f"output.lines.{name}: cannot write {folder}: {exc}"
    error = comm.bcast(error, root=0)
    if error is not None:
        raise RunError(error)
    return {
        "csv": f"{DIRECTORY}/{name}.csv",
        "png": f"{DIRECTORY}/{name}.png",
        "points": line.points,
        "fields": list(line.fields),
        "start": list(line.start),
        "end": list(line.end),
    }


def _plot(
    path: Path,
    title: str,
    line: Line,
    s: np.ndarray,
    values: dict[str, np.ndarray],
    gdim: int,
    units: Units,
) -> None:
    """One panel per field against s; legends outside the axes, so no curve is hidden."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    n = len(line.fields)
    fig = Figure(figsize=(8.0, 2.8 * n + 0.6), layout="constrained")
    FigureCanvasAgg(fig)
    axes = fig.subplots(n, 1, sharex=True, squeeze=False)[:, 0]
    for ax, field in zip(axes, line.fields, strict=True):
        for k, label in enumerate(field_columns(field, gdim)):
            ax.plot(s, values[field][:, k], label=label, marker="." if len(s) <= 30 else None)
        unit = _unit_of(field, units)
        ax.set_ylabel(f"{field.replace('_', ' ')} ({unit})" if unit else field.replace("_", " "))
        ax.grid(True, alpha=0.3)
        ax.ticklabel_format(axis="y", useOffset=False)
        ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize="small")
    start = ", ".join(f"{c:g}" for c in line.start)
    end = ", ".join(f"{c:g}" for c in line.end)
    s_label = units.label("s", "length")
    axes[-1].set_xlabel(f"{s_label}: distance from ({start}) towards ({end})")
    fig.suptitle(title)
    fig.savefig(path, dpi=110)


def _unit_of(field: str, units: Units) -> str:
    """The unit of a sampled field: displacement a length, stress a stress, strain none."""
    if field.startswith("displacement"):
        return units.length
    if field.startswith(("stress", "von_mises")):
        return units.stress
    return "-"
