"""gmsh model of a polygonal domain with a fracture network embedded as mesh lines.

One process, no MPI (:mod:`geofrac.meshing.distribute` hands the mesh to DOLFINx). The
input is a :class:`~geofrac.dfn.clean.CleanNetwork`, whose edges meet only at shared
vertices and keep at least the cleaning tolerance apart, so the built-in (``geo``)
kernel can take them as they are: every network vertex becomes a gmsh point, every edge
a line embedded in the surface, and vertices on the boundary split the boundary lines.
gmsh then meshes each embedded line with mesh edges, so every fracture is a chain of
element edges. No OpenCASCADE boolean fragment is needed and no geometry is changed by
gmsh.

Physical groups: ``domain`` (surface), one per polygon side (curves), ``fractures`` (all
fracture lines, one curve group) and one per corner (points).

With regions (:mod:`geofrac.dfn.regions`: the top heading and bench of a tunnel), each
region is a plane surface bounded by its outline, a physical surface group of its name,
and its outline a curve group ``<name>_outline``; ``domain`` is then the rest of the rock,
a surface with the regions as holes. The cleaned network was cut at the outlines
(``clean_network(constraints=...)``), so each fracture line lies in one surface and is
embedded in it, and the outline lines are split at the fracture vertices on them.
"""

from __future__ import annotations

import itertools
from collections.abc import Sequence
from dataclasses import dataclass
from types import ModuleType
from typing import Any, Literal

import numpy as np

from geofrac.dfn.clean import CleanNetwork
from geofrac.dfn.polygon import nearest_boundary_point, point_segment_distance
from geofrac.dfn.regions import RegionLayout, strictly_inside
from geofrac.meshing.geo import ALGORITHMS
from geofrac.meshing.quality import triangle_quality

__all__ = [
    "ALGORITHMS",
    "DOMAIN_GROUP",
    "FRACTURE_GROUP",
    "OUTLINE_SUFFIX",
    "TRIAL_INTEGRATION_PRECISION",
    "MeshSpec",
    "mesh_network",
    "trial_network",
]

#: Physical group names of the surface and of the fracture lines.
DOMAIN_GROUP = "domain"
FRACTURE_GROUP = "fractures"
#: A region's outline is the curve group ``<region name><OUTLINE_SUFFIX>``.
OUTLINE_SUFFIX = "_outline"
#: gmsh ``Mesh.LcIntegrationPrecision`` of the trial meshes (:func:`trial_network`).
TRIAL_INTEGRATION_PRECISION = 1e-4


@dataclass(frozen=True)
class MeshSpec:
    """Element sizes and algorithm.

    Attributes:
        size: element size away from fractures.
        fracture_size: element size on the fractures (<= ``size``).
        transition: distance from the fractures over which the size grows linearly from
            ``fracture_size`` to ``size`` (used when the two differ).
        algorithm: a key of :data:`ALGORITHMS`.
    """

    size: float
    fracture_size: float
    transition: float
    algorithm: Literal["frontal-delaunay", "delaunay", "meshadapt"] = "frontal-delaunay"


def _boundary_chains(clean: CleanNetwork) -> list[list[int]]:
    """Per polygon side, the vertex numbers along it from its first corner to the next.

    Corners get numbers ``num_vertices + k`` unless a network vertex sits on them.
    """
    domain, vertices = clean.domain, clean.vertices
    nv, m = len(vertices), len(domain)
    corner_ids = list(range(nv, nv + m))
    scale = float(np.ptp(domain, axis=0).max())
    on = np.flatnonzero(clean.on_boundary)
    side_of: dict[int, list[tuple[float, int]]] = {k: [] for k in range(m)}
    if len(on):
        _, side, t, _ = nearest_boundary_point(vertices[on], domain)
        for row, v in enumerate(on):
            at_corner = np.flatnonzero(np.hypot(*(domain - vertices[v]).T) <= 1e-12 * scale)
            if len(at_corner):
                corner_ids[int(at_corner[0])] = int(v)
                continue
            side_of[int(side[row])].append((float(t[row]), int(v)))
    return [
        [corner_ids[k]] + [v for _, v in sorted(side_of[k])] + [corner_ids[(k + 1) % m]]
        for k in range(m)
    ]


def _outline_chains(
    clean: CleanNetwork, layout: RegionLayout, first_id: int
) -> tuple[list[list[int]], np.ndarray]:
    """Per outline edge, the point numbers along it; and the extra outline points.

    A point number below ``len(clean.vertices)`` is a network vertex (a fracture ending
    on, crossing or bent through the outline); the outline's own vertices that no
    fracture touches get numbers from ``first_id`` on.

    Returns:
        (chains, one list per layout edge from its first to its second vertex; the
        coordinates of the extra points, shape=(k, 2)).
    """
    vertices = clean.vertices
    eps = 1e-12 * float(np.ptp(clean.domain, axis=0).max())
    ids = np.empty(len(layout.vertices), dtype=np.int64)
    extra: list[np.ndarray] = []
    for k, p in enumerate(layout.vertices):
        hit = np.flatnonzero(np.hypot(*(vertices - p).T) <= eps) if len(vertices) else np.zeros(0)
        if len(hit):
            ids[k] = int(hit[0])
        else:
            ids[k] = first_id + len(extra)
            extra.append(p)
    chains = []
    for u, v in layout.edges:
        chain = [int(ids[u])]
        if len(vertices):
            d, t = point_segment_distance(vertices, layout.vertices[u], layout.vertices[v])
            inner = np.flatnonzero((d <= eps) & (t > 0.0) & (t < 1.0))
            inner = inner[(inner != ids[u]) & (inner != ids[v])]
            chain += inner[np.argsort(t[inner])].tolist()
        chains.append([*chain, int(ids[v])])
    return chains, np.array(extra).reshape(-1, 2)


def _size_field(gmsh: ModuleType, spec: MeshSpec, refined: list[tuple[list[int], float]]) -> None:
    """Size ``spec.size`` growing from finer sizes on lines: (curve tags, size) pairs."""
    refined = [(lines, h) for lines, h in refined if lines and h < spec.size]
    if not refined:
        return
    gmsh.option.setNumber("Mesh.MeshSizeExtendFromBoundary", 0)
    field = gmsh.model.mesh.field
    thresholds = []
    for lines, h in refined:
        distance = field.add("Distance")
        field.setNumbers(distance, "CurvesList", lines)
        field.setNumber(distance, "Sampling", 20)
        threshold = field.add("Threshold")
        field.setNumber(threshold, "InField", distance)
        field.setNumber(threshold, "SizeMin", h)
        field.setNumber(threshold, "SizeMax", spec.size)
        field.setNumber(threshold, "DistMin", 0.0)
        field.setNumber(threshold, "DistMax", spec.transition)
        thresholds.append(threshold)
    background = thresholds[0]
    if len(thresholds) > 1:
        background = field.add("Min")
        field.setNumbers(background, "FieldsList", thresholds)
    field.setAsBackgroundMesh(background)


def _loop_lines(edge_lines: list[list[int]], loop: tuple[np.ndarray, np.ndarray]) -> list[int]:
    """Signed curve tags of a layout loop (edge numbers, forward flags)."""
    out: list[int] = []
    for e, forward in zip(*loop, strict=True):
        lines = edge_lines[int(e)]
        out += lines if forward else [-c for c in reversed(lines)]
    return out


def _surfaces(
    gmsh: ModuleType,
    outer: int,
    *,
    tag: dict[int, int],
    chains: list[list[int]],
    layout: RegionLayout | None,
) -> tuple[int, list[int], list[list[int]]]:
    """The rock's surface and the regions' (with their outline curves), made in ``geo``.

    Returns:
        (rock surface, region surfaces, outline curve tags per region).
    """
    geo = gmsh.model.geo
    if layout is None:
        return geo.addPlaneSurface([outer]), [], []
    edge_lines = [
        [geo.addLine(tag[a], tag[b]) for a, b in itertools.pairwise(chain)] for chain in chains
    ]
    outlines = [[abs(c) for c in _loop_lines(edge_lines, loop)] for loop in layout.loops]
    regions = [
        geo.addPlaneSurface([geo.addCurveLoop(_loop_lines(edge_lines, loop))])
        for loop in layout.loops
    ]
    holes = [geo.addCurveLoop(_loop_lines(edge_lines, hole)) for hole in layout.holes]
    return geo.addPlaneSurface([outer, *holes]), regions, outlines


def _surface_of_edges(clean: CleanNetwork, layout: RegionLayout | None) -> np.ndarray:
    """0 for the rock, k + 1 for region k: where each network edge lies, shape=(num_edges,)."""
    where = np.zeros(len(clean.edges), dtype=np.int64)
    if layout is None or len(clean.edges) == 0:
        return where
    mid = clean.segments.mean(axis=1)
    for k, region in enumerate(layout.regions):
        where[strictly_inside(mid, region.polygon)] = k + 1
    return where


def mesh_network(
    gmsh: ModuleType,
    clean: CleanNetwork,
    sides: Sequence[str],
    *,
    corners: Sequence[str],
    spec: MeshSpec,
    regions: RegionLayout | None = None,
) -> dict[str, Any]:
    """Build the model in an initialised gmsh session, mesh it, report counts and quality.

    Args:
        gmsh: the gmsh module, initialised, with an empty model.
        clean: the network, inside ``clean.domain``; with ``regions``, cleaned with their
            outlines as constraints (``clean_network(constraints=regions.segments)``).
        sides: physical group name of each polygon side (side k from corner k to k+1).
        corners: physical group name of each polygon corner.
        spec: sizes and algorithm.
        regions: named cell regions, or None.

    Returns:
        ``nodes``, ``cells``, ``fracture_edges`` (mesh edges on fractures), ``fracture_lines``
        (gmsh curves), the :func:`~geofrac.meshing.quality.triangle_quality` figures, and
        with regions ``region_cells`` (region name -> triangles).

    Raises:
        RuntimeError: gmsh failed (its message), or a fracture line was left without mesh
            edges.
    """
    fracture_lines, region_surfaces = _build_model(
        gmsh, clean, sides, corners=corners, spec=spec, regions=regions
    )
    gmsh.model.mesh.generate(2)
    return _report(gmsh, fracture_lines, region_surfaces)


def trial_network(
    gmsh: ModuleType,
    clean: CleanNetwork,
    sides: Sequence[str],
    *,
    corners: Sequence[str],
    spec: MeshSpec,
    regions: RegionLayout | None = None,
    factor: float,
    cells: float,
) -> list[tuple[float, int]]:
    """Cells of trial meshes of the model :func:`mesh_network` builds, every size times k >= 1.

    The model (points, lines, size fields, options) is built as for the run, in an
    initialised gmsh session with an empty model, and meshed in 2D by
    :func:`geofrac.meshing.geo_worker.trial_meshes` (the stepping of the ``.geo`` trial):
    first with ``Mesh.MeshSizeFactor`` = ``factor``, then finer until a mesh has about
    ``cells`` / 2 triangles or more, or k = 1 (the full mesh), and the finest mesh at
    k > 1 once more at 2k. The sizes along the curves are integrated to a precision of
    :data:`TRIAL_INTEGRATION_PRECISION` rather than gmsh's 1e-9: the 1D meshing of many
    fracture lines under a size field is then 30 times faster, the triangles about 1 %
    different.

    Returns:
        (k, triangles) of every mesh made, in order.

    Raises:
        Exception: gmsh failed on every mesh it tried (a bare ``Exception`` from gmsh).
    """
    from geofrac.meshing.geo_worker import trial_meshes

    _build_model(gmsh, clean, sides, corners=corners, spec=spec, regions=regions)
    gmsh.option.setNumber("Mesh.LcIntegrationPrecision", TRIAL_INTEGRATION_PRECISION)
    return trial_meshes(gmsh, 2, factor, cells=cells)


def _build_model(
    gmsh: ModuleType,
    clean: CleanNetwork,
    sides: Sequence[str],
    *,
    corners: Sequence[str],
    spec: MeshSpec,
    regions: RegionLayout | None,
) -> tuple[list[int], dict[str, int]]:
    """The model of :func:`mesh_network`, not meshed: (fracture curves, region name -> surface)."""
    geo = gmsh.model.geo
    gmsh.model.add("dfn")
    chains = _boundary_chains(clean)
    first_extra = len(clean.vertices) + len(clean.domain)
    outline_chains, extra = (
        _outline_chains(clean, regions, first_extra) if regions is not None else ([], None)
    )
    points = np.vstack([clean.vertices, clean.domain, *([extra] if extra is not None else [])])
    on_lines = {v for chain in chains + outline_chains for v in chain}
    used = sorted(on_lines | set(clean.edges.ravel().tolist()))
    tag = {v: geo.addPoint(points[v, 0], points[v, 1], 0.0) for v in used}
    side_lines = [
        [geo.addLine(tag[a], tag[b]) for a, b in itertools.pairwise(chain)] for chain in chains
    ]
    loop = geo.addCurveLoop([c for lines in side_lines for c in lines])
    surface, region_surfaces, outlines = _surfaces(
        gmsh, loop, tag=tag, chains=outline_chains, layout=regions
    )
    fracture_lines = [geo.addLine(tag[int(a)], tag[int(b)]) for a, b in clean.edges]
    geo.synchronize()
    model = gmsh.model
    where = _surface_of_edges(clean, regions)
    for k, surf in enumerate([surface, *region_surfaces]):
        lines = [c for c, w in zip(fracture_lines, where, strict=True) if w == k]
        if lines:
            model.mesh.embed(1, lines, 2, surf)
    model.setPhysicalName(2, model.addPhysicalGroup(2, [surface]), DOMAIN_GROUP)
    names = regions.names if regions is not None else ()
    for name, surf, lines in zip(names, region_surfaces, outlines, strict=True):
        model.setPhysicalName(2, model.addPhysicalGroup(2, [surf]), name)
        model.setPhysicalName(1, model.addPhysicalGroup(1, lines), name + OUTLINE_SUFFIX)
    for name, lines in zip(sides, side_lines, strict=True):
        model.setPhysicalName(1, model.addPhysicalGroup(1, lines), name)
    if fracture_lines:
        model.setPhysicalName(1, model.addPhysicalGroup(1, fracture_lines), FRACTURE_GROUP)
    for name, chain in zip(corners, chains, strict=True):
        model.setPhysicalName(0, model.addPhysicalGroup(0, [tag[chain[0]]]), name)

    option = gmsh.option
    option.setNumber("Mesh.MeshSizeMax", spec.size)
    option.setNumber("Mesh.MeshSizeFromPoints", 0)
    option.setNumber("Mesh.MeshSizeFromCurvature", 0)
    option.setNumber("Mesh.Algorithm", ALGORITHMS[spec.algorithm])
    refined = [(fracture_lines, spec.fracture_size)]
    if regions is not None:
        refined += [
            (lines, r.mesh_size or spec.fracture_size)
            for r, lines in zip(regions.regions, outlines, strict=True)
        ]
    _size_field(gmsh, spec, refined)
    return fracture_lines, dict(zip(names, region_surfaces, strict=True))


def _report(
    gmsh: ModuleType, fracture_lines: list[int], region_surfaces: dict[str, int]
) -> dict[str, Any]:
    """Counts and quality of the meshed model (see :func:`mesh_network`)."""
    model = gmsh.model
    node_tags, coords, _ = model.mesh.getNodes()
    index = np.zeros(int(node_tags.max()) + 1, dtype=np.int64)
    index[node_tags.astype(np.int64)] = np.arange(len(node_tags))
    _, tri_nodes = model.mesh.getElementsByType(2)
    triangles = index[tri_nodes.astype(np.int64)].reshape(-1, 3)
    fracture_edges = 0
    for line in fracture_lines:
        _, edge_nodes = model.mesh.getElementsByType(1, line)
        if len(edge_nodes) == 0:
            raise RuntimeError(f"gmsh left fracture line {line} without mesh edges")
        fracture_edges += len(edge_nodes) // 2
    extra: dict[str, Any] = {}
    if region_surfaces:
        extra["region_cells"] = {
            name: len(model.mesh.getElementsByType(2, surf)[0])
            for name, surf in region_surfaces.items()
        }
    return {
        "nodes": len(node_tags),
        "cells": len(triangles),
        "fracture_lines": len(fracture_lines),
        "fracture_edges": fracture_edges,
        **triangle_quality(coords.reshape(-1, 3), triangles),
        **extra,
    }
