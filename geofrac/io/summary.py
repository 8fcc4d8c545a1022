"""``summary.json``: what ran, on what, how long each phase took, and the key results.

Keys (contract, documented in docs/output.md): ``scene``, ``versions``, ``ranks``,
``mesh`` {``cells``, ``vertices``}, ``dofs``, ``timings_s`` {phase: seconds},
``results`` {``probes``: {name: [values]}, ...}, ``status`` (``"ok"`` or the error).
"""

from __future__ import annotations

import datetime as dt
import json
import os
import platform
import tempfile
from pathlib import Path
from typing import Any

import geofrac

__all__ = [
    "finish_summary",
    "start_summary",
    "versions",
    "write_json",
]


_UMASK = os.umask(0o022)
os.umask(_UMASK)


def versions(*, fem: bool = True) -> dict[str, str]:
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

            from geofrac.solvers import petsc_version

            out |= {"dolfinx": dolfinx.__version__, "petsc": petsc_version()}
    except ImportError as exc:  # pragma: no cover - the stack is a hard dependency
        out["error"] = str(exc)
    return out


def write_json(path: Path, data: dict[str, Any] | list[dict[str, Any]]) -> None:
    """Write ``data`` as indented JSON atomically (a reader never sees half a file)."""
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, name = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    try:
        os.fchmod(fd, 0o666 & ~_UMASK)  # as a plain open() would create it
        with os.fdopen(fd, "w") as f:
            f.write(json.dumps(data, indent=2, default=str) + "\n")
        os.replace(name, path)
    except BaseException:
        Path(name).unlink(missing_ok=True)
        raise


def start_summary(scene: Any, comm: Any, *, fem: bool = True, **details: Any) -> dict[str, Any]:
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
            "description": scene.description,
            "overrides": list(getattr(scene, "overrides", ())),
            "effects": list(scene.effect_names),
            **details,
            "input": scene.raw,
        },
        "warnings": list(scene.warnings),
        "versions": versions(fem=fem),
        "ranks": comm.size,
        "started": dt.datetime.now(dt.UTC).isoformat(timespec="seconds"),
    }


def finish_summary(summary: dict[str, Any], path: Path, comm: Any, *, timings: Any) -> None:
    """Add the reduced phase timings and the finish time; rank 0 writes ``path`` (collective)."""
    summary["timings_s"] = timings.reduced(comm)
    summary["finished"] = dt.datetime.now(dt.UTC).isoformat(timespec="seconds")
    if comm.rank == 0:
        write_json(path, summary)
