"""The node pairs of a split 3D joint: its P2 facets, paired face to face (numpy + DOLFINx).

The 3D counterpart of the facet search in :mod:`geofrac.fem.joints`. A joint is a surface
group of triangles cut when meshed (:func:`geofrac.meshing.split.split_model`), so each of
its facets has one tetrahedron, and each facet of the + face lies on a facet of the − face.
The + side is where the joint normal n points, n oriented by the rule of
:func:`geofrac.dfn3d.network.canonical_normals` (n_z > 0, else n_y > 0, else n_x > 0).

Lumping: the P2 triangle's Newton-Cotes rule, exact for quadratics, puts the weight A/3 on
each edge's middle node and none on the vertices (the integral of a P2 vertex function over
the triangle is zero). It is the edge-midpoint quadrature rule, so the springs at the
middle nodes integrate the joint's traction exactly where the jump is quadratic, as
Simpson's weights do on a 2D joint's P2 edge: a uniform stress gives a uniform jump with
the springs' force the facets' share of it. The vertices get no spring (their jump follows
the elastic solids), so only middle nodes are paired.
"""

from __future__ import annotations

import dolfinx_solver  # noqa: F401  (orders MPI before the DOLFINx bindings)

import dolfinx
import numpy as np

from geofrac.errors import RunError
from geofrac.meshing.distribute import TaggedMesh

__all__ = ["ROW", "face_facets_3d", "facet_faces_3d", "facet_pairs_3d", "tangent_frames"]

#: Columns of a facet row: 3 middle nodes (global), side ±1, their x, y, z (9), n (3),
#: area, mean edge length, the facet's vertices' x, y, z (9).
ROW = 27
#: |n_z| (then |n_y|) below which a unit normal counts as horizontal for the sign rule.
HORIZONTAL = 1e-9


def _orient(normal: np.ndarray) -> np.ndarray:
    """The unit normal with n_z > 0, else n_y > 0, else n_x > 0, shape=(3,)."""
    if normal[2] < -HORIZONTAL or (
        abs(normal[2]) <= HORIZONTAL
        and (normal[1] < -HORIZONTAL or (abs(normal[1]) <= HORIZONTAL and normal[0] < 0))
    ):
        return -normal
    return normal


def face_facets_3d(
    V: dolfinx.fem.FunctionSpace, tagged: TaggedMesh, group: str, *, key: str
) -> np.ndarray:
    """This rank's owned facets of the surface ``group`` with one cell, as rows.

    A facet with two cells stayed whole in the split (its three vertices on the joint's
    edge: no jump there) and is left out; in a group that was not split it is an error.

    Returns:
        rows of :data:`ROW` columns (middle nodes, side, their coordinates, n, area, mean
        edge length, the vertices' coordinates), shape=(m, 27).

    Raises:
        RunError: the group is not a surface group, is not split, or the space is not P2.
    """
    mesh = V.mesh
    tdim = mesh.topology.dim
    dim, facets = tagged.entities(group)
    if dim != tdim - 1:
        raise RunError(f"{key}: the group '{group}' is not a surface group")
    layout = V.dofmap.dof_layout
    per_entity = [len(layout.entity_dofs(d, 0)) for d in range(3)]
    if per_entity != [1, 1, 0]:
        raise RunError(f"{key}: 3D joints need the P2 element (a node per vertex and per edge)")
    facets = tagged.owned(dim, facets)
    mesh.topology.create_connectivity(dim, tdim)
    mesh.topology.create_connectivity(tdim, 1)
    mesh.topology.create_connectivity(dim, 1)
    f2c = mesh.topology.connectivity(dim, tdim)
    c2e = mesh.topology.connectivity(tdim, 1)
    f2e = mesh.topology.connectivity(dim, 1)
    coords = V.tabulate_dof_coordinates()
    imap = V.dofmap.index_map
    geom = mesh.geometry
    vertices = dolfinx.mesh.entities_to_geometry(mesh, dim, np.asarray(facets, dtype=np.int32))
    rows = []
    for f, facet_nodes in zip(facets, vertices, strict=True):
        cells = f2c.links(f)
        if len(cells) != 1:
            if group in tagged.split:
                continue
            raise RunError(
                f"{key}: the joint '{group}' is not split (a facet with {len(cells)} cells); "
                "a [plasticity.joints.NAME] surface group is cut along when meshed"
            )
        cell = cells[0]
        cell_edges = c2e.links(cell)
        dofs = V.dofmap.cell_dofs(cell)
        middle = [
            int(dofs[layout.entity_dofs(1, int(np.flatnonzero(cell_edges == e)[0]))[0]])
            for e in f2e.links(f)
        ]
        xyz = coords[middle]
        corners = geom.x[geom.dofmaps[0][cell]]
        vertex = geom.x[facet_nodes]
        normal = np.cross(vertex[1] - vertex[0], vertex[2] - vertex[0])
        area = 0.5 * float(np.linalg.norm(normal))
        normal = _orient(normal / (2.0 * area))
        edge = np.mean([np.linalg.norm(vertex[i] - vertex[j]) for i, j in ((0, 1), (1, 2), (2, 0))])
        side = 1.0 if np.dot(corners.mean(axis=0) - xyz.mean(axis=0), normal) > 0 else -1.0
        glob = imap.local_to_global(np.asarray(middle, dtype=np.int32))
        rows.append([*glob, side, *xyz.ravel(), *normal, area, edge, *vertex.ravel()])
    return np.asarray(rows, dtype=float).reshape(-1, ROW)


def _matched(rows: np.ndarray, key: str) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The + facets, the − facet at the same place for each, and which middle node of it.

    Returns:
        up (k, 27), down (k, 27) in the order of ``up``, and per + middle node the index
        (0-2) of the − middle node at the same place, shape=(k, 3).

    Raises:
        RunError: a facet or a node without a partner on the other side.
    """
    from scipy.spatial import cKDTree

    up, down = rows[rows[:, 3] > 0], rows[rows[:, 3] < 0]
    tol = 1e-6 * float(rows[:, 17].min()) if len(rows) else 0.0
    match = np.full(len(up), -1)
    if len(up) and len(down):
        c_up = up[:, 4:13].reshape(-1, 3, 3).mean(axis=1)
        c_down = down[:, 4:13].reshape(-1, 3, 3).mean(axis=1)
        dist, near = cKDTree(c_down).query(c_up)
        match = np.where(dist <= tol, near, -1)
    if len(up) == 0 or len(up) != len(down) or np.any(match < 0):
        raise RunError(
            f"{key}: the joint's faces have {len(up)} and {len(down)} facets, "
            f"{int(np.count_nonzero(match < 0))} with no facet at the same place on the other "
            "side; a joint must be split (meshed alike on both faces)"
        )
    if len(np.unique(match)) != len(up):
        raise RunError(f"{key}: two facets of one face lie on each other")
    down = down[match]
    x_up = up[:, 4:13].reshape(-1, 3, 3)
    x_down = down[:, 4:13].reshape(-1, 3, 3)
    gap = np.linalg.norm(x_up[:, :, None, :] - x_down[:, None, :, :], axis=3)  # (k, 3, 3)
    which = np.argmin(gap, axis=2)
    if np.any(np.take_along_axis(gap, which[:, :, None], axis=2) > tol):
        raise RunError(f"{key}: a facet's nodes have no partner on the other face")
    return up, down, which


def facet_pairs_3d(rows: np.ndarray, key: str) -> np.ndarray:
    """Each + facet with the − facet at the same place; their middle-node pairs.

    Args:
        rows: the facets of :func:`face_facets_3d` of all ranks, shape=(k, 27).
        key: the scene key named in errors.

    Returns:
        (plus node, minus node, x, y, z, weight A/3, n_x, n_y, n_z, mean edge length) per
        facet middle node, shape=(p, 10); a node pair appears once per facet it is in.
        Pairs of a node with itself (an edge on the joint's edge, not split) are dropped.

    Raises:
        RunError: a facet without a facet on the other side at the same place.
    """
    up, down, which = _matched(rows, key)
    k = len(up)
    out = np.zeros((3 * k, 10))
    area = 0.5 * (up[:, 16] + down[:, 16])
    edge = 0.5 * (up[:, 17] + down[:, 17])
    for m in range(3):
        part = out[m::3]
        part[:, 0], part[:, 1] = up[:, m], down[np.arange(k), which[:, m]]
        part[:, 2:5] = up[:, 4 + 3 * m : 7 + 3 * m]
        part[:, 5] = area / 3.0
        part[:, 6:9] = up[:, 13:16]
        part[:, 9] = edge
    return out[out[:, 0] != out[:, 1]]


def facet_faces_3d(rows: np.ndarray, key: str) -> tuple[np.ndarray, np.ndarray]:
    """The joint's faces (the + facets) and the node pairs of their middle nodes.

    Args:
        rows: the facets of :func:`face_facets_3d` of all ranks, shape=(k, 27).
        key: the scene key named in errors.

    Returns:
        the faces' vertices, shape=(k, 3, 3), and the (plus, minus) global nodes of their
        three middle nodes, shape=(k, 3, 2) (plus == minus where the edge was not split).
    """
    up, down, which = _matched(rows, key)
    k = len(up)
    pairs = np.stack([up[:, :3], np.take_along_axis(down[:, :3], which, axis=1)], axis=2)
    return up[:, 18:27].reshape(k, 3, 3), pairs.astype(np.int64).reshape(k, 3, 2)


def tangent_frames(normal: np.ndarray) -> np.ndarray:
    """Orthonormal frames [n t₁ t₂] per pair, t₁ along the strike where there is one.

    t₁ = e_z × n normalised (horizontal: the strike) where |n_z| < 0.9, else the
    projection of e_x on the plane; t₂ = n × t₁ (the dip direction, up or down). The
    joint law is isotropic in its plane, so the choice changes no traction, only the
    components written out.

    Args:
        normal: unit normals, shape=(m, 3).

    Returns:
        frames with the columns n, t₁, t₂, shape=(m, 3, 3).
    """
    n = np.asarray(normal, dtype=float).reshape(-1, 3)
    steep = np.abs(n[:, 2]) < 0.9
    t1 = np.where(
        steep[:, None],
        np.cross(np.array([0.0, 0.0, 1.0]), n),
        np.array([1.0, 0.0, 0.0]) - n[:, :1] * n,
    )
    t1 /= np.linalg.norm(t1, axis=1)[:, None]
    t2 = np.cross(n, t1)
    return np.stack([n, t1, t2], axis=2)
