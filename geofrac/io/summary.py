"""``summary.json``: what ran, on what, how long each phase took, and the key results.

Keys (contract, documented in docs/output.md): ``scene``, ``versions``, ``ranks``,
``mesh`` {``cells``, ``vertices``}, ``dofs``, ``timings_s`` {phase: seconds},
``results`` {``probes``: {name: [values]}, ...}, ``status`` (``"ok"`` or the error).
"""

from __future__ import annotations

import json
import platform
from pathlib import Path
from typing import Any

import geofrac

__all__ = ["versions", "write_json"]


def versions() -> dict[str, str]:
    """Versions of geofrac and the stack it runs on."""
    out = {"geofrac": geofrac.__version__, "python": platform.python_version()}
    try:
        import dolfinx_solver  # noqa: F401

        import dolfinx
        import gmsh
        import numpy
        from mpi4py import MPI
        from petsc4py import PETSc

        out |= {
            "dolfinx": dolfinx.__version__,
            "petsc": ".".join(map(str, PETSc.Sys.getVersion())),
            "mpi": MPI.Get_library_version().splitlines()[0].strip(),
            "gmsh": gmsh.__version__,
            "numpy": numpy.__version__,
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
