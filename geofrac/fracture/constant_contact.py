"""Crack-face contact under loads that do not scale together (pure numpy on the pairs).

With a constant part the faces' tractions are no longer proportional to the load factor:
at the event's state u = u_c + λ u_v a pair carries p = p0 + p_c + λ p_v and
τ = τ0 + τ_c + λ τ_v (p0, τ0 the initial stress σ0 resolved on the edge, zero without
one; p_c, τ_c and p_v, τ_v the faces' stress of the constant and the variable solution).
:class:`ConstantFaces` gives the constant-load loop
(:class:`~geofrac.fracture.constant_loop.ConstantEventLoop`) what it needs for that:

- the slip events of bonded pairs, the least λ ≥ 0 at which
  |τ_c' + λ τ_v| − μ (p_c' + λ p_v) reaches c (p_c' = p0 + p_c, τ_c' = τ0 + τ_c), 0 for
  a pair already beyond it (:func:`slip_factors_affine`);
- the initial traction of the closed pairs as a load of the constant right-hand side
  (:func:`~geofrac.fracture.contact.initial_force`): a closed joint carries σ0·n;
- the pre-cracked pairs' states from σ0 (:meth:`ConstantFaces.start_states`): open under
  initial tension, slipping where |τ0| > c + μ p0, else closed and stuck (bonded with
  c > 0).

The loop settles the states at u_c + λ u_v (docs/cracking.md, "Crack faces in contact
under constant loads").
"""

from __future__ import annotations

import numpy as np

from geofrac.fracture.contact import OPEN, SLIP, STICK, edge_tractions, initial_force
from geofrac.fracture.context import CrackContext
from geofrac.fracture.criterion import TIE_TOLERANCE, least
from geofrac.fracture.faces import Faces
from geofrac.fracture.modes import Choice

__all__ = ["ConstantFaces", "slip_factors_affine"]


def slip_factors_affine(
    p: tuple[np.ndarray, np.ndarray],
    tau: tuple[np.ndarray, np.ndarray],
    cohesion: np.ndarray,
    *,
    friction: np.ndarray,
    floor: float = 0.0,
) -> tuple[np.ndarray, np.ndarray]:
    """Least λ ≥ 0 with |τ_c + λ τ_v| − μ (p_c + λ p_v) = c, per pair.

    f(λ) = |τ| − μ p − c is the larger of two lines ±τ − μ p − c, so its least root with
    f(0) < 0 is the least root of the lines of positive slope. With p_c = τ_c = 0 it is
    c / (|τ_v| − μ p_v), the proportional factor
    (:func:`~geofrac.fracture.contact.slip_factors`).

    Args:
        p: (constant, variable) pressures (compression > 0), each shape=(k,).
        tau: (constant, variable) shear tractions, each shape=(k,).
        cohesion: c > 0 per pair, shape=(k,).
        friction: μ per pair, shape=(k,).
        floor: the variable drive |τ_v| − μ p_v must exceed it (≥ 0).

    Returns:
        (λ (inf: never), overstress ratio (|τ_c| − μ p_c) / c), each shape=(k,).
    """
    (p_c, p_v), (tau_c, tau_v) = p, tau
    ratio = (np.abs(tau_c) - friction * p_c) / cohesion
    lam = np.full(len(tau_c), np.inf)
    over = ratio >= 1.0
    lam[over] = 0.0
    go = ~over & (np.abs(tau_v) - friction * p_v > max(floor, 0.0))
    for sign in (1.0, -1.0):
        slope = sign * tau_v - friction * p_v
        up = go & (slope > 0.0)
        root = (cohesion[up] - (sign * tau_c[up] - friction[up] * p_c[up])) / slope[up]
        lam[up] = np.minimum(lam[up], root)
    return lam, ratio


class ConstantFaces:
    """The face pairs of a run with a constant load (and an initial stress).

    Args:
        faces: the crack faces (``cracking.contact``).
        ctx: the shared set-up data (DOFs, thickness).

    Attributes:
        started_open: pre-cracked pairs that σ0 opens at the start.
        started_slipping: pre-cracked pairs whose initial shear exceeds c + μ p0.
    """

    def __init__(self, faces: Faces, ctx: CrackContext) -> None:
        self.faces, self.ctx = faces, ctx
        self.started_open = 0
        self.started_slipping = 0

    def set_initial(self, edge_stress: np.ndarray) -> None:
        """The initial tractions p0 = −n·σ0 n, τ0 = t·σ0 n of every edge.

        Args:
            edge_stress: σ0 at each edge's midpoint (Voigt), shape=(num_edges, 3).
        """
        pairs = self.faces.pairs
        sn, tau = edge_tractions(edge_stress, pairs.tangent, pairs.normal)
        pairs.p0[:], pairs.tau0[:] = -sn, tau

    def start_states(self, tolerance: float) -> None:
        """The pre-cracked pairs' states from σ0 (before the first solve).

        A pair under initial tension (p0 < −``tolerance``) opens; one whose initial shear
        exceeds its strength (|τ0| − μ p0 − c > ``tolerance``) slips in the direction of
        τ0; both lose their bond. The others stay closed and stuck. The blocks in the
        system follow (nothing is assembled yet).
        """
        pairs = self.faces.pairs
        edges = pairs.active()
        edges = edges[pairs.state[edges] == STICK]
        p0, tau0 = pairs.p0[edges], pairs.tau0[edges]
        opened = edges[p0 < -tolerance]
        excess = np.abs(tau0) - pairs.friction[edges] * p0 - pairs.cohesion[edges]
        slipped = edges[(p0 >= -tolerance) & (excess > tolerance)]
        pairs.state[opened] = OPEN
        pairs.state[slipped] = SLIP
        pairs.sign[slipped] = np.where(pairs.tau0[slipped] < 0.0, -1.0, 1.0)
        pairs.bonded[opened] = pairs.bonded[slipped] = False
        self.faces.resync(np.concatenate([opened, slipped]).tolist())
        self.started_open, self.started_slipping = len(opened), len(slipped)

    def force(self) -> np.ndarray:
        """The closed pairs' initial tractions as loads, shape=(n_global,) (replicated).

        Every rank sums every pair (the pairs are replicated): no communication.
        """
        ctx, pairs = self.ctx, self.faces.pairs
        out = np.zeros(ctx.n_global)
        if not np.any(pairs.p0) and not np.any(pairs.tau0):
            return out
        for e in pairs.active().tolist():
            f = initial_force(pairs, e)
            if f is not None:
                np.add.at(out, ctx.mls_dofs(f[0]), ctx.t * f[1])
        return out

    def slip_events(
        self, u_const: np.ndarray, u_var: np.ndarray, *, floor: float
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The bonded sticking pairs, their λ of slip and overstress ratio, each shape=(k,).

        Args:
            u_const: the constant load's solution, shape=(n_global,).
            u_var: the variable load's at unit factor, shape=(n_global,).
            floor: a variable drive must exceed it.
        """
        faces, pairs = self.faces, self.faces.pairs
        active = pairs.active()
        bonded = pairs.bonded[active] & (pairs.state[active] == STICK)
        if not np.any(bonded):
            empty = np.zeros(0)
            return np.zeros(0, dtype=np.int64), empty, empty
        _, _, _, p_c, tau_c = pairs.measure(faces.nodal(u_const))
        _, _, _, p_v, tau_v = pairs.measure(faces.nodal(u_var))
        edges = active[bonded]
        lam, ratio = slip_factors_affine(
            (p_c[bonded] + pairs.p0[edges], p_v[bonded]),
            (tau_c[bonded] + pairs.tau0[edges], tau_v[bonded]),
            pairs.cohesion[edges],
            friction=pairs.friction[edges],
            floor=floor,
        )
        return edges, lam, ratio

    def with_slip(
        self,
        choice: Choice,
        u_const: np.ndarray,
        u_var: np.ndarray,
        *,
        floor: float,
        points: np.ndarray | None,
    ) -> Choice:
        """The event of least λ between ``choice`` (tension, shear) and the pairs' slip.

        Ties within :data:`~geofrac.fracture.criterion.TIE_TOLERANCE` keep ``choice``; a
        pair already beyond its strength slips at λ = 0 (the most overstressed first)
        unless a site cracks at λ = 0.
        """
        edges, lam, ratio = self.slip_events(u_const, u_var, floor=floor)
        if not len(edges):
            return choice
        over = ratio >= 1.0
        if np.any(over):
            e, r = int(edges[over][np.argmax(ratio[over])]), 0.0
        else:
            e, r = least(edges, lam, points)
        if e < 0:
            return choice
        if len(choice.sites) == 0 or r < choice.r * (1.0 - TIE_TOLERANCE):
            return Choice(np.array([e], dtype=np.int64), r, "slip")
        return choice
