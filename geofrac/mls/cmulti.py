"""C-MultiMLSM node field (Edo (2016), App. C, eqs. 3.12-3.28): numpy reference, C wrapper.

Node i at x_i with n satellite nodes j (0 < r_ij = |x_j - x_i| < h) carries the field

    u(x) = u_i + F(x - x_i) D                                        (3.12, C.6)

with the parameters D fitted by minimising (3.19, C.10)

    J = Σ_j W(r_ij, h) |u_i + F(x_j - x_i) D - u_j|²,

W the quartic spline (3.13) = (2.11). Hence A D = b with A = Σ_j W_j F_jᵀ F_j (3.21)
and b = Σ_j W_j F_jᵀ (u_j - u_i) = C u_nodes (3.22), u_nodes = (u_i, v_i, u_1, v_1, ...,
u_n, v_n) with the centre node first (3.22b), so D = A⁻¹ C u_nodes (3.23)-(3.24). App. C
defines the offsets x̃_ji = x_j - x_i from the node, independent of the evaluation point x,
so A and C are constant per node and the ∂A/∂x and ∂C/∂x terms of (3.25)-(3.26) vanish:
the strain is ε(x) = B(x) u_nodes with B from the derivatives of F only.

The order of F drops with the satellite count n (Edo (2016), §3.3.2(d)), for d = (dx, dy) = x - x_i:

- order 2 (n ≥ 10), 10 parameters D = (θ, εx, εy, γxy, εx,x, εx,y, εy,x, εy,y, γxy,x,
  γxy,y) (3.17b), F from (C.8) (3.17a has a sign/term typo in row v, column 7)::

      u: [-dy, dx, 0,  dy/2, dx²/2,  dx dy, -dy²/2, 0,     0,     dy²/2]
      v: [ dx, 0,  dy, dx/2, 0,     -dx²/2,  dx dy, dy²/2, dx²/2, 0    ]

  so that ∂u/∂x = εx + εx,x dx + εx,y dy, ∂v/∂y = εy + εy,x dx + εy,y dy and
  ∂u/∂y + ∂v/∂x = γ + γ,x dx + γ,y dy (γ the engineering shear strain);
- order 1 (4 ≤ n ≤ 9), D = (θ, εx, εy, γxy) (3.18a): u: [-dy, dx, 0, dy/2],
  v: [dx, 0, dy, dx/2];
- order 0 (1 ≤ n ≤ 3), rigid rotation only, D = (θ): u: [-dy], v: [dx];
- order -1 (n = 0), a fragment: no parameters, u(x) = u_i.

Numerics: the fit is done in the scaled offsets ξ = d/h, which leaves the fitted field
unchanged and keeps A of order one; the scaled parameters are h D for the first-order
ones (θ, εx, εy, γ) and h² D for the second-order ones, and ∂/∂x = (1/h) ∂/∂ξ.
``NodeFit.coefficients`` holds A⁻¹ C in the scaled parameters.

Robustness rule (ours; Edo (2016) only ties the order to the satellite count): the scaled
A (m × m) is Cholesky-factorised, A = L Lᵀ, and the order is accepted when the
factorisation succeeds and min(diag L)² / max(diag L)² ≥ ``MIN_PIVOT_RATIO``; otherwise
the next lower order is tried (2 → 1 → 0 → -1), e.g. for collinear satellites. Order -1
always succeeds. The numpy reference here and the C kernel ``geofrac/kernels/cmulti.c``
apply the same rule, so they pick the same branch.

The node stiffness is (3.27)-(3.28) K = t Σ_T ∫_T Bᵀ D_el B dΩ over the sub-triangles T
of the node's grain, integrated with the 3-point Gauss rule of degree 2, exact because
B is linear in x for order 2 (constant for order 1, zero for orders 0 and -1).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from geofrac.mls.shape import quartic_spline

if TYPE_CHECKING:
    from mpi4py import MPI

__all__ = [
    "MIN_PIVOT_RATIO",
    "ORDER_TERMS",
    "NodeFit",
    "basis",
    "basis_gradient",
    "compiled_node",
    "node_fit",
    "node_stiffness",
    "order_for",
]

#: An order is rejected when min(diag L)² / max(diag L)² of the Cholesky factor of the
#: scaled A is below this (or the factorisation fails).
MIN_PIVOT_RATIO = 1e-12

#: Number m of parameters of each order.
ORDER_TERMS: dict[int, int] = {2: 10, 1: 4, 0: 1, -1: 0}

#: Three-point Gauss rule of degree 2 on a triangle: barycentric points, weight 1/3 each.
_GAUSS = np.array([[2 / 3, 1 / 6, 1 / 6], [1 / 6, 2 / 3, 1 / 6], [1 / 6, 1 / 6, 2 / 3]])


def _power(order: int) -> np.ndarray:
    """The power of h in the scaled parameter: 1 (first order) or 2, shape=(m,)."""
    return np.array([1] * min(ORDER_TERMS[order], 4) + [2] * max(ORDER_TERMS[order] - 4, 0))


def _check_order(order: int) -> None:
    if order not in ORDER_TERMS:
        raise ValueError(f"order must be one of {sorted(ORDER_TERMS)}, got {order}")


def order_for(n: int) -> int:
    """Starting order for n satellites: 2 (n ≥ 10), 1 (4-9), 0 (1-3), -1 (0).

    Edo (2016), §3.3.2(d).

    Raises:
        ValueError: n < 0.
    """
    if n < 0:
        raise ValueError(f"the number of satellites must be >= 0, got {n}")
    if n >= 10:
        return 2
    if n >= 4:
        return 1
    if n >= 1:
        return 0
    return -1


def basis(d: np.ndarray, order: int) -> np.ndarray:
    """F of (C.6)/(C.8), (3.18a) or the rotation, at offsets d.

    Args:
        d: offsets from the node, shape=(k, 2).
        order: 2, 1, 0 or -1.

    Returns:
        F with rows u, v, shape=(k, 2, m), m = ``ORDER_TERMS[order]``.
    """
    _check_order(order)
    d = np.asarray(d, dtype=float).reshape(-1, 2)
    x, y = d[:, 0], d[:, 1]
    F = np.zeros((len(d), 2, ORDER_TERMS[order]))
    if order >= 0:
        F[:, 0, 0] = -y
        F[:, 1, 0] = x
    if order >= 1:
        F[:, 0, 1] = x
        F[:, 1, 2] = y
        F[:, 0, 3] = y / 2
        F[:, 1, 3] = x / 2
    if order >= 2:
        F[:, 0, 4] = x * x / 2
        F[:, 0, 5] = x * y
        F[:, 1, 5] = -x * x / 2
        F[:, 0, 6] = -y * y / 2
        F[:, 1, 6] = x * y
        F[:, 1, 7] = y * y / 2
        F[:, 1, 8] = x * x / 2
        F[:, 0, 9] = y * y / 2
    return F


def basis_gradient(d: np.ndarray, order: int) -> np.ndarray:
    """∂F/∂d of :func:`basis` at offsets d.

    Args:
        d: offsets from the node, shape=(k, 2).
        order: 2, 1, 0 or -1.

    Returns:
        [point, component u/v, derivative x/y, parameter], shape=(k, 2, 2, m).
    """
    _check_order(order)
    d = np.asarray(d, dtype=float).reshape(-1, 2)
    x, y = d[:, 0], d[:, 1]
    g = np.zeros((len(d), 2, 2, ORDER_TERMS[order]))
    if order >= 0:
        g[:, 0, 1, 0] = -1.0  # u = -y θ
        g[:, 1, 0, 0] = 1.0  # v = x θ
    if order >= 1:
        g[:, 0, 0, 1] = 1.0
        g[:, 1, 1, 2] = 1.0
        g[:, 0, 1, 3] = 0.5
        g[:, 1, 0, 3] = 0.5
    if order >= 2:
        g[:, 0, 0, 4] = x  # u: x²/2
        g[:, 0, 0, 5] = y  # u: x y
        g[:, 0, 1, 5] = x
        g[:, 1, 0, 5] = -x  # v: -x²/2
        g[:, 0, 1, 6] = -y  # u: -y²/2
        g[:, 1, 0, 6] = y  # v: x y
        g[:, 1, 1, 6] = x
        g[:, 1, 1, 7] = y  # v: y²/2
        g[:, 1, 0, 8] = x  # v: x²/2
        g[:, 0, 1, 9] = y  # u: y²/2
    return g


@dataclass(frozen=True)
class NodeFit:
    """The C-MultiMLSM field of one node: u(x) = u_i + F((x - x_i)/h) G u_nodes.

    Attributes:
        centre: the node position x_i, shape=(2,).
        h: influence radius.
        nodes: global node ids, the centre node first, shape=(n+1,), int64.
        order: accepted order, 2, 1, 0 or -1.
        coefficients: G = A⁻¹ C in the scaled parameters (3.23), the map from
            u_nodes = (u_i, v_i, u_1, v_1, ...) to h^p D, shape=(m, 2(n+1)).
    """

    centre: np.ndarray
    h: float
    nodes: np.ndarray
    order: int
    coefficients: np.ndarray

    def displacement_matrix(self, points: np.ndarray) -> np.ndarray:
        """N with u(x) = N(x) u_nodes, including the u_i term.

        Args:
            points: evaluation points, shape=(k, 2).

        Returns:
            N, shape=(k, 2, 2(n+1)).
        """
        xi = (np.asarray(points, dtype=float).reshape(-1, 2) - self.centre) / self.h
        N = basis(xi, self.order) @ self.coefficients
        N[:, 0, 0] += 1.0
        N[:, 1, 1] += 1.0
        return N

    def strain_matrix(self, points: np.ndarray) -> np.ndarray:
        """B with ε(x) = B(x) u_nodes, Voigt (εx, εy, γxy), engineering shear.

        Args:
            points: evaluation points, shape=(k, 2).

        Returns:
            B, shape=(k, 3, 2(n+1)); zero for orders 0 and -1.
        """
        xi = (np.asarray(points, dtype=float).reshape(-1, 2) - self.centre) / self.h
        return _strain_rows(basis_gradient(xi, self.order), self.h) @ self.coefficients

    def parameters(self, u_nodes: np.ndarray) -> np.ndarray:
        """The physical parameters D (θ, εx, ...; second-order ones per unit length).

        Args:
            u_nodes: (u_i, v_i, u_1, v_1, ...), shape=(2(n+1),).

        Returns:
            D, shape=(m,).
        """
        scaled = self.coefficients @ np.asarray(u_nodes, dtype=float)
        return scaled / self.h ** _power(self.order)


def _strain_rows(g: np.ndarray, h: float) -> np.ndarray:
    """Voigt strain rows of the scaled basis gradient g, shape=(k, 3, m)."""
    return np.stack([g[:, 0, 0], g[:, 1, 1], g[:, 0, 1] + g[:, 1, 0]], axis=1) / h


def _offsets(centre: np.ndarray, h: float, xy: np.ndarray) -> np.ndarray:
    """Satellite offsets x_j - x_i, shape=(n, 2), checking 0 < r < h."""
    if not h > 0.0:
        raise ValueError(f"h must be positive, got {h}")
    d = np.asarray(xy, dtype=float).reshape(-1, 2) - np.asarray(centre, dtype=float)
    r = np.hypot(d[:, 0], d[:, 1])
    if np.any(r <= 0.0) or np.any(r >= h):
        raise ValueError("every satellite must lie at a distance 0 < r < h from the node")
    return d


def _factor(A: np.ndarray) -> np.ndarray | None:
    """Cholesky factor of A when it passes the pivot rule, else None."""
    try:
        L = np.linalg.cholesky(A)
    except np.linalg.LinAlgError:
        return None
    diag = np.diag(L)
    if not np.all(np.isfinite(L)) or diag.min() ** 2 < MIN_PIVOT_RATIO * diag.max() ** 2:
        return None
    return L


def node_fit(
    centre: np.ndarray,
    h: float,
    centre_id: int,
    *,
    ids: np.ndarray,
    xy: np.ndarray,
    order: int | None = None,
) -> NodeFit:
    """Fit the node's field (3.19)-(3.24), dropping the order by the pivot rule.

    Args:
        centre: node position x_i, shape=(2,).
        h: influence radius.
        centre_id: global id of the node.
        ids: satellite ids (centre excluded), shape=(n,).
        xy: satellite positions, shape=(n, 2), each at 0 < |x_j - x_i| < h.
        order: starting order; None uses :func:`order_for` (n).

    Returns:
        the fit of the first accepted order.

    Raises:
        ValueError: a satellite outside 0 < r < h, h ≤ 0, or an unknown order.
    """
    centre = np.asarray(centre, dtype=float).reshape(2)
    d = _offsets(centre, h, xy)
    n = len(d)
    nodes = np.concatenate([[centre_id], np.asarray(ids).reshape(-1)]).astype(np.int64)
    if len(nodes) != n + 1:
        raise ValueError(f"{len(nodes) - 1} ids for {n} satellite positions")
    start = order_for(n) if order is None else order
    _check_order(start)
    w = quartic_spline(np.hypot(d[:, 0], d[:, 1]), h)
    xi = d / h
    for trial in range(start, -2, -1):
        m = ORDER_TERMS[trial]
        if m == 0:
            return NodeFit(centre, float(h), nodes, -1, np.zeros((0, 2 * (n + 1))))
        F = basis(xi, trial)  # shape=(n, 2, m)
        A = np.einsum("j,jam,jan->mn", w, F, F)  # eq. (3.21)
        L = _factor(A)
        if L is None:
            continue
        WF = w[:, None, None] * F  # shape=(n, 2, m)
        C = np.zeros((m, 2 * (n + 1)))  # eq. (3.22)
        C[:, 2:] = WF.transpose(2, 0, 1).reshape(m, 2 * n)
        C[:, :2] = -WF.sum(axis=0).T
        G = np.linalg.solve(L.T, np.linalg.solve(L, C))
        return NodeFit(centre, float(h), nodes, trial, G)
    raise AssertionError("unreachable: order -1 always succeeds")


def _gauss_points(triangles: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Points shape=(3 s, 2) and weights shape=(3 s,) of the degree-2 rule on the triangles."""
    tri = np.asarray(triangles, dtype=float).reshape(-1, 3, 2)
    e1, e2 = tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]
    area = 0.5 * np.abs(e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0])
    points = np.einsum("gk,skc->sgc", _GAUSS, tri).reshape(-1, 2)
    weights = np.repeat(area / 3.0, 3)
    return points, weights


def node_stiffness(
    fit: NodeFit, D: np.ndarray, thickness: float, *, triangles: np.ndarray
) -> np.ndarray:
    """Node stiffness (3.27)-(3.28): K = t Σ_T ∫_T Bᵀ D B dΩ over the grain's sub-triangles.

    Args:
        fit: the node's field.
        D: elasticity matrix (Voigt, engineering shear), shape=(3, 3).
        thickness: t.
        triangles: the grain's sub-triangles in absolute coordinates, shape=(s, 3, 2).

    Returns:
        K in the order of u_nodes, shape=(2(n+1), 2(n+1)).
    """
    points, weights = _gauss_points(triangles)
    B = fit.strain_matrix(points)  # shape=(3 s, 3, 2(n+1))
    D = np.asarray(D, dtype=float)
    return thickness * np.einsum("g,gai,ab,gbj->ij", weights, B, D, B)


def compiled_node(
    centre: np.ndarray,
    h: float,
    xy: np.ndarray,
    *,
    order: int | None,
    triangles: np.ndarray,
    D: np.ndarray,
    thickness: float,
    comm: MPI.Comm | None = None,
) -> tuple[int, np.ndarray, np.ndarray]:
    """Fit and node stiffness of one node with the C kernel ``cmulti``.

    Args:
        centre: node position x_i, shape=(2,).
        h: influence radius.
        xy: satellite positions (absolute), shape=(n, 2), each at 0 < r < h.
        order: starting order; None uses :func:`order_for` (n).
        triangles: the grain's sub-triangles (absolute), shape=(s, 3, 2).
        D: elasticity matrix, shape=(3, 3).
        thickness: t.
        comm: MPI communicator passed to :func:`geofrac.kernels.load` (collective then).

    Returns:
        (accepted order, coefficients as ``NodeFit.coefficients`` shape=(m, 2(n+1)),
        K shape=(2(n+1), 2(n+1))).

    Raises:
        ValueError: invalid input (as :func:`node_fit`).
    """
    from geofrac import kernels

    centre = np.asarray(centre, dtype=float).reshape(2)
    d = np.ascontiguousarray(_offsets(centre, h, xy))
    n = len(d)
    start = order_for(n) if order is None else order
    _check_order(start)
    tri = np.ascontiguousarray(np.asarray(triangles, dtype=float).reshape(-1, 3, 2) - centre)
    Del = np.ascontiguousarray(np.asarray(D, dtype=float).reshape(3, 3))
    ncol = 2 * (n + 1)
    G = np.zeros((ORDER_TERMS[start], ncol))
    K = np.zeros((ncol, ncol))
    module = kernels.load("cmulti", comm)
    ffi = module.ffi

    def buf(a: np.ndarray) -> Any:
        return ffi.from_buffer("double[]", a) if a.size else ffi.NULL

    accepted = module.lib.cmulti_node(
        n,
        start,
        float(h),
        buf(d),
        len(tri),
        buf(tri),
        buf(Del),
        float(thickness),
        buf(G),
        buf(K),
    )
    if accepted not in ORDER_TERMS:
        raise ValueError(f"the cmulti kernel rejected its input (code {accepted})")
    return accepted, G[: ORDER_TERMS[accepted]].copy(), K
