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

Ties. The motion is a continuous function of the nodal velocity: the impulse
max(Δv_n, 0) and the slowing min(μ Δv_n, |v_t|) do not jump where a row enters contact or
a node turns from slip to stick, so a round-off change of the velocity changes the
motion by round-off and those comparisons need no tolerance (one would let material
into the boundary). The decisions whose outcome does jump, the normals a corner node
keeps (its Gram-Schmidt basis) and a row's state (:func:`contact_states`: free,
sticking, slipping), treat differences within ``tol`` as ties: ``tol`` is a speed, the
step's ``REST_TOL`` × L/Δt (:func:`geofrac.mpm.schemes.rest_speed`, a billionth of a
cell per step), far above the round-off of any velocity the step forms (each is
below L/Δt) and of a gap over Δt, and far below any motion. A body at rest on a
boundary, whose nodes approach it by 0 ± round-off, is then in contact and sticking
on every machine, instead of in and out of contact with the sign of the round-off.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from geofrac.mpm.parallel import Domain

__all__ = [
    "FREE",
    "NORMAL_TOL",
    "SLIP",
    "STICK",
    "Friction",
    "apply_friction",
    "approach_allowed",
    "contact_states",
    "free_normals",
    "friction",
    "gaps",
    "held_rows",
    "hold",
    "restore_held",
]

#: A row's state (:func:`contact_states`): not in contact (moving away from the boundary,
#: or approaching it by less than its gap).
FREE = 0
#: In contact, its tangential velocity stopped: within the Coulomb bound μ Δv_n (4.45).
STICK = 1
#: In contact, sliding: the friction μ Δv_n slows it but cannot stop it (4.46).
SLIP = 2

#: Shortest length of a normal (relative to its unit length: dimensionless) that still
#: constrains anything: a frictional normal projected onto a node's free components
#: (:func:`free_normals`), or a corner's normal after the Gram-Schmidt step against the
#: normals already in contact. Below it the normal is parallel to held components or to
#: those normals (exactly 0 for the axis-aligned walls; a geometric property of the
#: boundaries, not of the motion).
NORMAL_TOL = 1e-12


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
        held_vn: the step's memory (changed by every step that uses the boundary): per
            row, the normal velocity v·n the contact left its node with in the last
            grid update where it held the row (in contact), NaN where it did not,
            shape=(k,). USF's strain takes it (:mod:`geofrac.mpm.schemes`); a
            checkpoint keeps it (:func:`held_rows`).
        held_stuck: the same memory: whether the row stuck then, shape=(k,) bool.

    The memory belongs to one run: two runs stepped with the same boundary object
    would read each other's (build or copy one per run).
    """

    nodes: np.ndarray
    normals: np.ndarray
    mu: np.ndarray
    offsets: np.ndarray | None = None
    held_vn: np.ndarray = field(default=None, repr=False, compare=False)  # type: ignore[arg-type]
    held_stuck: np.ndarray = field(default=None, repr=False, compare=False)  # type: ignore[arg-type]

    def __post_init__(self) -> None:
        """A new boundary has held nothing yet (:attr:`held_vn` all NaN)."""
        if self.held_vn is None:
            object.__setattr__(self, "held_vn", np.full(len(self.nodes), np.nan))
        if self.held_stuck is None:
            object.__setattr__(self, "held_stuck", np.zeros(len(self.nodes), dtype=bool))

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
    *,
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
    normals: np.ndarray, held: np.ndarray, tol: float = NORMAL_TOL
) -> tuple[np.ndarray, np.ndarray]:
    """Frictional normals projected onto a node's free (not held) velocity components.

    Args:
        normals: unit normals, shape=(k, dim).
        held: the nodes' held components, shape=(k, dim) bool.
        tol: a projection shorter than this (relative to the unit normal) leaves nothing
            to constrain (:data:`NORMAL_TOL`).

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
    *,
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
    # any weight counts, however small: a particle entering a node's support has the
    # weight 0 there, so whatever its gap changes reaches the particles through weights
    # that start at 0, and a node lighter than MASS_FLOOR has no velocity to constrain
    hit = (r >= 0) & (phi > 0)[:, :, None]
    if not np.any(hit):
        return out
    p_idx, slot, j = np.nonzero(hit)
    rr = r[p_idx, slot, j]
    n = fr.normals[rr]
    reach = np.einsum("ka,ka->k", x[p_idx], n) + np.einsum("ka,ka->k", lp[p_idx], np.abs(n))
    assert fr.offsets is not None  # a boundary with a touch check (the gaps need its planes)
    np.minimum.at(out, (nodes[p_idx, slot], j), fr.offsets[rr] - reach)
    return out


def approach_allowed(
    fr: Friction,
    x: np.ndarray,
    lp: np.ndarray,
    *,
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
    g = gaps(fr, x, lp, nodes=nodes, phi=phi, num_nodes=num_nodes)
    if dom is not None:
        g = dom.min_halo(g)
    # continuous in g: material reaching past the boundary (g < 0) may not approach more
    return np.maximum(g[fr.nodes, fr.layer], 0.0) / dt


def apply_friction(
    v: np.ndarray,
    fr: Friction,
    allow: np.ndarray | None = None,
    *,
    sliding_only: bool = False,
    tol: float = 0.0,
    states: np.ndarray | None = None,
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
        tol: the speed within which two velocities tie (the step's
            :func:`~geofrac.mpm.schemes.rest_speed`); 0: exact comparisons. Only a
            corner node's normals depend on it (the module's "Ties").
        states: filled with the rows' states (:func:`contact_states`' decisions, taken
            on the way), shape=(k,) int8; None: not kept.

    Returns:
        ``v``, changed on the nodes in contact.
    """
    decided = _contact(v, fr, allow, sliding_only, tol)
    if states is not None:
        states[:] = decided
    return v


def contact_states(
    v: np.ndarray,
    fr: Friction,
    allow: np.ndarray | None = None,
    *,
    sliding_only: bool = False,
    tol: float = 0.0,
) -> np.ndarray:
    """Each row's state under the nodal velocities ``v``: :data:`FREE`, :data:`STICK`, :data:`SLIP`.

    The decisions :func:`apply_friction` takes with the same arguments (``v`` is not
    changed). A row is in contact when its excess approach Δv_n = v·n − allow is above
    −``tol`` (it moves into the boundary beyond its gap, or touches it within ``tol``);
    then it sticks when the tangential speed left after the friction,
    |v_t| − μ max(Δv_n, 0) (at a corner: Σ_j μ_j Δv_n,j against the velocity left
    tangential to all its normals in contact), is at most ``tol``, and slips otherwise.

    Args:
        v: nodal velocities, shape=(num_nodes, dim).
        fr: the boundary.
        allow: per row, the normal speed at which the node may still approach,
            shape=(k,), or None (0).
        sliding_only: no friction (a row in contact sticks only when it has no
            tangential velocity beyond ``tol``).
        tol: the speed within which two velocities tie; 0: exact comparisons.

    Returns:
        The rows' states, shape=(k,) int8.
    """
    return _contact(v.copy(), fr, allow, sliding_only, tol)


def _contact(
    v: np.ndarray, fr: Friction, allow: np.ndarray | None, no_mu: bool, tol: float
) -> np.ndarray:
    """:func:`apply_friction` on ``v`` in place; returns the rows' states, shape=(k,) int8."""
    states = np.full(len(fr.nodes), FREE, dtype=np.int8)
    if len(fr.nodes) == 0:
        return states
    vn = np.einsum("ka,ka->k", v[fr.nodes], fr.normals)
    excess = vn if allow is None else vn - allow
    # in contact: moving into the boundary beyond the gap (4.44), or touching it within tol
    contact = excess > -tol
    if not np.any(contact):
        return states
    single = np.flatnonzero(contact & ~fr.shared)
    states[single] = _single(v, fr, single, vn[single], excess[single], no_mu, tol)
    corner = contact & fr.shared
    if np.any(corner):
        rows = np.flatnonzero(corner)
        for node in np.unique(fr.nodes[rows]):  # corners: a few nodes
            mine = rows[fr.nodes[rows] == node]
            states[mine] = _corner(v, fr, mine, None if allow is None else allow[mine], no_mu, tol)
    return states


def _single(
    v: np.ndarray,
    fr: Friction,
    rows: np.ndarray,
    vn: np.ndarray,
    excess: np.ndarray,
    no_mu: bool,
    tol: float,
) -> np.ndarray:
    """One boundary per node: (4.45)-(4.47) in impulse form, vectorised over ``rows``.

    ``vn``: the rows' normal velocities, ``excess`` > −tol their excess approach, both
    shape=(m,). Only the rows with ``excess`` > 0 change: the impulse max(Δv_n, 0) and
    the slowing are continuous there, so a row within ``tol`` of it keeps its velocity
    to the bit. Returns the rows' states (:data:`STICK` or :data:`SLIP`), shape=(m,).
    """
    ids, n = fr.nodes[rows], fr.normals[rows]
    vt = v[ids] - vn[:, None] * n  # tangential part
    speed = np.linalg.norm(vt, axis=1)
    dvn = np.maximum(excess, 0.0)
    budget = np.zeros_like(dvn) if no_mu else fr.mu[rows] * dvn
    # stick: the Coulomb bound μ Δv_n (4.45) stops the tangential velocity within tol
    states = np.where(speed - budget <= tol, STICK, SLIP).astype(np.int8)
    push = excess > 0.0  # a non-zero impulse (continuous at 0: no tolerance)
    ids, n, vt, speed = ids[push], n[push], vt[push], speed[push]
    if not no_mu:
        slow = np.minimum(budget[push], speed)  # at most to rest: stick
        # the division guard: a node with no tangential velocity keeps none (continuous)
        scale = np.where(speed > 0, 1.0 - slow / np.where(speed > 0, speed, 1.0), 0.0)
        vt = vt * scale[:, None]
    v[ids] = vt + (vn[push] - dvn[push])[:, None] * n  # (4.47): no approach beyond the gap
    return states


def _corner(
    v: np.ndarray,
    fr: Friction,
    rows: np.ndarray,
    allow: np.ndarray | None,
    no_mu: bool,
    tol: float,
) -> np.ndarray:
    """Several boundaries at one node: excess approaches removed, then Σ μ_j Δv_n,j.

    ``rows``: the node's rows in contact; ``allow``: their allowed approach speeds,
    shape=(m,), or None (0). A row whose excess approach, when its turn comes, is above
    −``tol`` joins the Gram-Schmidt basis: a node touching a boundary at rest keeps it
    as a constraint on every machine, whatever the sign of its round-off (the later
    rows' normals are orthogonalised against it, which changes their removal by the
    whole approach, not by round-off). ``v`` changes only when an approach is removed.

    Returns:
        The rows' states, shape=(m,) int8.
    """
    node = fr.nodes[rows[0]]
    u = v[node].copy()
    basis: list[np.ndarray] = []
    budget = 0.0
    touching = np.zeros(len(rows), dtype=bool)
    moved = False
    for k, r in enumerate(rows):
        n = fr.normals[r].copy()
        for b in basis:  # Gram-Schmidt against the normals already in contact
            n -= (n @ b) * b
        length = np.linalg.norm(n)
        if length < NORMAL_TOL:  # parallel to them: nothing left to constrain
            continue
        n /= length
        un = u @ n - (0.0 if allow is None else allow[k])
        if un <= -tol:
            continue
        touching[k] = True
        basis.append(n)
        if un > 0.0:  # a non-zero impulse (continuous at 0)
            u -= un * n
            budget += fr.mu[r] * un
            moved = True
    normal = sum(((u @ b) * b for b in basis), np.zeros_like(u))  # the allowed approach
    t = u - normal
    speed = float(np.linalg.norm(t))
    left = speed if no_mu else speed - budget  # the tangential speed left
    states = np.where(touching, STICK if left <= tol else SLIP, FREE).astype(np.int8)
    if not moved:
        return states
    if not no_mu and speed > 0:  # the division guard: no tangential velocity keeps none
        u = normal + t * (1.0 - min(budget, speed) / speed)
    v[node] = u
    return states


def hold(
    v: np.ndarray,
    fr: Friction,
    rows: np.ndarray,
    *,
    target: np.ndarray,
    stuck: np.ndarray,
) -> np.ndarray:
    """Give ``rows``' nodes the velocity the contact held them at (in place and returned).

    Args:
        v: nodal velocities, shape=(num_nodes, dim).
        fr: the boundary.
        rows: the rows, shape=(m,) int.
        target: per row, its normal velocity v·n, shape=(m,).
        stuck: per row, whether it sticks (its node keeps no velocity tangential to its
            rows' normals), shape=(m,) bool.

    A corner node's rows are taken in turn (exact for orthogonal normals, as the
    contact's Gram-Schmidt step is).

    Returns:
        ``v``.
    """
    rows = np.asarray(rows, dtype=np.int64)
    v[fr.nodes[rows[stuck]]] = 0.0  # then only the normal parts below
    layer = fr.layer[rows]
    for k in np.unique(layer):  # no node twice within a layer
        mine = layer == k
        ids, n = fr.nodes[rows[mine]], fr.normals[rows[mine]]
        vn = np.einsum("ka,ka->k", v[ids], n)
        v[ids] += (target[mine] - vn)[:, None] * n
    return v


#: A row's global key: KEY_LAYERS × its node's global id + its layer (a node has at
#: most dim walls and the bed: fewer than KEY_LAYERS rows).
KEY_LAYERS = 8


def held_rows(fr: Friction, offset: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The rows holding a memory (:attr:`Friction.held_vn` finite), by global key.

    Args:
        fr: the boundary.
        offset: the global id of this rank's local node 0 (0 without a domain).

    Returns:
        (keys shape=(h,) int64, their normal velocities shape=(h,), whether they stuck
        shape=(h,) bool), for a checkpoint.
    """
    rows = np.flatnonzero(np.isfinite(fr.held_vn))
    keys = KEY_LAYERS * (fr.nodes[rows] + offset) + fr.layer[rows]
    return keys, fr.held_vn[rows].copy(), fr.held_stuck[rows].copy()


def restore_held(
    fr: Friction, offset: int, keys: np.ndarray, *, vn: np.ndarray, stuck: np.ndarray
) -> None:
    """Set :attr:`Friction.held_vn` and ``held_stuck`` from :func:`held_rows`' arrays.

    The arrays may be any ranks' union. Rows whose key is absent are not held (NaN). A
    key held on several ranks (a halo node) has the same values on each: the nodal
    velocities are complete there.
    """
    mine = KEY_LAYERS * (fr.nodes + offset) + fr.layer
    fr.held_vn[:] = np.nan
    fr.held_stuck[:] = False
    if len(keys) == 0:
        return
    order = np.argsort(keys, kind="stable")
    keys = np.asarray(keys)[order]
    at = np.clip(np.searchsorted(keys, mine), 0, len(keys) - 1)
    found = keys[at] == mine
    fr.held_vn[found] = np.asarray(vn)[order][at[found]]
    fr.held_stuck[found] = np.asarray(stuck, dtype=bool)[order][at[found]]
