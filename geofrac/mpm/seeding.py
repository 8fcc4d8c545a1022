"""Particles of an MPM scene: a regular lattice, or one particle per gmsh cell.

``from_cells`` is pure numpy (centroids and measures of triangles or tetrahedra);
``mesh_cells`` runs gmsh (no MPI, no DOLFINx) to mesh a scene geometry and return the
cells of its top-dimensional physical groups.
"""

from __future__ import annotations

from math import factorial
from pathlib import Path

import numpy as np

from geofrac.mpm.particles import Particles, lattice, particles

__all__ = ["COLUMN_TOL", "from_cells", "from_lattice", "geostatic", "mesh_cells"]

#: Tolerance of :func:`geostatic`'s columns and layers, relative to the column width
#: (the cell size): particles whose heights differ by at most this are one layer, and a
#: particle within it below a column's edge belongs to the column above the edge. The
#: centroids of a mesh's cells carry round-off of a few ulps of the coordinates; without
#: it, two particles of one row of cells would be two layers (the lower one bearing the
#: upper one's whole weight instead of half) or change column with the round-off.
COLUMN_TOL = 1e-9


def from_lattice(
    lower: tuple[float, ...], counts: tuple[int, ...], spacing: float, *, density: float
) -> Particles:
    """Particles on a regular lattice (one per lattice cell, at its centre)."""
    return lattice(list(lower), list(counts), spacing, density=density)


def from_cells(points: np.ndarray, cells: np.ndarray, density: np.ndarray) -> Particles:
    """One particle per simplex, at its centroid, with its area (volume).

    The GIMP half-width of a particle is half the side of the square (cube) of the same
    measure, in every direction.

    Args:
        points: vertex coordinates, shape=(num_points, dim).
        cells: vertex ids per simplex, shape=(num_cells, dim + 1).
        density: initial density per cell, shape=(num_cells,).
    """
    dim = points.shape[1]
    corners = points[cells]  # shape=(num_cells, dim + 1, dim)
    edges = corners[:, 1:, :] - corners[:, :1, :]
    measure = np.abs(np.linalg.det(edges)) / factorial(dim)
    if np.any(measure <= 0):
        raise ValueError(f"{int(np.sum(measure <= 0))} degenerate cell(s) in the particle mesh")
    half = 0.5 * measure ** (1.0 / dim)
    return particles(
        corners.mean(axis=1), measure, density, lp0=np.repeat(half[:, None], dim, axis=1)
    )


def mesh_cells(
    file: Path,
    parameters: dict[str, float],
    mesh_size: float | None,
    *,
    dim: int,
    curve: str | None = None,
    time_limit: float | None = None,
    trusted: bool = False,
    algorithm: str | None = None,
) -> tuple[dict[str, tuple[np.ndarray, np.ndarray]], np.ndarray | None]:
    """Mesh a gmsh geometry; the simplices of each ``dim``-D physical group, and a curve.

    A ``.geo`` file is checked (unless ``trusted``) and meshed by gmsh in a child process
    within ``time_limit`` seconds (:func:`geofrac.meshing.geo.meshed_model`), with the 2D
    ``algorithm`` overriding the file's (None: the file's).

    Returns:
        (group name -> (vertex coordinates shape=(num_points, dim), simplices
        shape=(num_cells, dim + 1) indexing them); the mesh nodes of the physical curve
        group ``curve`` sorted by x, shape=(k, 2), or None without ``curve``).

    Raises:
        RuntimeError: gmsh failed or timed out, or a group holds cells other than simplices.
        ValueError: the ``.geo`` file does more than describe a geometry
            (:class:`~geofrac.meshing.geo_guard.GeoRefused`).
    """
    from geofrac.meshing.geo import meshed_model

    simplex = {2: 2, 3: 4}[dim]  # gmsh element types: 3-node triangle, 4-node tetrahedron
    out = {}
    with meshed_model(
        file,
        parameters,
        mesh_size,
        dim=dim,
        time_limit=time_limit,
        trusted=trusted,
        algorithm=algorithm,
    ) as gmsh:
        model = gmsh.model
        tags, coords, _ = model.mesh.getNodes()
        xyz = coords.reshape(-1, 3)[:, :dim]
        index = np.zeros(int(tags.max()) + 1, dtype=np.int64)
        index[tags.astype(np.int64)] = np.arange(len(tags))
        for d, group in model.getPhysicalGroups(dim):
            name = model.getPhysicalName(d, group)
            blocks = []
            for entity in model.getEntitiesForPhysicalGroup(d, group):
                types, _, nodes = model.mesh.getElements(d, entity)
                for kind, conn in zip(types, nodes, strict=True):
                    if kind != simplex:
                        raise RuntimeError(
                            f"group '{name}' has gmsh elements of type {kind}; particles are "
                            "seeded from linear triangles/tetrahedra only"
                        )
                    blocks.append(index[conn.astype(np.int64)].reshape(-1, dim + 1))
            if blocks:
                out[name] = (xyz, np.concatenate(blocks))
        polyline = None
        if curve is not None:
            tag = next(
                t for d, t in model.getPhysicalGroups(1) if model.getPhysicalName(d, t) == curve
            )
            xyz_c = model.mesh.getNodesForPhysicalGroup(1, tag)[1].reshape(-1, 3)[:, :2]
            polyline = xyz_c[np.argsort(xyz_c[:, 0], kind="stable")]
            if np.any(np.diff(polyline[:, 0]) <= 0):
                raise RuntimeError(f"curve group '{curve}' is not a graph y(x) (x repeats)")
    if not out:
        raise RuntimeError(f"'{file.name}' has no meshed {dim}D physical group")
    return out, polyline


def geostatic(p: Particles, gravity: np.ndarray, nu: float, *, width: float) -> None:
    """Give the particles the at-rest stress of their own weight (in place).

    The vertical stress of a particle is the weight of the particles above it in its
    column per unit column area, σ_v = −Σ_above m_q |g| / w^(dim−1) (its own weight counts
    half), and the horizontal ones are K₀ σ_v with K₀ = ν / (1 − ν) (in 2D also the
    out-of-plane σ_zz of plane strain). Columns are bins of width ``width`` across the
    vertical axis, which is the last one and must carry all of gravity; heights within
    :data:`COLUMN_TOL` × ``width`` are one layer.

    Args:
        p: the particles, 2D or 3D.
        gravity: body force per mass, shape=(dim,), pointing along −(last axis).
        nu: Poisson's ratio.
        width: column width (the grid cell size).
    """
    dim = p.dim
    g = np.asarray(gravity, dtype=float)
    if dim < 2 or np.any(g[:-1] != 0) or not g[-1] < 0:
        raise ValueError("geostatic stress needs 2D/3D particles and gravity along -(last axis)")
    cols = np.floor(p.x[:, :-1] / width + COLUMN_TOL).astype(np.int64)
    _, column = np.unique(cols, axis=0, return_inverse=True)
    height = p.x[:, -1]
    order = np.lexsort((-height, column.ravel()))  # by column, top first
    col, y = column.ravel()[order], height[order]
    weight = p.mass[order] * -g[-1] / width ** (dim - 1)
    # particles at one height in a column form a layer: each sees the layers above it
    # plus half its own layer
    # (y falls within a column: a new layer where it falls by more than the tolerance)
    layer = np.r_[0, np.cumsum((np.diff(col) != 0) | (np.diff(y) < -COLUMN_TOL * width))]
    layer_weight = np.bincount(layer, weights=weight)
    first = np.r_[True, np.diff(col) != 0][np.r_[0, np.flatnonzero(np.diff(layer)) + 1]]
    above = np.cumsum(layer_weight) - layer_weight
    above -= np.maximum.accumulate(np.where(first, above, 0.0))  # restart per column
    sigma_v = np.empty(p.n)
    sigma_v[order] = -(above + 0.5 * layer_weight)[layer]
    k0 = nu / (1.0 - nu)
    p.stress[:] = 0.0
    for a in range(dim - 1):
        p.stress[:, a, a] = k0 * sigma_v
    p.stress[:, -1, -1] = sigma_v
    if dim == 2:
        p.stress_zz[:] = k0 * sigma_v
