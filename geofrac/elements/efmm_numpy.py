"""Enriched Free Mesh Method (seed 3.2, eqs. 3.1-3.7): pure-numpy reference, 2D.

Each node i has a patch (the triangles around it) with a CST displacement per triangle
and one complete linear stress field per patch, σ = P(x) e (eq. 3.2b), P = I₃ ⊗ [1, x, y]
in coordinates centred on the node and scaled by the patch size. The Hellinger-Reissner
functional (3.1) over the node's integration domain Ω_i gives (3.3)-(3.4)

    A_i = ∫_Ω_i Pᵀ D⁻¹ P dΩ,   C_i = ∫_Ω_i Pᵀ B dΩ,

and condensing e, the node stiffness K_i = C_iᵀ A_i⁻¹ C_i (3.6), assembled over nodes.

Integration domains (seed 3.2.2, Fig. 3.3). In every triangle T a point p_T is taken
inside the incircle: the incentre for q_rand = 0, else a seeded random point of the
disc of radius q_rand x r around it (the 2D blocks' points,
:func:`geofrac.blocks.dual2d.inner_points`). Neighbouring triangles' points are joined
directly; the segment p_T p_T' crosses their shared edge ij at X_ij. Node i's domain
inside T = (i, j, k) is the quadrilateral (i, X_ij, p_T, X_ik), integrated with Gauss
rules on its two triangles (i, X_ij, p_T) and (i, p_T, X_ik) (the seed's triangles of
the centre node, an incircle point and an edge crossing). On a boundary edge, which has
one triangle, X_ij is the edge midpoint (our choice: the seed does not say). The three
quadrilaterals of a triangle tile it, so the domains tile the mesh exactly.

When two triangles form a non-convex quadrilateral the segment p_T p_T' can miss their
shared edge; X_ij is then clamped onto the edge (``clamped`` counts such edges), which
keeps the tiling exact.

This module is the reference the compiled kernel is tested against; it builds a dense
global matrix and is meant for small meshes.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from geofrac.blocks.dual2d import inner_points
from geofrac.meshing.distorted import signed_areas

__all__ = ["GAUSS_3", "Domains", "integration_domains", "node_stiffness", "stiffness"]

#: Three-point Gauss rule on a triangle, degree 2: barycentric points and weights
#: (weights sum to 1; multiply by the area).
GAUSS_3 = (
    np.array([[2 / 3, 1 / 6, 1 / 6], [1 / 6, 2 / 3, 1 / 6], [1 / 6, 1 / 6, 2 / 3]]),
    np.array([1 / 3, 1 / 3, 1 / 3]),
)


@dataclass
class Domains:
    """The integration domains' sub-triangles.

    Attributes:
        node: the node each sub-triangle belongs to, shape=(num_sub,).
        cell: the mesh triangle it lies in, shape=(num_sub,).
        corners: its corners (the node, an edge crossing or midpoint, the inner point),
            shape=(num_sub, 3, 2).
        inner: the inner point of each mesh triangle, shape=(num_cells, 2).
        clamped: edges whose crossing had to be clamped onto the edge.
    """

    node: np.ndarray
    cell: np.ndarray
    corners: np.ndarray
    inner: np.ndarray
    clamped: int


def integration_domains(
    points: np.ndarray, triangles: np.ndarray, q_rand: float = 0.0, seed: int = 0
) -> Domains:
    """Each node's integration domain as sub-triangles (Fig. 3.3).

    Args:
        points: node coordinates, shape=(num_nodes, 2).
        triangles: node indices, shape=(num_cells, 3).
        q_rand: randomness of the inner points in [0, 1] (Fig. 3.13).
        seed: seed of the random points.
    """
    points = np.asarray(points, dtype=float)[:, :2]
    tri = np.asarray(triangles, dtype=np.int64).copy()
    flip = signed_areas(points, tri) < 0
    tri[flip] = tri[flip][:, [0, 2, 1]]  # counter-clockwise
    n = len(points)
    ordered = np.sort(tri, axis=1)
    keys = (ordered[:, 0] * n + ordered[:, 1]) * n + ordered[:, 2]
    inner = inner_points(
        points[ordered], keys, "random" if q_rand > 0 else "incentre", q_rand, False, seed
    )
    # edges: (cell, local edge c from corner c to c + 1) keyed by their sorted nodes
    a, b = tri, np.roll(tri, -1, axis=1)
    edge_key = np.minimum(a, b) * n + np.maximum(a, b)
    flat = edge_key.ravel()
    order = np.argsort(flat, kind="stable")
    sorted_keys = flat[order]
    twin = np.full(len(flat), -1)
    same = sorted_keys[1:] == sorted_keys[:-1]
    twin[order[1:][same]] = order[:-1][same]
    twin[order[:-1][same]] = order[1:][same]
    cell_of = np.repeat(np.arange(len(tri)), 3)
    pa, pb = points[a.ravel()], points[b.ravel()]
    cross = 0.5 * (pa + pb)  # boundary edges: the midpoint
    clamped = 0
    first = np.flatnonzero((twin >= 0) & (twin > np.arange(len(flat))))  # once per edge
    if len(first):
        p = inner[cell_of[first]]
        q = inner[cell_of[twin[first]]]
        ea, e = pa[first], pb[first] - pa[first]
        d = q - p
        denom = d[:, 0] * e[:, 1] - d[:, 1] * e[:, 0]
        w = ea - p
        t = (w[:, 0] * d[:, 1] - w[:, 1] * d[:, 0]) / denom  # along the edge, a -> b
        clamped = int(np.count_nonzero((t <= 0) | (t >= 1)))
        t = np.clip(t, 1e-3, 1 - 1e-3)
        cross[first] = ea + t[:, None] * e
        cross[twin[first]] = cross[first]  # the same point, bit for bit, on both sides
    cross = cross.reshape(-1, 3, 2)  # cross[t, c]: on the edge from corner c to c + 1
    nodes, cells, corners = [], [], []
    for c in range(3):
        i = tri[:, c]
        after, before = cross[:, c], cross[:, (c + 2) % 3]  # edges (c, c+1) and (c-1, c)
        corners += [
            np.stack([points[i], after, inner], axis=1),
            np.stack([points[i], inner, before], axis=1),
        ]
        nodes += [i, i]
        cells += [np.arange(len(tri))] * 2
    return Domains(
        node=np.concatenate(nodes),
        cell=np.concatenate(cells),
        corners=np.concatenate(corners),
        inner=inner,
        clamped=clamped,
    )


def _b_matrices(points: np.ndarray, tri: np.ndarray) -> np.ndarray:
    """CST strain-displacement matrices, shape=(num_cells, 3, 6), DOFs (u0, v0, u1, ...)."""
    x = points[tri]
    area2 = (x[:, 1, 0] - x[:, 0, 0]) * (x[:, 2, 1] - x[:, 0, 1]) - (x[:, 2, 0] - x[:, 0, 0]) * (
        x[:, 1, 1] - x[:, 0, 1]
    )
    b = np.stack([x[:, 1, 1] - x[:, 2, 1], x[:, 2, 1] - x[:, 0, 1], x[:, 0, 1] - x[:, 1, 1]], 1)
    c = np.stack([x[:, 2, 0] - x[:, 1, 0], x[:, 0, 0] - x[:, 2, 0], x[:, 1, 0] - x[:, 0, 0]], 1)
    B = np.zeros((len(tri), 3, 6))
    B[:, 0, 0::2] = b
    B[:, 1, 1::2] = c
    B[:, 2, 0::2] = c
    B[:, 2, 1::2] = b
    return B / area2[:, None, None]


def node_stiffness(
    points: np.ndarray, triangles: np.ndarray, D: np.ndarray, domains: Domains, node: int
) -> tuple[np.ndarray, np.ndarray]:
    """K_i = C_iᵀ A_i⁻¹ C_i of one node (eqs. 3.4, 3.6) and the global DOFs it acts on.

    Returns:
        ``K`` shape=(2m, 2m) and ``dofs`` shape=(2m,), m the nodes of the node's patch.
    """
    points = np.asarray(points, dtype=float)[:, :2]
    tri = np.asarray(triangles, dtype=np.int64)
    mine = np.flatnonzero(domains.node == node)
    cells = domains.cell[mine]
    patch = np.unique(tri[cells])
    local = {int(v): k for k, v in enumerate(patch)}
    B = _b_matrices(points, tri[cells])
    Dinv = np.linalg.inv(D)
    origin = points[node]
    scale = max(float(np.abs(points[patch] - origin).max()), 1e-300)
    A = np.zeros((9, 9))
    C = np.zeros((9, 2 * len(patch)))
    bary, weights = GAUSS_3
    subs = domains.corners[mine]
    areas = np.abs(signed_areas(subs.reshape(-1, 2), np.arange(3 * len(subs)).reshape(-1, 3)))
    for s, (sub, area) in enumerate(zip(subs, areas, strict=True)):
        gp = bary @ sub
        cols = np.array([[2 * local[int(v)], 2 * local[int(v)] + 1] for v in tri[cells[s]]]).ravel()
        for g in range(3):
            xi = (gp[g] - origin) / scale
            P = np.kron(np.eye(3), np.array([[1.0, xi[0], xi[1]]]))  # (3, 9)
            A += weights[g] * area * P.T @ Dinv @ P
            C[:, cols] += weights[g] * area * P.T @ B[s]
    K = C.T @ np.linalg.solve(A, C)
    dofs = np.stack([2 * patch, 2 * patch + 1], axis=1).ravel()
    return K, dofs


def stiffness(
    points: np.ndarray, triangles: np.ndarray, D: np.ndarray, q_rand: float = 0.0, seed: int = 0
) -> np.ndarray:
    """The global EFMM stiffness, dense, shape=(2 num_nodes, 2 num_nodes) (small meshes)."""
    domains = integration_domains(points, triangles, q_rand, seed)
    n = len(points)
    K = np.zeros((2 * n, 2 * n))
    for i in np.unique(domains.node):
        Ki, dofs = node_stiffness(points, triangles, D, domains, int(i))
        K[np.ix_(dofs, dofs)] += Ki
    return K
