"""``summary.json``: what ran, on what, how long each phase took, and the key results.

Keys (contract, documented in docs/output.md): ``scene``, ``versions``, ``ranks``,
``mesh`` {``cells``, ``vertices``}, ``dofs``, ``timings_s`` {phase: seconds},
``results`` {``probes``: {name: [values]}, ...}, ``status`` (``"ok"`` or the error).
"""

from __future__ import annotations

import datetime as dt
import json
import platform
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import geofrac

__all__ = [
    "finish_summary",
    "prepare_output",
    "start_summary",
    "versions",
    "write_json",
]


def versions(fem: bool = True) -> dict[str, str]:
    """Versions of geofrac and the stack it runs on.

    ``fem=False`` (MPM runs) leaves out DOLFINx and PETSc, which such a run never imports.
    """
    out = {"geofrac": geofrac.__version__, "python": platform.python_version()}
    try:
        import gmsh
        import numpy
        from mpi4py import MPI

        out |= {
            "mpi": MPI.Get_library_version().splitlines()[0].strip(),
            "gmsh": gmsh.__version__,
            "numpy": numpy.__version__,
        }
        if fem:
            import dolfinx_solver  # noqa: F401

            import dolfinx
            from petsc4py import PETSc

            out |= {
                "dolfinx": dolfinx.__version__,
                "petsc": ".".join(map(str, PETSc.Sys.getVersion())),
            }
    except ImportError as exc:  # pragma: no cover - the stack is a hard dependency
        out["error"] = str(exc)
    return out


def write_json(path: Path, data: dict[str, Any]) -> None:
    """Write ``data`` as indented JSON atomically (a reader never sees half a file)."""
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(path.name + ".tmp")
    tmp.write_text(json.dumps(data, indent=2, default=str) + "\n")
    tmp.replace(path)


def prepare_output(directory: Path, names: Sequence[str], comm: Any) -> str | None:
    """Create ``directory`` and remove a previous run's ``names`` in it (rank 0; collective).

    Returns:
        None, or on every rank the message of the failure (``output.dir: ...``).
    """
    error = None
    if comm.rank == 0:
        try:
            directory.mkdir(parents=True, exist_ok=True)
            for name in names:
                (directory / name).unlink(missing_ok=True)
        except OSError as exc:
            error = f"output.dir: cannot prepare {directory}: {exc.strerror}"
    return comm.bcast(error, root=0)


def start_summary(scene: Any, comm: Any, fem: bool = True, **details: Any) -> dict[str, Any]:
    """The head of a run's ``summary.json``: the scene, warnings, versions, ranks, start.

    Args:
        scene: the validated scene.
        comm: the communicator (its size is recorded).
        fem: whether the run uses DOLFINx (``versions(fem)``).
        details: extra entries of ``summary["scene"]`` (e.g. ``method``, ``element``).
    """
    return {
        "scene": {
            "path": str(scene.path),
            "sha256": scene.sha256,
            "name": scene.name,
            "effects": list(scene.effect_names),
            **details,
            "input": scene.raw,
        },
        "warnings": list(scene.warnings),
        "versions": versions(fem=fem),
        "ranks": comm.size,
        "started": dt.datetime.now(dt.UTC).isoformat(timespec="seconds"),
    }


def finish_summary(summary: dict[str, Any], path: Path, comm: Any, timings: Any) -> None:
    """Add the reduced phase timings and the finish time; rank 0 writes ``path`` (collective)."""
    summary["timings_s"] = timings.reduced(comm)
    summary["finished"] = dt.datetime.now(dt.UTC).isoformat(timespec="seconds")
    if comm.rank == 0:
        write_json(path, summary)
