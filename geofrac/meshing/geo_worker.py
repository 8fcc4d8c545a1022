"""Child process that runs gmsh on one ``.geo`` file; see :mod:`geofrac.meshing.geo`.

Run as ``python -m geofrac.meshing.geo_worker REQUEST``.
``REQUEST`` is a JSON file: ``mode`` (``"inspect"``, ``"mesh"`` or ``"trial"``),
``path``, ``parameters``, ``answer`` (where to write the JSON answer), for ``"mesh"`` and
``"trial"`` also ``mesh_size``, ``algorithm`` (gmsh's ``Mesh.Algorithm`` number, set
after the file is read so it overrides the file's; null keeps it) and ``dim``, for
``"mesh"`` ``out`` (the ``.msh`` to write), ``options`` (gmsh options set before writing)
and ``verbose``, for ``"trial"`` ``factor`` (the first size factor k >= 1) and ``cells``
(the cells a trial aims at; see :func:`trial_meshes`). The answer is ``{"ok": true, ...}``
(``"inspect"``: ``dim``, ``groups`` as [name, dim] pairs, ``overlaps``, ``order``;
``"trial"``: ``meshes`` as [k, cells] pairs) or ``{"ok": false, "error": ...}``.

Loads gmsh and nothing of MPI, so it is safe to start from an MPI rank.
"""

from __future__ import annotations

import contextlib
import json
import math
import sys
from pathlib import Path
from typing import Any

from geofrac.meshing.geo import failure_message, gmsh_session, inspect_model

__all__ = ["MAX_TRIALS", "main", "run", "trial_meshes"]

#: Most trial meshes one ``"trial"`` request makes.
MAX_TRIALS = 6


def run(request: dict[str, Any]) -> dict[str, Any]:
    """Do what ``request`` asks; the JSON-ready answer."""
    mode = request["mode"]
    verbose = bool(request.get("verbose", False))
    try:
        with gmsh_session(
            Path(request["path"]), request["parameters"], request.get("mesh_size"), verbose=verbose
        ) as gmsh:
            try:
                if mode == "inspect":
                    info = inspect_model(gmsh.model)
                    return {
                        "ok": True,
                        "dim": info.dim,
                        "groups": list(info.groups.items()),
                        "overlaps": [list(o) for o in info.overlaps],
                        "order": info.order,
                    }
                if request.get("algorithm") is not None:
                    gmsh.option.setNumber("Mesh.Algorithm", int(request["algorithm"]))
                if mode == "trial":
                    dim, factor, cells = request["dim"], request["factor"], request["cells"]
                    meshes = trial_meshes(gmsh, int(dim), float(factor), cells=float(cells))
                    return {"ok": True, "meshes": [list(m) for m in meshes]}
                gmsh.model.mesh.generate(int(request["dim"]))
                for name, value in request.get("options", {}).items():
                    gmsh.option.setNumber(name, value)
                gmsh.write(request["out"])
                return {"ok": True}
            except Exception as exc:  # gmsh raises bare Exceptions; its log is still open
                return {"ok": False, "error": failure_message(exc, gmsh)}
    except Exception as exc:  # reading failed: gmsh_session has put the message in exc
        return {"ok": False, "error": str(exc)}


def _cells(model: Any, dim: int) -> int:
    """Elements of dimension ``dim`` in the physical groups of that dimension (DOLFINx's cells)."""
    entities = {
        int(e)
        for _, tag in model.getPhysicalGroups(dim)
        for e in model.getEntitiesForPhysicalGroup(dim, tag)
    }
    return sum(len(t) for e in entities for t in model.mesh.getElements(dim, e)[1])


def trial_meshes(gmsh: Any, dim: int, factor: float, *, cells: float) -> list[tuple[float, int]]:
    """Mesh the open model with every mesh size multiplied by k, until a count is trustworthy.

    The first mesh is made at k = ``factor`` (times the file's own ``Mesh.MeshSizeFactor``).
    A mesh of n < ``cells`` / 2 cells is made again at k' = max(1, k (n / ``cells``)^(1/dim)),
    where n k^dim / k'^dim = ``cells``: a mesh so coarse that its curves bound it has more
    cells than the sizes ask for, so the next mesh has fewer than ``cells``; at k' = 1 it is
    the full mesh. A mesh that gmsh fails to make at k > 1 (too coarse for a detail of the
    geometry) is tried at k / 2. At most :data:`MAX_TRIALS` tries; the finest mesh at
    k > 1 is followed by one at 2k, so that the caller can tell the part of the count that
    does not scale with the sizes (a transfinite or extruded mesh) from the part that does.

    Returns:
        (k, cells) of every mesh made, in order.
    """
    option = gmsh.option
    base = float(option.getNumber("Mesh.MeshSizeFactor"))
    base = base if base > 0 else 1.0

    def mesh(k: float) -> tuple[float, int]:
        gmsh.model.mesh.clear()
        option.setNumber("Mesh.MeshSizeFactor", base * k)
        gmsh.model.mesh.generate(dim)
        return k, _cells(gmsh.model, dim)

    k = max(1.0, factor)
    made: list[tuple[float, int]] = []
    for attempt in range(1, MAX_TRIALS + 1):
        try:
            made.append(mesh(k))
        except Exception:  # gmsh may fail on a mesh too coarse for the geometry's details
            if k > 1.0 and attempt < MAX_TRIALS:
                k = max(1.0, k / 2)
                continue
            if not made:
                raise
            break  # extrapolate from the coarser meshes
        n = made[-1][1]
        if k <= 1.0:
            return made
        if n >= cells / 2:
            break
        k = max(1.0, k * math.pow(max(n, 1) / cells, 1.0 / dim))
    k = min(made)[0]
    with contextlib.suppress(Exception):  # else the caller extrapolates from what it has
        made.append(mesh(2 * k))
    return made


def main(argv: list[str] | None = None) -> int:
    """Read the request named on the command line, write the answer; exit status 0."""
    args = sys.argv[1:] if argv is None else argv
    request = json.loads(Path(args[0]).read_text())
    answer = run(request)
    Path(request["answer"]).write_text(json.dumps(answer))
    return 0


if __name__ == "__main__":
    sys.exit(main())
