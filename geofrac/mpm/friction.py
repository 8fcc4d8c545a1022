"""Contact and Coulomb friction on grid nodes of a boundary (Edo (2016), eqs. 4.44-4.47).

A frictional boundary is a set of rows (node, unit normal n out of the body into the
boundary, μ, and the boundary's plane x·n = d at that node). A node on a corner has
one row per boundary.

Contact (4.44). A node is in contact with a boundary when its trial velocity
v* = v + aΔt would carry its material past the boundary within the step: v*·n > g/Δt,
g >= 0 the gap between the boundary's plane x·n = d and the nearest particle with
weight on the node (its GIMP box, or for point MPM its half-spacing box, measured
along n). Material resting on the boundary has g = 0, so this is (4.44) with the
velocity; a layer lifted by g may come back down by g and no further. Before, the
contact stopped every approach of a node whose material was within 0.1 cell of the
boundary, so each upward jitter of a sliding body's bottom layer stayed for good: it
ratcheted up to the 0.1 cell (2-3 mm in 0.3 s for a block launched on a level floor,
10 mm on a 30° slope), and once beyond it the body hopped.

Impulse form. (4.44-4.47) multiplied by Δt: the excess approach Δv_n = v*·n − g/Δt is
removed (4.47) and the tangential velocity is slowed by μ Δv_n against its direction,
at most to rest
(4.45-4.46: the thesis's μ' = μ while the node slides, μ' = |a_t| / (a·n) while it sticks,
i.e. stick when the tangential impulse needed to stop it is within μ times the normal
impulse, Coulomb slip otherwise). A node moving away from the boundary is free: the
boundary never pulls.

Several boundaries at one node (a corner of two walls, a wall meeting the bed). The
excess approaches are removed one after the other (exact for orthogonal normals;
Gram-Schmidt for others), then the remaining tangential velocity is slowed by
Σ μ_j Δv_n,j over the boundaries in contact. Components held by a wall (``fixed``) are
projected out of a frictional normal beforehand (:func:`free_normals`), so a roller
wall meeting a frictional floor holds its component and the floor keeps its normal.

Where the constraint applies. Like the held components, which are zero in every nodal
velocity the step forms, the contact acts on every nodal velocity: the one mapped from
the particles at the start of the step (USF and USAVG strain from it), the updated one
(which moves the particles), and MUSL's re-mapped one (its strain). Before, only the
updated velocity felt the contact (and the re-mapped one only its normal part), so the
strain of the bottom layer saw a floor node moving down and sideways while the
particles did not: extra compression pushed the layer up, and missing shear let a
block on a 30° slope with μ = 0.7 creep off (USF, from its equilibrium stress). The
particles take the whole change the contact makes in a step, from the mapped velocity
to the updated one; otherwise the approach removed from the mapped velocity would stay
in the particles' velocities step after step and its friction would be lost.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from geofrac.mpm.parallel import Domain

__all__ = ["Friction", "apply_friction", "approach_allowed", "free_normals", "friction", "gaps"]


@dataclass(frozen=True)
class Friction:
    """Rows (node, normal, μ, plane offset) of frictional boundaries.

    Attributes:
        nodes: flat grid node ids, shape=(k,) (a node on a corner appears once per
            boundary).
        normals: unit normals out of the body into the boundary, shape=(k, dim).
        mu: Coulomb friction coefficients μ >= 0, shape=(k,) (Edo (2016): 0.1).
        offsets: the boundary's plane at the node, x·n = d, shape=(k,); None: the
            material always touches (no touch check).
    """

    nodes: np.ndarray
    normals: np.ndarray
    mu: np.ndarray
    offsets: np.ndarray | None = None

    @cached_property
    def layer(self) -> np.ndarray:
        """Each row's layer (rows split so that no node repeats within a layer), shape=(k,).

        0 for a node's first row, 1 for its second (a corner)…
        """
        order = np.argsort(self.nodes, kind="stable")
        nodes = self.nodes[order]
        first = np.r_[True, nodes[1:] != nodes[:-1]]
        start = np.maximum.accumulate(np.where(first, np.arange(len(nodes)), 0))
        out = np.empty(len(nodes), dtype=np.int64)
        out[order] = np.arange(len(nodes)) - start
        return out

    @cached_property
    def row_table(self) -> np.ndarray:
        """Node id -> its row in each layer, or -1, shape=(max node + 1, layers)."""
        out = np.full(
            (int(self.nodes.max(initial=-1)) + 1, int(self.layer.max(initial=-1)) + 1), -1
        )
        out[self.nodes, self.layer] = np.arange(len(self.nodes))
        return out

    @cached_property
    def shared(self) -> np.ndarray:
        """Rows whose node has another row (a corner), shape=(k,) bool."""
        counts = np.bincount(self.nodes, minlength=int(self.nodes.max(initial=-1)) + 1)
        return counts[self.nodes] > 1


def friction(
    nodes: np.ndarray,
    normals: np.ndarray,
    mu: float | np.ndarray,
    offsets: np.ndarray | None = None,
) -> Friction:
    """Validated :class:`Friction` (normals normalised, μ one per row)."""
    nodes = np.asarray(nodes, dtype=np.int64).reshape(-1)
    n = np.asarray(normals, dtype=float).reshape(len(nodes), -1)
    length = np.linalg.norm(n, axis=1)
    if np.any(length == 0):
        raise ValueError("friction: every normal must be non-zero")
    mus = np.broadcast_to(np.asarray(mu, dtype=float), nodes.shape).copy()
    if not np.all(mus >= 0):
        raise ValueError(f"friction: mu must be >= 0, got {mu}")
    d = None if offsets is None else np.asarray(offsets, dtype=float).reshape(len(nodes))
    return Friction(nodes, n / length[:, None], mus, d)


def free_normals(
    normals: np.ndarray, held: np.ndarray, tol: float = 1e-12
) -> tuple[np.ndarray, np.ndarray]:
    """Frictional normals projected onto a node's free (not held) velocity components.

    Args:
        normals: unit normals, shape=(k, dim).
        held: the nodes' held components, shape=(k, dim) bool.
        tol: a projection shorter than this leaves nothing to constrain.

    Returns:
        (keep shape=(k,) bool: rows with a free normal part, the unit projected normals
        of the kept rows shape=(m, dim)).
    """
    n = np.where(held, 0.0, normals)
    length = np.linalg.norm(n, axis=1)
    keep = length > tol
    return keep, n[keep] / length[keep, None]


def gaps(
    fr: Friction,
    x: np.ndarray,
    lp: np.ndarray,
    nodes: np.ndarray,
    phi: np.ndarray,
    num_nodes: int,
) -> np.ndarray:
    """Per layer (:attr:`Friction.layer`) and node, the gap between its material and row.

    The gap of row r (node i, normal n, plane d) is the least d − (x_p·n + Σ_a |n_a| lp_a)
    over the particles p with weight on i: how far the nearest material (its box) is from
    the boundary, negative when it reaches past it. The minima are nodal (complete them
    across ranks with a minimum).

    Args:
        fr: the boundary.
        x: particle positions, shape=(n, dim).
        lp: particle half-widths, shape=(n, dim).
        nodes: the particles' node ids, shape=(n, kk).
        phi: their weights, shape=(n, kk).
        num_nodes: grid nodes.

    Returns:
        shape=(num_nodes, dim + 1), +inf where no particle has weight on a row (a node
        lies on at most dim walls and the bed; the same width on every rank).
    """
    width = max(x.shape[1] + 1, int(fr.layer.max(initial=-1)) + 1)
    out = np.full((num_nodes, width), np.inf)
    table = fr.row_table  # node -> its row in each layer, or -1
    inside = nodes < len(table)
    r = np.where(inside[:, :, None], table[np.where(inside, nodes, 0)], -1)  # (n, kk, L)
    hit = (r >= 0) & (phi > 0)[:, :, None]
    if not np.any(hit):
        return out
    p_idx, slot, j = np.nonzero(hit)
    rr = r[p_idx, slot, j]
    n = fr.normals[rr]
    reach = np.einsum("ka,ka->k", x[p_idx], n) + np.einsum("ka,ka->k", lp[p_idx], np.abs(n))
    np.minimum.at(out, (nodes[p_idx, slot], j), fr.offsets[rr] - reach)
    return out


def approach_allowed(
    fr: Friction,
    x: np.ndarray,
    lp: np.ndarray,
    nodes: np.ndarray,
    phi: np.ndarray,
    num_nodes: int,
    dt: float,
    dom: Domain | None = None,
) -> np.ndarray | None:
    """Per row, the normal speed max(g, 0)/Δt at which its node may still approach.

    Args:
        fr: the boundary.
        x: particle positions, shape=(n, dim).
        lp: particle half-widths, shape=(n, dim).
        nodes: the particles' node ids, shape=(n, kk).
        phi: their weights, shape=(n, kk).
        num_nodes: grid nodes.
        dt: the step.
        dom: the decomposition (the gaps are completed over the ranks), or None.

    Returns:
        shape=(k,); None when ``fr`` has no planes (every row touches: no gap).
    """
    if fr.offsets is None:
        return None
    g = gaps(fr, x, lp, nodes, phi, num_nodes)
    if dom is not None:
        g = dom.min_halo(g)
    return np.maximum(g[fr.nodes, fr.layer], 0.0) / dt


def apply_friction(
    v: np.ndarray, fr: Friction, allow: np.ndarray | None = None, sliding_only: bool = False
) -> np.ndarray:
    """Contact and Coulomb friction on nodal velocities (in place and returned).

    Args:
        v: nodal velocities (the trial v* = v + a Δt, or one mapped from the particles),
            shape=(num_nodes, dim).
        fr: the boundary.
        allow: per row, the normal speed at which the node may still approach
            (:func:`approach_allowed`: its gap over Δt), shape=(k,); None: 0, the
            material touches.
        sliding_only: only remove the normal approach (no friction).

    Returns:
        ``v``, changed on the nodes in contact.
    """
    if len(fr.nodes) == 0:
        return v
    vn = np.einsum("ka,ka->k", v[fr.nodes], fr.normals)
    excess = vn if allow is None else vn - allow
    contact = excess > 0.0  # moving into the boundary beyond the gap (4.44)
    if not np.any(contact):
        return v
    single = np.flatnonzero(contact & ~fr.shared)
    _single(v, fr, single, vn[single], excess[single], sliding_only)
    corner = contact & fr.shared
    if np.any(corner):
        rows = np.flatnonzero(corner)
        for node in np.unique(fr.nodes[rows]):  # corners: a few nodes
            mine = rows[fr.nodes[rows] == node]
            _corner(v, fr, mine, None if allow is None else allow[mine], sliding_only)
    return v


def _single(
    v: np.ndarray, fr: Friction, rows: np.ndarray, vn: np.ndarray, dvn: np.ndarray, no_mu: bool
) -> None:
    """One boundary per node: (4.45)-(4.47) in impulse form, vectorised over ``rows``.

    ``vn``: the rows' normal velocities, ``dvn`` > 0 the excess approach, both shape=(m,).
    """
    ids, n = fr.nodes[rows], fr.normals[rows]
    vt = v[ids] - vn[:, None] * n  # tangential part
    if not no_mu:
        speed = np.linalg.norm(vt, axis=1)
        slow = np.minimum(fr.mu[rows] * dvn, speed)  # at most to rest: stick
        scale = np.where(speed > 0, 1.0 - slow / np.where(speed > 0, speed, 1.0), 0.0)
        vt = vt * scale[:, None]
    v[ids] = vt + (vn - dvn)[:, None] * n  # (4.47): no approach beyond the gap


def _corner(
    v: np.ndarray, fr: Friction, rows: np.ndarray, allow: np.ndarray | None, no_mu: bool
) -> None:
    """Several boundaries at one node: excess approaches removed, then Σ μ_j Δv_n,j.

    ``allow``: the rows' allowed approach speeds, shape=(m,), or None (0).
    """
    node = fr.nodes[rows[0]]
    u = v[node].copy()
    basis: list[np.ndarray] = []
    budget = 0.0
    for k, r in enumerate(rows):
        n = fr.normals[r].copy()
        for b in basis:  # Gram-Schmidt against the normals already in contact
            n -= (n @ b) * b
        length = np.linalg.norm(n)
        if length < 1e-12:
            continue
        n /= length
        un = u @ n - (0.0 if allow is None else allow[k])
        if un <= 0:
            continue
        u -= un * n
        basis.append(n)
        budget += fr.mu[r] * un
    if not no_mu:
        normal = sum(((u @ b) * b for b in basis), np.zeros_like(u))  # the allowed approach
        t = u - normal
        speed = np.linalg.norm(t)
        if speed > 0:
            u = normal + t * (1.0 - min(budget, speed) / speed)
    v[node] = u
