"""gmsh on one process: read a parametrised ``.geo``, inspect it, mesh it.

No MPI here. :mod:`geofrac.meshing.distribute` hands the meshed model to DOLFINx.
Parameters reach the ``.geo`` file as parser variables set before the file is merged, so
they override the defaults of its ``DefineConstant[...]`` block and a specimen file stays
runnable on its own in the gmsh GUI. (gmsh's ``-setnumber`` does the same but its values
outlive ``gmsh.finalize()``, so a later scene in the same process would inherit them.)

Geometry files are data: a ``.geo`` file is checked by
:func:`~geofrac.meshing.geo_guard.scan_geo` (unless the scene trusts it) and then read or
meshed by gmsh in a child process (:mod:`geofrac.meshing.geo_worker`, a fresh Python
that loads no MPI) under a time limit, so an endless loop cannot hang ``geofrac check``
or a run, and an ``Exit`` ends only the child. A meshed ``.geo`` comes back as a binary
``.msh`` in a temporary directory (exact coordinates), which :func:`meshed_model` reads
in-process (a ``.msh`` is data) and deletes. :func:`trial_counts` meshes a ``.geo`` file
coarsely in the same child process, under a shorter limit, for the size estimate.
:func:`gmsh_session` is the in-process tool the worker and the Python-API builders (DFN,
terrain) use.
"""

from __future__ import annotations

import json
import os
import re
import subprocess
import sys
import tempfile
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from types import ModuleType
from typing import Any

from geofrac import interrupt
from geofrac.meshing.geo_guard import scan_geo

__all__ = [
    "ALGORITHMS",
    "DEFAULT_MESH_TIME_LIMIT",
    "DEFAULT_READ_TIME_LIMIT",
    "MAX_TIME_LIMIT",
    "TRIAL_TIME_LIMIT",
    "GeoInfo",
    "GmshTimeout",
    "MeshingFailed",
    "define_constants",
    "failure_message",
    "gmsh_session",
    "inspect_geometry",
    "inspect_model",
    "meshed_model",
    "trial_counts",
]

#: gmsh 2D algorithms by name (``Mesh.Algorithm``): a scene's ``geometry.algorithm`` and
#: the ``dfn`` effect's ``algorithm``.
ALGORITHMS = {"frontal-delaunay": 6, "delaunay": 5, "meshadapt": 1}
#: Seconds gmsh may take to read a ``.geo`` file (``geofrac check``) by default.
DEFAULT_READ_TIME_LIMIT = 60.0
#: Seconds gmsh may take to read and mesh a ``.geo`` file (a run) by default.
DEFAULT_MESH_TIME_LIMIT = 600.0
#: Largest ``geometry.time_limit`` a scene may set (one day).
MAX_TIME_LIMIT = 86400.0
#: Seconds the trial meshes of the size estimate may take (less if the scene's
#: ``geometry.time_limit`` is less).
TRIAL_TIME_LIMIT = 20.0

_DEFINE = re.compile(r"DefineConstant\s*\[(.*?)\]\s*;", re.DOTALL)
_NAME = re.compile(r"(?:^|,)\s*([A-Za-z_]\w*)\s*=")
#: Options that make the worker's ``.msh`` an exact copy of the meshed model, whatever the
#: ``.geo`` file set: binary (no rounding of coordinates), every entity and node (node tags
#: stay 1..N as DOLFINx expects), no scaling on save.
_WRITE_OPTIONS = {
    "Mesh.MshFileVersion": 4.1,
    "Mesh.Binary": 1,
    "Mesh.SaveAll": 1,
    "Mesh.SaveParametric": 0,
    "Mesh.SaveTopology": 0,
    "Mesh.PartitionSplitMeshFiles": 0,
    "Mesh.ScalingFactor": 1,
    "Mesh.SaveGroupsOfNodes": 0,
    "Mesh.SaveWithoutOrphans": 0,
}


class GmshTimeout(RuntimeError):
    """gmsh did not finish reading or meshing a geometry within its time limit."""


class MeshingFailed(RuntimeError):
    """gmsh failed without a message; this one says what was being done."""


@dataclass(frozen=True)
class GeoInfo:
    """What a geometry file declares.

    Attributes:
        dim: highest dimension of an entity in the model.
        groups: physical group name -> dimension.
        overlaps: physical groups of one dimension that share a model entity, as
            (dimension, group, other group, entity tag), one per pair.
        order: polynomial order of the geometry of the cells: 1 (straight), 2 (curved,
            ``Mesh.ElementOrder = 2``), ...; from the elements of a meshed file, else from
            the ``Mesh.ElementOrder`` option the ``.geo`` file set.
    """

    dim: int
    groups: dict[str, int]
    overlaps: tuple[tuple[int, str, str, int], ...] = ()
    order: int = 1


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
    *,
    verbose: bool = False,
) -> Iterator[ModuleType]:
    """Initialise gmsh, open ``path`` with ``parameters`` set, yield the gmsh module, finalise.

    In-process and unchecked: production code opens scene ``.geo`` files through
    :func:`inspect_geometry` and :func:`meshed_model`. With ``path`` None the session
    starts empty (a builder adds the model).

    Raises:
        RuntimeError: gmsh could not read the file (message from gmsh).
    """
    import gmsh

    gmsh.initialize(["geofrac", "-nopopup"], readConfigFiles=False)
    interrupt.reassert()  # gmsh reset SIGTERM/SIGINT to their defaults
    try:
        gmsh.option.setNumber("General.Terminal", 1 if verbose else 0)
        gmsh.logger.start()
        if mesh_size is not None:
            gmsh.option.setNumber("Mesh.MeshSizeMax", mesh_size)
        for name, value in parameters.items():
            gmsh.parser.setNumber(name, [float(value)])
        try:
            if path is not None:
                gmsh.merge(str(path))
        except Exception as exc:  # gmsh raises a bare Exception with its parser message
            raise RuntimeError(failure_message(exc, gmsh)) from exc
        yield gmsh
    finally:
        gmsh.finalize()
        interrupt.reassert()


def failure_message(exc: BaseException, gmsh: ModuleType | None = None) -> str:
    """The message of gmsh error ``exc``; if it is empty, the last error gmsh logged, or ``""``."""
    text = str(exc).strip()
    if text or gmsh is None:
        return text
    try:
        log = gmsh.logger.get()
    except Exception:  # the session may be gone
        return ""
    errors = [line for line in log if line.startswith("Error")]
    return errors[-1].split(":", 1)[-1].strip() if errors else ""


def inspect_model(model: Any) -> GeoInfo:
    """Dimension, physical groups, overlapping groups and cell order of the gmsh ``model``."""
    groups: dict[str, int] = {}
    owners: dict[tuple[int, int], str] = {}
    overlaps: dict[tuple[int, str, str], int] = {}
    for d, tag in model.getPhysicalGroups():
        name = model.getPhysicalName(d, tag)
        groups[name] = d
        for entity in model.getEntitiesForPhysicalGroup(d, tag):
            other = owners.setdefault((d, int(entity)), name)
            if other != name:
                overlaps.setdefault((d, other, name), int(entity))
    dim = int(model.getDimension())
    return GeoInfo(
        dim=dim,
        groups=groups,
        overlaps=tuple((d, a, b, e) for (d, a, b), e in overlaps.items()),
        order=_cell_order(model, dim),
    )


def _cell_order(model: Any, dim: int) -> int:
    """Order of the ``dim``-dimensional elements of ``model``.

    A meshed model (a ``.msh`` file) answers with its highest element order; an unmeshed
    one (a ``.geo`` file read without meshing) with the ``Mesh.ElementOrder`` option, which
    the file may have set and which gmsh applies when it meshes.
    """
    import gmsh

    types = model.mesh.getElementTypes(dim) if dim > 0 else []
    if len(types):
        return max(int(model.mesh.getElementProperties(t)[2]) for t in types)
    return int(gmsh.option.getNumber("Mesh.ElementOrder"))


def _python_path() -> str:
    """PYTHONPATH for the worker: this package's parent first."""
    here = str(Path(__file__).resolve().parents[2])
    rest = os.environ.get("PYTHONPATH")
    return here if not rest else here + os.pathsep + rest


def _run_worker(request: dict[str, Any], limit: float, what: str, verbose: bool) -> dict[str, Any]:
    """Run :mod:`geofrac.meshing.geo_worker` on ``request``; its JSON answer.

    Raises:
        GmshTimeout: the child did not finish within ``limit`` seconds (it is killed).
        RuntimeError: gmsh failed (its message), or the child ended without an answer.
    """
    with tempfile.TemporaryDirectory(prefix="geofrac-gmsh-") as tmp:
        answer = Path(tmp) / "answer.json"
        (Path(tmp) / "request.json").write_text(json.dumps({**request, "answer": str(answer)}))
        env = {**os.environ, "PYTHONPATH": _python_path()}
        proc = subprocess.Popen(
            [sys.executable, "-m", "geofrac.meshing.geo_worker", str(Path(tmp) / "request.json")],
            stdin=subprocess.DEVNULL,
            stdout=None if verbose else subprocess.DEVNULL,
            stderr=subprocess.PIPE,
            cwd=tmp,
            env=env,
        )
        try:
            _, err = proc.communicate(timeout=limit)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.communicate()
            raise GmshTimeout(
                f"gmsh did not finish {what} within {limit:g} s (geometry.time_limit)"
            ) from None
        finally:
            if proc.poll() is None:  # interrupted while waiting: take the child with us
                proc.kill()
                proc.wait()
        if answer.is_file():
            result: dict[str, Any] = json.loads(answer.read_text())
            if not result.get("ok"):
                raise RuntimeError(result.get("error", ""))
            return result
        if proc.returncode == 0:
            raise RuntimeError(f"gmsh stopped {what} without finishing (an 'Exit' in the file?)")
        if proc.returncode < 0:
            raise RuntimeError(f"gmsh was killed by signal {-proc.returncode} while {what}")
        lines = (err or b"").decode(errors="replace").strip().splitlines()
        detail = f": {lines[-1]}" if lines else ""
        raise RuntimeError(f"gmsh failed while {what} (exit status {proc.returncode}){detail}")


def inspect_geometry(
    path: Path,
    parameters: dict[str, float],
    time_limit: float | None = None,
    *,
    trusted: bool = False,
) -> GeoInfo:
    """Open a geometry file (no meshing) and report its dimension and physical groups.

    A ``.geo`` file is checked (unless ``trusted``) and read by gmsh in a child process
    within ``time_limit`` seconds (default :data:`DEFAULT_READ_TIME_LIMIT`); a ``.msh`` is
    read in-process.

    Raises:
        GeoRefused: the file does more than describe a geometry.
        GmshTimeout: gmsh did not finish in time.
        RuntimeError: gmsh could not read the file (message from gmsh).
    """
    if path.suffix != ".geo":
        with gmsh_session(path, {}) as gmsh:
            return inspect_model(gmsh.model)
    if not trusted:
        scan_geo(path)
    limit = DEFAULT_READ_TIME_LIMIT if time_limit is None else time_limit
    request = {"mode": "inspect", "path": str(path), "parameters": parameters}
    result = _run_worker(request, limit, f"reading '{path.name}'", verbose=False)
    return GeoInfo(
        dim=result["dim"],
        groups=dict(result["groups"]),
        overlaps=tuple(tuple(o) for o in result["overlaps"]),
        order=int(result["order"]),
    )


@contextmanager
def meshed_model(
    path: Path,
    parameters: dict[str, float],
    mesh_size: float | None,
    *,
    dim: int,
    time_limit: float | None = None,
    trusted: bool = False,
    verbose: bool = False,
    algorithm: str | None = None,
) -> Iterator[ModuleType]:
    """A gmsh session holding the meshed model of ``path``; yields the gmsh module.

    A ``.msh`` file is read as it is. A ``.geo`` file is checked (unless ``trusted``),
    meshed to dimension ``dim`` by gmsh in a child process within ``time_limit`` seconds
    (default :data:`DEFAULT_MESH_TIME_LIMIT`) and written as a binary ``.msh`` to a
    temporary directory, which is read here and deleted. ``algorithm`` (a key of
    :data:`ALGORITHMS`) overrides the ``Mesh.Algorithm`` the ``.geo`` file set; None
    keeps the file's own.

    Raises:
        GeoRefused: the file does more than describe a geometry.
        GmshTimeout: gmsh did not finish in time.
        RuntimeError: gmsh failed (its message, or what was being done when it gave none).
    """
    if path.suffix != ".geo":
        with gmsh_session(path, {}, None, verbose=verbose) as gmsh:
            yield gmsh
        return
    if not trusted:
        scan_geo(path)
    limit = DEFAULT_MESH_TIME_LIMIT if time_limit is None else time_limit
    with tempfile.TemporaryDirectory(prefix="geofrac-mesh-") as tmp:
        out = Path(tmp) / "mesh.msh"
        request = {
            "mode": "mesh",
            "path": str(path),
            "parameters": parameters,
            "mesh_size": mesh_size,
            "algorithm": None if algorithm is None else ALGORITHMS[algorithm],
            "dim": dim,
            "out": str(out),
            "options": _WRITE_OPTIONS,
            "verbose": verbose,
        }
        try:
            _run_worker(request, limit, f"meshing '{path.name}'", verbose)
        except GmshTimeout:
            raise
        except RuntimeError as exc:
            if str(exc).strip():
                raise
            raise MeshingFailed(
                f"meshing {path.name} with parameters {parameters} failed (gmsh gave no "
                f"message; run gmsh {path} -{dim} to see its log)"
            ) from None
        with gmsh_session(out, {}) as gmsh:
            yield gmsh


def trial_counts(
    path: Path,
    parameters: dict[str, float],
    mesh_size: float | None,
    *,
    dim: int,
    factor: float,
    cells: float,
    time_limit: float | None = None,
    trusted: bool = False,
    algorithm: str | None = None,
) -> list[tuple[float, int]]:
    """Cells of trial meshes of a ``.geo`` file with every mesh size multiplied by k >= 1.

    Read as :func:`meshed_model` reads it (``parameters``, ``mesh_size``, ``algorithm``)
    and meshed to dimension ``dim`` by gmsh in a child process, first at k = ``factor``,
    then finer until a mesh has about ``cells`` / 2 cells or more, or k = 1 (the full
    mesh); see :func:`geofrac.meshing.geo_worker.trial_meshes`. Within ``time_limit``
    seconds, at most :data:`TRIAL_TIME_LIMIT`.

    Returns:
        (k, cells in the ``dim``-dimensional physical groups) of every mesh, in order.

    Raises:
        GeoRefused: the file does more than describe a geometry.
        GmshTimeout: gmsh did not finish in time.
        RuntimeError: gmsh failed (its message).
    """
    if not trusted:
        scan_geo(path)
    limit = min(TRIAL_TIME_LIMIT, DEFAULT_READ_TIME_LIMIT if time_limit is None else time_limit)
    request = {
        "mode": "trial",
        "path": str(path),
        "parameters": parameters,
        "mesh_size": mesh_size,
        "algorithm": None if algorithm is None else ALGORITHMS[algorithm],
        "dim": dim,
        "factor": factor,
        "cells": cells,
    }
    result = _run_worker(request, limit, f"trial-meshing '{path.name}'", verbose=False)
    return [(float(k), int(n)) for k, n in result["meshes"]]
