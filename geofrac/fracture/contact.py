"""Crack faces in contact: face pairs, their open/stick/slip states, joint slip (pure numpy).

Every cracked interior edge is a *face pair*: the fields of its two cells (MLS fits,
Edo (2016), eqs. 2.10-2.18) meet on it. With n the edge's unit normal pointing from the
*minus* cell into the *plus* cell and t = (x_b − x_a)/L its tangent, the faces' relative
displacement at the edge midpoint m is

    [u] = u₊(m) − u₋(m) = Σ_q w_q u_q,    g = n · [u] (opening > 0),   s = t · [u] (slip),

a fixed linear combination of the two fits' satellite displacements. Closed faces are held
by a penalty (one-point rule at the midpoint, weight t·L):

- *stick*: normal and tangential springs, tractions p = −k g (compression > 0), τ = k s;
- *slip*: the normal spring, and Coulomb's tangential traction τ = μ p sgn, with sgn the
  direction of the slip: the block t·L·k (BₙᵀBₙ − μ sgn BₜᵀBₙ) is unsymmetric;
- *open*: nothing;

with k = ``penalty`` · E / L, so the pair's block t · penalty · E · BᵀB does not depend on
L. A closed pair penetrates by p / k: ``penalty`` = 100 leaves 1 % of the elastic
shortening of a cell of size L under the same stress.

The springs transmit the load, but their tractions k [u] are a poor measure of it: [u] is
the small difference of two fits at one point, and along a joint under uniform stress the
spring tractions of neighbouring pairs scatter by a factor of several about the true
traction. The states are therefore judged on the *faces' stress*: the mean of the two
cells' (constant) MLS stresses σ̄ = ½ D (B₊ u₊ + B₋ u₋) (eq. 2.19), resolved on the edge,

    p = −n · σ̄ n (compression > 0),    τ = t · σ̄ n,

which is exact for a uniform field and, like the stress of the tensile criterion, an
average over the fits' satellites. The states are settled per event by an active-set
iteration on the unit-load solution (:meth:`FacePairs.update`): closed pairs whose faces'
stress is tensile (p < 0) open, open pairs that interpenetrate (g < 0) close (stick),
sticking pairs with |τ| > μ p slip in the direction of τ, slipping pairs whose slip
reverses stick. Under the unit load every traction is proportional to the
load (no cohesion enters the system), so the settled states hold at the event's load.
Cohesion c enters as a strength, like f_t (2.20): a *bonded* pair (c > 0, never slipped
or opened) sticks whatever its τ, and slips as an event at the load factor
r = c / (|τ| − μ p) (:func:`slip_factors`); the first such event is the onset of
slip on a joint (Jaeger's single plane of weakness). Slipping or opening breaks the bond
(c is a peak strength; the residual strength is friction only, as the residual tensile
strength of a cracked edge is zero).

A *cohesive* pair (fracture energy, :mod:`geofrac.fracture.softening`) has, besides its
state's penalty block, springs of its current tooth's stiffness k_i per unit area in the
normal and the tangential direction, t·L·k_i (BₙᵀBₙ + BₜᵀBₜ), whatever its state: open,
they carry the crack's cohesion (traction k_i [u]); closed, the penalty adds to them, so
the normal spring is never below the contact penalty. The springs being alike in both
directions, their traction and energy are those of the effective opening
w = √(⟨g⟩² + s²) (⟨g⟩ = max(g, 0): closed faces drive the teeth by slip only): traction
k_i w, energy ½ k_i w² per unit area, so that a tooth's drop dissipates ½ w_i² (k_i −
k_{i+1}) in mixed mode too (the edges crack on σ1, Edo (2016) eq. 2.20, whatever their
orientation: an edge along the load opens in slip). Its next tooth is an event at
r = f_i / (k_i w) (:func:`soften_factors`); after its last tooth it carries
nothing more than a contact pair.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from geofrac.fracture.topology import EdgeMesh
from geofrac.mls.shape import LinearFit

__all__ = [
    "NO_PAIR",
    "OPEN",
    "SLIP",
    "STATES",
    "STICK",
    "FacePairs",
    "PairOperator",
    "constraint_terms",
    "edge_frames",
    "edge_tractions",
    "initial_force",
    "pair_block",
    "pair_links",
    "shear_factors",
    "slip_factors",
    "soften_factors",
]

#: Pair states (``-1``: the edge is no face pair).
NO_PAIR, OPEN, STICK, SLIP = -1, 0, 1, 2
#: Names of the states, by value.
STATES = ("open", "stick", "slip")

#: A pair changes state only when it violates its state's conditions by more than this
#: fraction of the pairs' typical (median) jump or traction: pairs whose faces carry almost
#: nothing (a fracture parallel to the load) would otherwise chatter between states on
#: round-off and the slightest change of the field.
STATE_TOLERANCE = 1e-3
#: The floor of the tolerances: round-off, relative to the largest jump or traction of
#: the solution, and at least relative to the unit load's a-priori scales (the control
#: displacement δ for jumps, E δ / L for tractions; :class:`FacePairs` ``jump_floor``,
#: ``traction_floor``), so that faces that carry nothing (jumps and tractions all
#: round-off) keep their states instead of following the round-off's signs.
ROUNDOFF = 1e-9


def edge_frames(mesh: EdgeMesh) -> tuple[np.ndarray, np.ndarray]:
    """Unit tangents t = (x_b − x_a)/L and normals n = (−t_y, t_x) of every edge.

    Returns:
        (t, n), each shape=(num_edges, 2).
    """
    d = mesh.coords[mesh.edges[:, 1]] - mesh.coords[mesh.edges[:, 0]]
    t = d / np.hypot(d[:, 0], d[:, 1])[:, None]
    return t, np.column_stack([-t[:, 1], t[:, 0]])


def edge_tractions(
    stress: np.ndarray, tangent: np.ndarray, normal: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Normal traction σn = n·σn (tension > 0) and shear traction τ = t·σn on planes.

    Args:
        stress: (σ_xx, σ_yy, σ_xy), shape=(k, 3).
        tangent: unit tangents of the planes, shape=(k, 2).
        normal: unit normals of the planes, shape=(k, 2).

    Returns:
        (σn, τ), each shape=(k,).
    """
    sx, sy, sxy = stress.T
    tx = sx * normal[:, 0] + sxy * normal[:, 1]
    ty = sxy * normal[:, 0] + sy * normal[:, 1]
    return tx * normal[:, 0] + ty * normal[:, 1], tx * tangent[:, 0] + ty * tangent[:, 1]


def shear_factors(
    sigma_n: np.ndarray,
    tau: np.ndarray,
    cohesion: float,
    *,
    friction_angle: float,
    floor: float = 0.0,
) -> np.ndarray:
    """Load factor r at which Mohr-Coulomb shear failure |τ| = c − σn tan φ is reached.

    Tractions under the unit load scale with r, so r (|τ| + σn tan φ) = c.

    Args:
        sigma_n: normal tractions (tension > 0), shape=(k,).
        tau: shear tractions, shape=(k,).
        cohesion: c > 0.
        friction_angle: φ in degrees.
        floor: the drive |τ| + σn tan φ must exceed it (≥ 0): a drive at round-off is
            no drive (:data:`~geofrac.fracture.scales.TENSION_FLOOR`).

    Returns:
        r per plane (inf where the tractions never reach the envelope), shape=(k,).
    """
    drive = np.abs(tau) + sigma_n * np.tan(np.radians(friction_angle))
    out = np.full(len(tau), np.inf)
    ok = drive > max(floor, 0.0)
    out[ok] = cohesion / drive[ok]
    return out


@dataclass(frozen=True)
class PairOperator:
    """The jump [u] and the faces' tractions of one pair as maps of nodal displacements.

    Attributes:
        nodes: satellite nodes of the two fits, shape=(q,).
        weights: [u] = Σ weights_q u(nodes_q), shape=(q,).
        traction: (p, τ) of the faces' mean stress = traction @ (u_x, u_y of nodes,
            interleaved), shape=(2, 2q).
    """

    nodes: np.ndarray
    weights: np.ndarray
    traction: np.ndarray


def pair_operator(
    plus: LinearFit,
    minus: LinearFit,
    point: np.ndarray,
    *,
    tangent: np.ndarray,
    normal: np.ndarray,
    D: np.ndarray,
    faces: tuple[LinearFit, LinearFit] | None = None,
) -> PairOperator:
    """[u] = u₊(point) − u₋(point) of two linear fits, and (p, τ) of their mean stress.

    Args:
        plus: the field of the cell on the +n side.
        minus: the field of the cell on the −n side.
        point: the edge midpoint, shape=(2,).
        tangent: the edge's unit t, shape=(2,).
        normal: the edge's unit n, shape=(2,).
        D: plane stress-strain matrix (Voigt, engineering shear), shape=(3, 3).
        faces: the (+, −) cells' own fits when their fields are not those fits
            (:mod:`geofrac.fracture.consistent`): the jump is taken from them, the
            stress from ``plus`` and ``minus``. Default: ``(plus, minus)``.
    """
    fp, fm = (plus, minus) if faces is None else faces
    nodes = np.concatenate([fp.nodes, fm.nodes, plus.nodes, minus.nodes]).astype(np.int64)
    w = np.concatenate([fp.shape_functions(point[None])[0], -fm.shape_functions(point[None])[0]])
    unique, index = np.unique(nodes, return_inverse=True)
    jump_at, inverse = index[: len(w)], index[len(w) :]
    q = len(unique)
    # mean strain ½ (B₊ u₊ + B₋ u₋) on the union's interleaved DOFs, shape=(3, 2q)
    B = np.zeros((3, 2 * q))
    for fit, at in ((plus, inverse[: len(plus.nodes)]), (minus, inverse[len(plus.nodes) :])):
        gx, gy = 0.5 * fit.gradients()
        np.add.at(B[0], 2 * at, gx)
        np.add.at(B[1], 2 * at + 1, gy)
        np.add.at(B[2], 2 * at, gy)
        np.add.at(B[2], 2 * at + 1, gx)
    n, t = normal, tangent
    # Voigt rows resolving (σ_xx, σ_yy, σ_xy) on the edge: −n·σn and t·σn
    resolve = np.array(
        [
            [-(n[0] ** 2), -(n[1] ** 2), -2.0 * n[0] * n[1]],
            [t[0] * n[0], t[1] * n[1], t[0] * n[1] + t[1] * n[0]],
        ]
    )
    return PairOperator(unique, np.bincount(jump_at, weights=w, minlength=q), resolve @ D @ B)


def _jump_row(op: PairOperator, direction: np.ndarray) -> np.ndarray:
    """The faces' jump along ``direction`` as a row on (u_x, u_y) of ``op.nodes``, shape=(2q,)."""
    row = np.empty(2 * len(op.nodes))
    row[0::2], row[1::2] = op.weights * direction[0], op.weights * direction[1]
    return row


class FacePairs:
    """Face pairs of the cracked interior edges: operators, states, tractions (replicated).

    Args:
        mesh: the triangle mesh with edges.
        friction: μ per edge, shape=(num_edges,).
        cohesion: c per edge, shape=(num_edges,).
        modulus: E of the penalty k = penalty · E / L.
        penalty: see the module docstring.
        D: plane stress-strain matrix of the faces' stress, shape=(3, 3).
        jump_floor: jumps within it are zero whatever the solution's own scale
            (:data:`ROUNDOFF` times the unit load's displacement in the loop).
        traction_floor: tractions within it are zero likewise (:data:`ROUNDOFF` times
            the unit load's stress E δ / L in the loop).

    Attributes:
        state: per edge, :data:`NO_PAIR` or a state, shape=(num_edges,) int8.
        sign: slip direction of slipping pairs (±1), shape=(num_edges,).
        bonded: pairs whose cohesion still holds, shape=(num_edges,) bool.
        gap, slip: g and s of the last :meth:`update`, shape=(num_edges,).
        pressure, shear: p and τ of the faces' stress at the last :meth:`update`,
            shape=(num_edges,).
    """

    def __init__(
        self,
        mesh: EdgeMesh,
        friction: np.ndarray,
        cohesion: np.ndarray,
        *,
        modulus: float,
        penalty: float,
        D: np.ndarray,
        jump_floor: float = 0.0,
        traction_floor: float = 0.0,
    ) -> None:
        self.mesh = mesh
        self.jump_floor, self.traction_floor = jump_floor, traction_floor
        self.D = np.asarray(D, dtype=float)
        self.friction = np.asarray(friction, dtype=float)
        self.cohesion = np.asarray(cohesion, dtype=float)
        ne = len(mesh.edges)
        self.tangent, self.normal = edge_frames(mesh)
        seg = mesh.coords[mesh.edges]
        self.midpoint = seg.mean(axis=1)
        self.length = np.hypot(*(seg[:, 1] - seg[:, 0]).T)
        self.k = penalty * modulus / self.length  # k per unit area, shape=(ne,)
        self.block_scale = penalty * modulus  # t L k = t · penalty · E (times thickness)
        centroids = mesh.centroids()
        c0, c1 = mesh.edge_cells[:, 0], mesh.edge_cells[:, 1]
        side = np.einsum("ij,ij->i", centroids[np.maximum(c1, 0)] - self.midpoint, self.normal)
        #: cell on the +n side and on the −n side of each edge (−1: boundary edge).
        self.plus = np.where(side > 0.0, c1, c0)
        self.minus = np.where(side > 0.0, c0, c1)
        self.plus[c1 < 0] = -1
        self.minus[c1 < 0] = -1
        self.state = np.full(ne, NO_PAIR, dtype=np.int8)
        self.sign = np.ones(ne)
        self.bonded = np.zeros(ne, dtype=bool)
        self.gap = np.zeros(ne)
        self.slip = np.zeros(ne)
        self.pressure = np.zeros(ne)
        self.shear = np.zeros(ne)
        #: the initial (in-situ) tractions p0, τ0 on every edge that the faces' stress of a
        #: solution adds to (zero without an initial stress), shape=(num_edges,) each.
        self.p0 = np.zeros(ne)
        self.tau0 = np.zeros(ne)
        #: pairs held in their state after a cycle (:meth:`update` leaves them), and the
        #: violation they were held at.
        self.frozen = np.zeros(ne, dtype=bool)
        self.held_at = np.zeros(ne)
        #: how far the last :meth:`update` found each pair outside its state's
        #: conditions, in units of the largest |g|, |s| (0: consistent).
        self.violation = np.zeros(ne)
        #: cohesive pairs: the index of the current tooth (−1: not cohesive).
        self.tooth = np.full(ne, -1, dtype=np.int64)
        #: the teeth of each pair made cohesive: (k per unit area, peak traction), each
        #: shape=(N,) (:func:`~geofrac.fracture.softening.saw_tooth`).
        self.teeth: dict[int, tuple[np.ndarray, np.ndarray]] = {}
        #: the jump operator of each pair with fits on both sides (absent: inactive).
        self.ops: dict[int, PairOperator] = {}
        #: padded arrays of the operators for :meth:`measure` (None: rebuild).
        self._table: tuple[np.ndarray, ...] | None = None

    # -- topology --------------------------------------------------------------------
    def add(self, edges: np.ndarray, state: int = STICK) -> np.ndarray:
        """Make newly cracked interior ``edges`` pairs; returns the new ones, shape=(k,).

        New pairs are in ``state`` (closed and sticking by default), bonded when their
        cohesion is positive.
        """
        edges = np.asarray(edges, dtype=np.int64)
        new = edges[(self.plus[edges] >= 0) & (self.state[edges] == NO_PAIR)]
        self.state[new] = state
        self.bonded[new] = self.cohesion[new] > 0.0
        return new

    def make_cohesive(self, edges: np.ndarray, k: np.ndarray, f: np.ndarray) -> None:
        """Give pairs ``edges`` teeth: stiffness ``k`` and peak traction ``f``, shape=(m, N)."""
        for j, e in enumerate(np.asarray(edges, dtype=np.int64).tolist()):
            self.teeth[e] = (np.array(k[j], dtype=float), np.array(f[j], dtype=float))
            self.tooth[e] = 0

    def remove(self, edge: int) -> None:
        """The pair is no pair any more (its faces carry nothing, even closed)."""
        self.state[edge] = NO_PAIR
        self.tooth[edge] = -1
        if self.ops.pop(edge, None) is not None:
            self._table = None

    def soften(self, edge: int) -> tuple[float, bool]:
        """The pair's next tooth: (energy dissipated per unit area, whether it was the last).

        The drop from tooth i to i + 1 at the peak opening w_i = f_i / k_i dissipates
        ½ w_i² (k_i − k_{i+1}) (k_{N+1} = 0).
        """
        k, f = self.teeth[edge]
        i = int(self.tooth[edge])
        w = f[i] / k[i]
        k_next = k[i + 1] if i + 1 < len(k) else 0.0
        last = i + 1 == len(k)
        self.tooth[edge] = -1 if last else i + 1
        return 0.5 * w * w * (k[i] - k_next), last

    def pairs_of_cells(self, cells: np.ndarray) -> np.ndarray:
        """The pairs with ``cells`` on either side, sorted, shape=(k,)."""
        m = self.mesh
        e = np.unique(m.cell_edges[np.asarray(cells, dtype=np.int64)].ravel())
        return e[self.state[e] != NO_PAIR]

    def refresh(
        self,
        edges: np.ndarray,
        fits: dict[int, LinearFit | None],
        *,
        own: dict[int, LinearFit | None] | None = None,
    ) -> np.ndarray:
        """Recompute the operators of pairs ``edges`` from the cells' ``fits``.

        ``own``: the cells' own fits, the faces' jump (:func:`pair_operator`). A pair
        with a void cell is inactive. Returns the pairs whose operator changed, shape=(k,).
        """
        changed = []
        for e in np.asarray(edges, dtype=np.int64).tolist():
            p, m = int(self.plus[e]), int(self.minus[e])
            fp, fm = fits.get(p), fits.get(m)
            old = self.ops.get(e)
            if fp is None or fm is None:
                if old is not None:
                    del self.ops[e]
                    changed.append(e)
                continue
            faces = None if own is None or own is fits else (own[p], own[m])
            t, n = self.tangent[e], self.normal[e]
            op = pair_operator(fp, fm, self.midpoint[e], tangent=t, normal=n, D=self.D, faces=faces)  # type: ignore[arg-type]
            if old is None or not (
                np.array_equal(old.nodes, op.nodes)
                and np.array_equal(old.weights, op.weights)
                and np.array_equal(old.traction, op.traction)
            ):
                self.ops[e] = op
                changed.append(e)
        if changed:
            self._table = None
        return np.array(changed, dtype=np.int64)

    # -- mechanics -------------------------------------------------------------------
    def _padded(self) -> tuple[np.ndarray, ...]:
        """(edges, nodes, weights, traction) of the active pairs, padded with zeros.

        Shapes (k,), (k, q), (k, q), (k, 2, 2q) with q the largest operator.
        """
        if self._table is None:
            edges = self.active()
            q = max((len(op.nodes) for op in self.ops.values()), default=1)
            nodes = np.zeros((len(edges), q), dtype=np.int64)
            weights = np.zeros((len(edges), q))
            traction = np.zeros((len(edges), 2, 2 * q))
            for i, e in enumerate(edges.tolist()):
                op = self.ops[e]
                m = len(op.nodes)
                nodes[i, :m], weights[i, :m], traction[i, :, : 2 * m] = (
                    op.nodes,
                    op.weights,
                    op.traction,
                )
            self._table = (edges, nodes, weights, traction)
        return self._table

    def measure(self, u_nodes: np.ndarray) -> tuple[np.ndarray, ...]:
        """(edges, g, s, p, τ) of the active pairs for nodal displacements.

        Args:
            u_nodes: shape=(num_nodes, 2).

        Returns:
            the active pairs and their gap, slip, and the pressure and shear traction of
            the faces' stress, each shape=(k,).
        """
        edges, nodes, weights, traction = self._padded()
        u = u_nodes[nodes]  # shape=(k, q, 2)
        jump = np.einsum("kq,kqi->ki", weights, u)
        g = np.einsum("ki,ki->k", jump, self.normal[edges])
        s = np.einsum("ki,ki->k", jump, self.tangent[edges])
        pt = np.einsum("kjd,kd->kj", traction, u.reshape(len(edges), -1))
        return edges, g, s, pt[:, 0], pt[:, 1]

    def active(self) -> np.ndarray:
        """Pairs with an operator, sorted, shape=(k,)."""
        return np.array(sorted(self.ops), dtype=np.int64)

    def tractions(self, edges: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(p, τ) of pairs ``edges`` at the last :meth:`update` (p > 0 in compression).

        The faces' stress on closed pairs; zero on open ones.
        """
        st = self.state[edges]
        closed = (st == STICK) | (st == SLIP)
        return (
            np.where(closed, self.pressure[edges], 0.0),
            np.where(closed, self.shear[edges], 0.0),
        )

    def update(self, u_nodes: np.ndarray) -> list[tuple[int, int, int]]:
        """One active-set step from the solution; returns (edge, old, new) per change.

        The faces' stress is that of the solution plus the initial tractions
        (:attr:`p0`, :attr:`tau0`; zero without an initial stress).

        Pairs in :attr:`frozen` keep their state, unless the solution violates it by more
        than twice the violation they were held at (then they are released).

        Args:
            u_nodes: nodal displacements, shape=(num_nodes, 2).
        """
        if not self.ops:
            return []
        edges, g, s, p, tau = self.measure(u_nodes)
        p, tau = p + self.p0[edges], tau + self.tau0[edges]
        self.gap[edges], self.slip[edges] = g, s
        self.pressure[edges], self.shear[edges] = p, tau
        # violations in units of the largest jump and traction; the springs' traction of
        # the largest jump keeps the traction scale meaningful when the faces carry
        # nothing (a block sliding off: p, τ are round-off)
        jump = np.maximum(np.abs(g), np.abs(s))
        traction = np.maximum(np.abs(p), np.abs(tau))
        u_scale = max(float(jump.max()), 1e-300)
        t_scale = max(float(traction.max()), float(self.k[edges].max()) * u_scale)
        tol_u = max(STATE_TOLERANCE * float(np.median(jump)), ROUNDOFF * u_scale, self.jump_floor)
        tol_t = max(
            STATE_TOLERANCE * float(np.median(traction)),
            ROUNDOFF * t_scale,
            self.traction_floor,
        )
        st = self.state[edges].copy()
        new = st.copy()
        mu = self.friction[edges]
        closed = (st == STICK) | (st == SLIP)
        violation = np.zeros(len(edges))
        close = (st == OPEN) & (g < -tol_u)
        new[close], violation[close] = STICK, -g[close] / u_scale
        opens = closed & (p < -tol_t)
        new[opens], violation[opens] = OPEN, -p[opens] / t_scale
        excess = np.abs(tau) - mu * p
        slips = (st == STICK) & ~self.bonded[edges] & ~opens & (excess > tol_t)
        new[slips], violation[slips] = SLIP, excess[slips] / t_scale
        back = (st == SLIP) & ~opens & (self.sign[edges] * s < -tol_u)
        new[back], violation[back] = STICK, -self.sign[edges][back] * s[back] / u_scale
        self.violation[edges] = violation
        # a held pair is released when the field has moved it well past its held state
        frozen = self.frozen[edges]
        release = frozen & (violation > 2.0 * self.held_at[edges] + STATE_TOLERANCE)
        self.frozen[edges[release]] = False
        frozen &= ~release
        new[frozen] = st[frozen]
        change = np.flatnonzero(new != st)
        for i in change.tolist():
            e = edges[i]
            self.state[e] = new[i]
            if new[i] == SLIP:
                self.sign[e] = np.sign(tau[i]) if tau[i] != 0.0 else np.sign(s[i])
            if new[i] == OPEN:
                self.bonded[e] = False
        return [(int(edges[i]), int(st[i]), int(new[i])) for i in change]

    def unbond(self, edge: int) -> None:
        """The pair's cohesion is lost (its slip event)."""
        self.bonded[edge] = False

    def counts(self) -> dict[str, int]:
        """Active pairs per state."""
        st = self.state[self.active()]
        return {name: int((st == i).sum()) for i, name in enumerate(STATES)}


# -- the pairs' events (the loop's modes "slip" and "soften") --------------------------
def slip_factors(pairs: FacePairs, *, floor: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """Bonded sticking pairs and the load factor r = c / (|τ| − μ p) of their slip.

    Args:
        pairs: the face pairs (states and tractions of their last update).
        floor: the drive |τ| − μ p must exceed it (≥ 0): a drive at round-off is no
            drive (:data:`~geofrac.fracture.scales.TENSION_FLOOR`).

    Returns:
        (pairs, r), shape=(k,) each; pairs whose τ never reaches c + μ p are left out.
    """
    edges = np.flatnonzero(pairs.bonded & (pairs.state == STICK))
    edges = edges[np.isin(edges, pairs.active())]
    p, tau = pairs.tractions(edges)
    drive = np.abs(tau) - pairs.friction[edges] * p
    ok = drive > max(floor, 0.0)
    return edges[ok], pairs.cohesion[edges[ok]] / drive[ok]


def soften_factors(pairs: FacePairs, *, floor: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """Cohesive pairs and the load factor r = f_i / (k_i w) of their next tooth.

    w = √(⟨g⟩² + s²) is the effective opening of the last :meth:`FacePairs.update` (module
    docstring): k_i w is the springs' traction, whose work the teeth dissipate.

    Args:
        pairs: the face pairs (jumps of their last update, current teeth).
        floor: the traction must exceed it (≥ 0;
            :data:`~geofrac.fracture.scales.TENSION_FLOOR`).

    Returns:
        (pairs, r), shape=(k,) each; pairs whose faces do not move are left out.
    """
    edges = np.flatnonzero(pairs.tooth >= 0)
    edges = edges[np.isin(edges, pairs.active())]
    if not len(edges):
        return edges, np.zeros(0)
    k = np.array([pairs.teeth[e][0][pairs.tooth[e]] for e in edges.tolist()])
    f = np.array([pairs.teeth[e][1][pairs.tooth[e]] for e in edges.tolist()])
    traction = k * np.hypot(np.maximum(pairs.gap[edges], 0.0), pairs.slip[edges])
    ok = traction > max(floor, 0.0)
    return edges[ok], f[ok] / traction[ok]


# -- what the closed pairs add to the linear system ------------------------------------
def pair_block(pairs: FacePairs, edge: int) -> tuple[np.ndarray, np.ndarray] | None:
    """(nodes, shape=(q,); matrix, shape=(2q, 2q)) of a pair's current state.

    Per unit thickness; None when the pair carries nothing (open or inactive). The
    matrix acts on (u_x, u_y) of ``nodes`` interleaved.
    """
    op = pairs.ops.get(edge)
    st = int(pairs.state[edge])
    tooth = int(pairs.tooth[edge])
    if op is None or (st not in (STICK, SLIP) and tooth < 0):
        return None
    Bn, Bt = _jump_row(op, pairs.normal[edge]), _jump_row(op, pairs.tangent[edge])
    out = None
    if st == STICK:
        K = np.outer(Bn, Bn) + np.outer(Bt, Bt)
        out = pairs.block_scale * K
    elif st == SLIP:
        K = np.outer(Bn, Bn) - pairs.friction[edge] * pairs.sign[edge] * np.outer(Bt, Bn)
        out = pairs.block_scale * K
    if tooth >= 0:  # the cohesive springs, t L k_i (BnᵀBn + BtᵀBt) per unit thickness
        springs = pairs.length[edge] * pairs.teeth[edge][0][tooth]
        cohesive = springs * (np.outer(Bn, Bn) + np.outer(Bt, Bt))
        out = cohesive if out is None else out + cohesive
    return op.nodes, out


def initial_force(pairs: FacePairs, edge: int) -> tuple[np.ndarray, np.ndarray] | None:
    """(nodes, shape=(q,); load, shape=(2q,)) of a closed pair's initial traction.

    Per unit thickness, on (u_x, u_y) of ``nodes`` interleaved: the pair's force is its
    initial traction plus the penalty's, t L (−p Bₙ + τ Bₜ) with p = p0 − k g; the
    constant part t L (−p0 Bₙ + τ0 Bₜ) goes to the right-hand side with its sign
    flipped. A sticking pair carries (p0, τ0): L (p0 Bₙ − τ0 Bₜ); a slipping one
    Coulomb's τ = μ p sgn: L p0 (Bₙ − μ sgn Bₜ). None: an open or inactive pair.
    """
    op = pairs.ops.get(edge)
    st = int(pairs.state[edge])
    if op is None or st not in (STICK, SLIP):
        return None
    p0 = float(pairs.p0[edge])
    tau = float(pairs.tau0[edge])
    if st == SLIP:
        tau = float(pairs.friction[edge] * pairs.sign[edge]) * p0
    Bn, Bt = _jump_row(op, pairs.normal[edge]), _jump_row(op, pairs.tangent[edge])
    return op.nodes, float(pairs.length[edge]) * (p0 * Bn - tau * Bt)


def pair_links(pairs: FacePairs) -> tuple[np.ndarray, np.ndarray]:
    """Node pairs (a, b) joined across closed faces: the pieces' graph."""
    a, b = [], []
    for e, op in pairs.ops.items():
        joined = pairs.state[e] in (STICK, SLIP) or pairs.tooth[e] >= 0
        if joined and len(op.nodes) > 1:
            a += [int(op.nodes[0])] * (len(op.nodes) - 1)
            b += op.nodes[1:].tolist()
    return np.array(a, dtype=np.int64), np.array(b, dtype=np.int64)


def constraint_terms(pairs: FacePairs) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """What the closed pairs hold, as rows of jumps: (rows, nodes, components, weights).

    Row r is Σ weights · u_component(node) over its terms, shape=(k,) each. A
    sticking pair ties both components of its faces' jump (two rows); a slipping
    pair the normal one only: its block (B_n − μ s B_t) B_nᵀ has no stiffness for a
    motion with B_n · u = 0, so the pieces it joins may slide along it. A cohesive
    pair's springs tie both components whatever its state.
    """
    rows, nodes, comps, weights = [], [], [], []
    r = 0
    for e in sorted(pairs.ops):
        op, st = pairs.ops[e], pairs.state[e]
        cohesive = pairs.tooth[e] >= 0
        if st not in (STICK, SLIP) and not cohesive:
            continue
        both = st == STICK or cohesive
        dirs = [pairs.normal[e], pairs.tangent[e]] if both else [pairs.normal[e]]
        q = len(op.nodes)
        for d in dirs:
            rows += [r] * (2 * q)
            nodes += np.repeat(op.nodes, 2).tolist()
            comps += [0, 1] * q
            weights += _jump_row(op, d).tolist()
            r += 1
    return (
        np.array(rows, dtype=np.int64),
        np.array(nodes, dtype=np.int64),
        np.array(comps, dtype=np.int64),
        np.array(weights, dtype=float),
    )
