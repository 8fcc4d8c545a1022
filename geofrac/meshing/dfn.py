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
"""

from __future__ import annotations

import itertools
from collections.abc import Sequence
from dataclasses import dataclass
from types import ModuleType
from typing import Any, Literal

import numpy as np

from geofrac.dfn.clean import CleanNetwork
from geofrac.dfn.polygon import nearest_boundary_point
from geofrac.meshing.geo import ALGORITHMS
from geofrac.meshing.quality import triangle_quality

__all__ = ["ALGORITHMS", "DOMAIN_GROUP", "FRACTURE_GROUP", "MeshSpec", "mesh_network"]

#: Physical group names of the surface and of the fracture lines.
DOMAIN_GROUP = "domain"
FRACTURE_GROUP = "fractures"


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


def mesh_network(
    gmsh: ModuleType,
    clean: CleanNetwork,
    sides: Sequence[str],
    *,
    corners: Sequence[str],
    spec: MeshSpec,
) -> dict[str, Any]:
    """Build the model in an initialised gmsh session, mesh it, report counts and quality.

    Args:
        gmsh: the gmsh module, initialised, with an empty model.
        clean: the network, inside ``clean.domain``.
        sides: physical group name of each polygon side (side k from corner k to k+1).
        corners: physical group name of each polygon corner.
        spec: sizes and algorithm.

    Returns:
        ``nodes``, ``cells``, ``fracture_edges`` (mesh edges on fractures), ``fracture_lines``
        (gmsh curves), and the :func:`~geofrac.meshing.quality.triangle_quality` figures.

    Raises:
        RuntimeError: gmsh failed (its message), or a fracture line was left without mesh
            edges.
    """
    geo = gmsh.model.geo
    gmsh.model.add("dfn")
    points = np.vstack([clean.vertices, clean.domain])
    chains = _boundary_chains(clean)
    used = sorted({v for chain in chains for v in chain} | set(clean.edges.ravel().tolist()))
    tag = {v: geo.addPoint(points[v, 0], points[v, 1], 0.0) for v in used}
    side_lines = [
        [geo.addLine(tag[a], tag[b]) for a, b in itertools.pairwise(chain)] for chain in chains
    ]
    loop = geo.addCurveLoop([c for lines in side_lines for c in lines])
    surface = geo.addPlaneSurface([loop])
    fracture_lines = [geo.addLine(tag[int(a)], tag[int(b)]) for a, b in clean.edges]
    geo.synchronize()
    model = gmsh.model
    if fracture_lines:
        model.mesh.embed(1, fracture_lines, 2, surface)
    model.setPhysicalName(2, model.addPhysicalGroup(2, [surface]), DOMAIN_GROUP)
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
    if fracture_lines and spec.fracture_size < spec.size:
        option.setNumber("Mesh.MeshSizeExtendFromBoundary", 0)
        field = model.mesh.field
        distance = field.add("Distance")
        field.setNumbers(distance, "CurvesList", fracture_lines)
        field.setNumber(distance, "Sampling", 20)
        threshold = field.add("Threshold")
        field.setNumber(threshold, "InField", distance)
        field.setNumber(threshold, "SizeMin", spec.fracture_size)
        field.setNumber(threshold, "SizeMax", spec.size)
        field.setNumber(threshold, "DistMin", 0.0)
        field.setNumber(threshold, "DistMax", spec.transition)
        field.setAsBackgroundMesh(threshold)
    model.mesh.generate(2)

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
    return {
        "nodes": len(node_tags),
        "cells": len(triangles),
        "fracture_lines": len(fracture_lines),
        "fracture_edges": fracture_edges,
        **triangle_quality(coords.reshape(-1, 3), triangles),
    }
