"""gmsh sessions on one process: read a parametrised ``.geo``, inspect it, mesh it.

No MPI here. :mod:`geofrac.meshing.distribute` hands the meshed model to DOLFINx.
Parameters reach the ``.geo`` file as parser variables set before the file is merged, so
they override the defaults of its ``DefineConstant[...]`` block and a specimen file stays
runnable on its own in the gmsh GUI. (gmsh's ``-setnumber`` does the same but its values
outlive ``gmsh.finalize()``, so a later scene in the same process would inherit them.)
"""

from __future__ import annotations

import re
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path

__all__ = ["GeoInfo", "define_constants", "gmsh_session", "inspect_geometry"]

_DEFINE = re.compile(r"DefineConstant\s*\[(.*?)\]\s*;", re.DOTALL)
_NAME = re.compile(r"(?:^|,)\s*([A-Za-z_]\w*)\s*=")


@dataclass(frozen=True)
class GeoInfo:
    """What a geometry file declares.

    Attributes:
        dim: highest dimension of an entity in the model.
        groups: physical group name -> dimension.
    """

    dim: int
    groups: dict[str, int]


def define_constants(text: str) -> list[str]:
    """Names declared in the ``DefineConstant[...]`` blocks of ``.geo`` source ``text``."""
    names: list[str] = []
    for block in _DEFINE.findall(text):
        depth, flat = 0, []
        for ch in block:  # blank out nested {...} so only top-level "name =" matches
            depth += ch == "{"
            flat.append(ch if depth == 0 else " ")
            depth -= ch == "}"
        names += _NAME.findall("".join(flat))
    return names


@contextmanager
def gmsh_session(
    path: Path | None,
    parameters: dict[str, float],
    mesh_size: float | None = None,
    verbose: bool = False,
) -> Iterator[object]:
    """Initialise gmsh, open ``path`` with ``parameters`` set, yield the gmsh module, finalise.

    With ``path`` None the session starts empty (a builder adds the model).

    Raises:
        RuntimeError: gmsh could not read the file (message from gmsh).
    """
    import gmsh

    gmsh.initialize(["geofrac", "-nopopup"], readConfigFiles=False)
    try:
        gmsh.option.setNumber("General.Terminal", 1 if verbose else 0)
        if mesh_size is not None:
            gmsh.option.setNumber("Mesh.MeshSizeMax", mesh_size)
        for name, value in parameters.items():
            gmsh.parser.setNumber(name, [float(value)])
        try:
            if path is not None:
                gmsh.merge(str(path))
        except Exception as exc:  # gmsh raises a bare Exception with its parser message
            raise RuntimeError(str(exc)) from exc
        yield gmsh
    finally:
        gmsh.finalize()


def inspect_geometry(path: Path, parameters: dict[str, float]) -> GeoInfo:
    """Open a geometry file (no meshing) and report its dimension and physical groups."""
    with gmsh_session(path, parameters) as gmsh:
        model = gmsh.model  # type: ignore[attr-defined]
        groups = {model.getPhysicalName(d, t): d for d, t in model.getPhysicalGroups()}
        return GeoInfo(dim=int(model.getDimension()), groups=groups)
