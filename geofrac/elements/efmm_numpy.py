"""Enriched Free Mesh Method (Edo (2016), §3.2, eqs. 3.1-3.7): pure-numpy reference, 2D.

Each node i has a patch (the triangles around it) with a CST displacement per triangle
and one complete linear stress field per patch, σ = P(x) e (eq. 3.2b), P = I₃ ⊗ [1, x, y]
in coordinates centred on the node and scaled by the patch size. The Hellinger-Reissner
functional (3.1) over the node's integration domain Ω_i gives (3.3)-(3.4)

    A_i = ∫_Ω_i Pᵀ D⁻¹ P dΩ,   C_i = ∫_Ω_i Pᵀ B dΩ,

and condensing e, the node stiffness K_i = C_iᵀ A_i⁻¹ C_i (3.6), assembled over nodes.

Integration domains (§3.2.2, Fig. 3.3). In every triangle T a point p_T is taken
inside the incircle: the incentre for q_rand = 0, else a seeded random point of the
disc of radius q_rand x r around it (the 2D blocks' points,
:func:`geofrac.geometry.triangles.inner_points`). Neighbouring triangles' points are joined
directly; the segment p_T p_T' crosses their shared edge ij at X_ij. Node i's domain
inside T = (i, j, k) is the quadrilateral (i, X_ij, p_T, X_ik), integrated with Gauss
rules on its two triangles (i, X_ij, p_T) and (i, p_T, X_ik) (the thesis's triangles of
the centre node, an incircle point and an edge crossing). On a boundary edge, which has
one triangle, X_ij is the edge midpoint (our choice: the thesis does not say). The three
quadrilaterals of a triangle tile it, so the domains tile the mesh exactly.

When two triangles form a non-convex quadrilateral the segment p_T p_T' can miss their
shared edge; X_ij is then clamped onto the edge (``clamped`` counts such edges), which
keeps the tiling exact.

This module is the reference the compiled kernel is tested against; it builds a dense
global matrix and is meant for small meshes.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from geofrac.geometry.triangles import inner_points
from geofrac.meshing.distorted import signed_areas

__all__ = [
    "GAUSS_3",
    "Domains",
    "NodeOperator",
    "cell_subtriangles",
    "edge_crossings",
    "integration_domains",
    "node_operator",
    "node_stiffness",
    "stiffness",
    "stress_error",
    "triangle_areas",
]

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
        triangles: the node indices of each triangle, counter-clockwise,
            shape=(num_cells, 3).
        crossings: the point X on the edge from corner c to c + 1 of ``triangles`` (the
            crossing, or the midpoint of a boundary edge), shape=(num_cells, 3, 2).
    """

    node: np.ndarray
    cell: np.ndarray
    corners: np.ndarray
    inner: np.ndarray
    clamped: int
    triangles: np.ndarray
    crossings: np.ndarray


def edge_crossings(
    xa: np.ndarray, xb: np.ndarray, *, left: np.ndarray, right: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Where the segment between two triangles' inner points crosses their shared edge.

    The edge runs from ``xa`` to ``xb`` (its vertex with the smaller global id first) and
    ``left``/``right`` are the inner points of the triangles on its left and right, so
    every rank computes the same bits for the same edge. When the segment misses the
    edge (a non-convex pair of triangles) the point is clamped onto the edge, 1e-3 of its
    length away from the vertices.

    Args:
        xa: edge start, shape=(num_edges, 2).
        xb: edge end, shape=(num_edges, 2).
        left: inner point of the triangle on the left, shape=(num_edges, 2).
        right: inner point of the triangle on the right, shape=(num_edges, 2).

    Returns:
        the crossings, shape=(num_edges, 2), and which were clamped, shape=(num_edges,).
    """
    e, d = xb - xa, right - left
    denom = d[:, 0] * e[:, 1] - d[:, 1] * e[:, 0]
    w = xa - left
    t = (w[:, 0] * d[:, 1] - w[:, 1] * d[:, 0]) / denom  # along the edge, a -> b
    clamped = ~((t > 0) & (t < 1))
    t = np.clip(np.nan_to_num(t, nan=0.5), 1e-3, 1 - 1e-3)
    return xa + t[:, None] * e, clamped


def integration_domains(
    points: np.ndarray,
    triangles: np.ndarray,
    q_rand: float = 0.0,
    *,
    seed: int = 0,
    keys: np.ndarray | None = None,
    ids: np.ndarray | None = None,
) -> Domains:
    """Each node's integration domain as sub-triangles (Fig. 3.3).

    Args:
        points: node coordinates, shape=(num_nodes, 2).
        triangles: node indices, shape=(num_cells, 3).
        q_rand: randomness of the inner points in [0, 1] (Fig. 3.13).
        seed: seed of the random points.
        keys: a global key per triangle that seeds its random point, shape=(num_cells,)
            (default: :func:`~geofrac.geometry.triangles.coordinate_keys`, made of its
            corners' coordinates, as the EFMM element does).
        ids: a global id per node, shape=(num_nodes,) (default: the node's index); the
            inner point sees a triangle's corners in increasing id order and an edge runs
            from its smaller id, so results do not depend on local numbering.
    """
    points = np.asarray(points, dtype=float)[:, :2]
    tri = np.asarray(triangles, dtype=np.int64).copy()
    ids = np.arange(len(points)) if ids is None else np.asarray(ids, dtype=np.int64)
    keys = None if keys is None else np.asarray(keys, dtype=np.int64)
    flip = signed_areas(points, tri) < 0
    tri[flip] = tri[flip][:, [0, 2, 1]]  # counter-clockwise
    by_id = np.take_along_axis(tri, np.argsort(ids[tri], axis=1), axis=1)
    inner = inner_points(
        points[by_id],
        keys,
        "random" if q_rand > 0 else "incentre",
        radius=q_rand,
        convex=False,
        seed=seed,
    )
    # edges: (cell, local edge c from corner c to c + 1); a CCW triangle lies on the left
    a, b = tri.ravel(), np.roll(tri, -1, axis=1).ravel()
    lo = np.where(ids[a] < ids[b], a, b)
    hi = np.where(ids[a] < ids[b], b, a)
    on_left = lo == a
    n = len(points)
    order = np.argsort(lo * n + hi, kind="stable")
    key = (lo * n + hi)[order]
    pair = np.flatnonzero(key[1:] == key[:-1])
    first, second = order[pair], order[pair + 1]
    cell_of = np.repeat(np.arange(len(tri)), 3)
    cross = 0.5 * (points[lo] + points[hi])  # boundary edges: the midpoint
    left = np.where(on_left[first], first, second)
    right = np.where(on_left[first], second, first)
    x, was_clamped = edge_crossings(
        points[lo[first]], points[hi[first]], left=inner[cell_of[left]], right=inner[cell_of[right]]
    )
    cross[first] = x
    cross[second] = x  # the same point, bit for bit, on both sides
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
        clamped=int(np.count_nonzero(was_clamped)),
        triangles=tri,
        crossings=cross,
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


@dataclass(frozen=True)
class NodeOperator:
    """One node's condensed EFMM operators (eqs. 3.4-3.6).

    Attributes:
        patch: the nodes of its patch, sorted, shape=(m,).
        K: node stiffness C_iᵀ A_i⁻¹ C_i on the patch's (u, v) pairs, shape=(2m, 2m).
        stress: A_i⁻¹ C_i, the stress coefficients e_i from the patch displacements,
            shape=(9, 2m), ordered (σx, σy, τxy) x (1, ξ, η) with
            (ξ, η) = (x - x_i) / scale.
        origin: x_i, shape=(2,).
        scale: the patch size used to scale the monomials.
    """

    patch: np.ndarray
    K: np.ndarray
    stress: np.ndarray
    origin: np.ndarray
    scale: float

    def stress_at(self, points: np.ndarray) -> np.ndarray:
        """The node's stress field's operator at points, shape=(k, 3, 2m) for (k, 2)."""
        xi = (np.atleast_2d(points) - self.origin) / self.scale
        mono = np.column_stack([np.ones(len(xi)), xi])  # shape=(k, 3)
        return np.einsum("km,smd->ksd", mono, self.stress.reshape(3, 3, -1))


def node_operator(
    points: np.ndarray,
    triangles: np.ndarray,
    D: np.ndarray,
    *,
    domains: Domains,
    node: int,
    mine: np.ndarray | None = None,
) -> NodeOperator:
    """The condensed operators of one node (eqs. 3.4, 3.6); see :class:`NodeOperator`.

    Args:
        points: node coordinates, shape=(num_nodes, 2).
        triangles: node indices, shape=(num_cells, 3).
        D: elasticity matrix, shape=(3, 3).
        domains: the integration domains.
        node: the node.
        mine: the node's sub-triangles (indices into ``domains``), shape=(s,); found
            by a search when absent.
    """
    points = np.asarray(points, dtype=float)[:, :2]
    tri = np.asarray(triangles, dtype=np.int64)
    if mine is None:
        mine = np.flatnonzero(domains.node == node)
    cells = domains.cell[mine]
    patch = np.unique(tri[cells])
    B = _b_matrices(points, tri[cells])  # shape=(s, 3, 6)
    Dinv = np.linalg.inv(D)
    origin = points[node]
    scale = max(float(np.abs(points[patch] - origin).max()), 1e-300)
    bary, weights = GAUSS_3
    subs = domains.corners[mine]  # shape=(s, 3, 2)
    wa = triangle_areas(subs)[:, None] * weights  # shape=(s, 3): Gauss weight x area
    xi = (np.einsum("gk,skd->sgd", bary, subs) - origin) / scale
    mono = np.concatenate([np.ones((*xi.shape[:2], 1)), xi], axis=2)  # shape=(s, 3, 3)
    # P = I3 (x) [1, xi, eta]: e index 3 a + m for stress component a and monomial m
    A = np.kron(Dinv, np.einsum("sg,sgm,sgn->mn", wa, mono, mono))
    Cs = np.einsum("sg,sgm,sak->samk", wa, mono, B).reshape(len(subs), 9, 6)
    cols = 2 * np.searchsorted(patch, tri[cells])[:, :, None] + np.arange(2)  # (s, 3, 2)
    Ct = np.zeros((2 * len(patch), 9))
    np.add.at(Ct, cols.reshape(-1), Cs.transpose(0, 2, 1).reshape(-1, 9))
    C = Ct.T
    S = np.linalg.solve(A, C)
    return NodeOperator(patch, C.T @ S, S, origin, scale)


def node_stiffness(
    points: np.ndarray, triangles: np.ndarray, D: np.ndarray, *, domains: Domains, node: int
) -> tuple[np.ndarray, np.ndarray]:
    """K_i = C_iᵀ A_i⁻¹ C_i of one node (eqs. 3.4, 3.6) and the global DOFs it acts on.

    Returns:
        ``K`` shape=(2m, 2m) and ``dofs`` shape=(2m,), m the nodes of the node's patch.
    """
    op = node_operator(points, triangles, D, domains=domains, node=node)
    patch = op.patch
    return op.K, np.stack([2 * patch, 2 * patch + 1], axis=1).ravel()


def stiffness(
    points: np.ndarray, triangles: np.ndarray, D: np.ndarray, *, q_rand: float = 0.0, seed: int = 0
) -> np.ndarray:
    """The global EFMM stiffness, dense, shape=(2 num_nodes, 2 num_nodes) (small meshes)."""
    domains = integration_domains(points, triangles, q_rand, seed=seed)
    n = len(points)
    K = np.zeros((2 * n, 2 * n))
    for i in np.unique(domains.node):
        Ki, dofs = node_stiffness(points, triangles, D, domains=domains, node=int(i))
        K[np.ix_(dofs, dofs)] += Ki
    return K


def triangle_areas(corners: np.ndarray) -> np.ndarray:
    """Unsigned areas of triangles, corners shape=(..., 3, 2); returns shape=(...)."""
    a, b, c = corners[..., 0, :], corners[..., 1, :], corners[..., 2, :]
    return 0.5 * np.abs((b[..., 0] - a[..., 0]) * (c[..., 1] - a[..., 1])
                        - (c[..., 0] - a[..., 0]) * (b[..., 1] - a[..., 1]))  # fmt: skip


def cell_subtriangles(x: np.ndarray, domain: np.ndarray) -> np.ndarray:
    """The sub-triangles of each cell's three node parts, as the C kernel integrates them.

    Args:
        x: cell vertices, shape=(num_cells, 3, 2).
        domain: per cell the inner point p and the crossings X_k on the edge opposite
            vertex k, shape=(num_cells, 8) (:func:`geofrac.elements.efmm.domain_data`).

    Returns:
        corners, shape=(num_cells, 3, 2, 3, 2): for vertex j the triangles
        (x_j, X_(j+2)%3, p) and (x_j, p, X_(j+1)%3) (the parts on edges (j, j+1) and
        (j-1, j)).
    """
    p = domain[:, 0:2]
    X = domain[:, 2:8].reshape(-1, 3, 2)
    out = np.empty((len(x), 3, 2, 3, 2))
    for j in range(3):
        out[:, j, 0] = np.stack([x[:, j], X[:, (j + 2) % 3], p], axis=1)
        out[:, j, 1] = np.stack([x[:, j], p, X[:, (j + 1) % 3]], axis=1)
    return out


def stress_error(
    x: np.ndarray,
    domain: np.ndarray,
    e: np.ndarray,
    *,
    Dinv: np.ndarray,
    length: float,
    exact_stress: Callable[[np.ndarray, np.ndarray], np.ndarray],
    rule: tuple[np.ndarray, np.ndarray],
) -> tuple[float, float]:
    """∫ ½ (σ_h - σ)ᵀ D⁻¹ (σ_h - σ) and ∫ ½ σᵀ D⁻¹ σ over the cells' node parts.

    σ_h is each node's own stress field P_i e_i (eq. 3.2b) on its integration domain:
    the stress of the energy error norm of Edo (2016) (eq. 3.30b with ε = D⁻¹ σ, eq. 3.32).

    Args:
        x: cell vertices, shape=(num_cells, 3, 2).
        domain: see :func:`cell_subtriangles`, shape=(num_cells, 8).
        e: stress coefficients of the cells' vertices, shape=(num_cells, 3, 9) ordered
            (σx, σy, τxy) x (1, (x - x_i)/h, (y - y_i)/h).
        Dinv: compliance, shape=(3, 3).
        length: h.
        exact_stress: (x, y) -> (σx, σy, τxy), arrays shape=(n,) in, shape=(n, 3) out.
        rule: reference-triangle points, shape=(nq, 2), and weights, shape=(nq,),
            summing to 1/2.

    Returns:
        (error energy, exact energy), both sums over the given cells.
    """
    subs = cell_subtriangles(x, domain)  # shape=(nc, 3, 2, 3, 2)
    a, b, c = subs[..., 0, :], subs[..., 1, :], subs[..., 2, :]
    det = 2.0 * triangle_areas(subs)
    pts, wts = rule
    q = (
        a[..., None, :]
        + pts[:, 0, None] * (b - a)[..., None, :]
        + pts[:, 1, None] * (c - a)[..., None, :]
    )  # shape=(nc, 3, 2, nq, 2)
    rel = (q - x[:, :, None, None, :]) / length
    mono = np.concatenate([np.ones((*rel.shape[:-1], 1)), rel], axis=-1)  # (..., 3)
    coef = e.reshape(len(e), 3, 3, 3)  # (cell, node, component, monomial)
    sigma_h = np.einsum("cjsqm,cjkm->cjsqk", mono, coef)
    sigma = exact_stress(q[..., 0].ravel(), q[..., 1].ravel()).reshape(sigma_h.shape)
    weight = det[..., None] * wts  # shape=(nc, 3, 2, nq)
    err = sigma_h - sigma
    e_err = 0.5 * float((np.einsum("...k,kl,...l->...", err, Dinv, err) * weight).sum())
    e_ex = 0.5 * float((np.einsum("...k,kl,...l->...", sigma, Dinv, sigma) * weight).sum())
    return e_err, e_ex
