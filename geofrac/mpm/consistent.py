"""Energy-consistent MLS smoothing (docs/mpm_energy.md).

The fit of the strain increments of Edo (2016), and its adjoint applied to the stresses
that make the grid forces.

The smoothing of Edo (2016) (eqs. 4.57, 4.66) replaces each particle's strain increment
by a linear combination of its neighbours', Δε̃_p = Σ_I Φ_pI Δε_I. The stored energy
then changes by Σ_p V_p σ_p : Δε̃_p to first order, while the grid forces
f_i = −Σ_p V_p σ_p ∇φ_ip take Σ_p V_p σ_p : Δε_p(v) out of the kinetic energy: the two
differ, and the difference is energy the smoothing creates or destroys every step. With
the internal forces made from the V-weighted adjoint of the same operator,

    σ̃_I = (1 / V_I) Σ_p V_p Φ_pI σ_p,     f_i = −Σ_I V_I σ̃_I ∇φ_iI,

the force work is −Σ_I V_I σ̃_I : Δε_I(v) = −Σ_p V_p σ_p : Σ_I Φ_pI Δε_I(v) = −Σ_p V_p
σ_p : Δε̃_p(v): what the kinetic energy loses is what the stress gains, as in MPM without
smoothing, whatever Φ is. The operator is built once per step at the particles' positions
at the step's start and used for both.

On several ranks (a :class:`~geofrac.mpm.parallel.Domain`) each rank builds the rows of
the particles it owns, with the other ranks' particles within the radius as ghosts
(:meth:`~geofrac.mpm.parallel.Domain.ghosts`). :meth:`MlsOperator.apply` fetches the
ghosts' values; :meth:`MlsOperator.adjoint` sends the terms V_p Φ_pI σ_p of a ghost I to
I's owner. Every sum runs in an order fixed by global ids (a row over its neighbours' ids,
an adjoint entry over its rows' ids), so the results are the serial ones bit for bit on
any number of ranks.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from geofrac.mpm.smoothing import COND_MAX, basis, cubic_spline, neighbour_pairs

if TYPE_CHECKING:
    from geofrac.mpm.parallel import Domain

__all__ = ["MlsOperator", "mls_operator"]


class MlsOperator:
    """The sparse MLS operator Φ of eq. 4.57 at fixed positions (this rank's rows).

    Attributes:
        rows: p of each entry (an owned particle), shape=(k,).
        cols: I of each entry: an owned particle (< n) or ghost n + j, shape=(k,).
        phi: Φ_pI, shape=(k,).
        n: particles this rank owns.
        ids: global ids of the owned particles, then of the ghosts, shape=(n + ghosts,).
        domain: the decomposition, or None on one process.
        sent: per rank, the owned rows sent to it as ghosts (with a domain).
        source: the owner rank of each ghost, shape=(ghosts,).
    """

    def __init__(
        self,
        rows: np.ndarray,
        cols: np.ndarray,
        phi: np.ndarray,
        *,
        n: int,
        ids: np.ndarray,
        domain: Domain | None = None,
        sent: list[np.ndarray] | None = None,
        source: np.ndarray | None = None,
    ) -> None:
        """Hold the entries and, with a domain, the ghost exchange."""
        self.rows, self.cols, self.phi, self.n = rows, cols, phi, n
        self.ids, self.domain, self.sent = ids, domain, sent
        self.source = np.zeros(0, np.int64) if source is None else source

    def apply(self, values: np.ndarray) -> np.ndarray:
        """Σ_I Φ_pI values_I for the owned p, values shape=(n, c) → shape=(n, c).

        Collective with a domain (the ghosts' values are fetched).
        """
        if self.domain is not None:
            assert self.sent is not None  # given with the domain
            values = np.concatenate([values, self.domain.send_rows(self.sent, values)[0]])
        return np.stack(
            [
                np.bincount(self.rows, self.phi * values[self.cols, c], minlength=self.n)
                for c in range(values.shape[1])
            ],
            axis=1,
        )

    def adjoint(self, values: np.ndarray, volume: np.ndarray) -> np.ndarray:
        """(1/V_I) Σ_p V_p Φ_pI values_p for the owned I, each sum in the order of p's id.

        Collective with a domain (the terms of ghost columns go to their owners).

        Args:
            values: the owned particles' values, shape=(n, c).
            volume: their volumes, shape=(n,).

        Returns:
            shape=(n, c).
        """
        terms = (self.phi * volume[self.rows])[:, None] * values[self.rows]
        cols, by = self.cols, self.ids[self.rows]
        if self.domain is not None:
            ghost = cols >= self.n
            owner = self.source[cols[ghost] - self.n]
            out = np.flatnonzero(ghost)
            send = [out[owner == q] for q in range(len(self.domain.planes))]
            gcol, gby, gterms = self.domain.send_rows(send, self.ids[cols], by, terms)
            own = self.ids[: self.n]
            order = np.argsort(own)
            local = order[np.searchsorted(own, gcol, sorter=order)]
            keep = ~ghost
            cols = np.concatenate([cols[keep], local])
            by = np.concatenate([by[keep], gby])
            terms = np.concatenate([terms[keep], gterms])
        order = np.lexsort((by, cols))
        cols, terms = cols[order], terms[order]
        return (
            np.stack(
                [np.bincount(cols, terms[:, c], minlength=self.n) for c in range(values.shape[1])],
                axis=1,
            )
            / volume[:, None]
        )


def mls_operator(
    x: np.ndarray, h: float, ids: np.ndarray | None = None, *, domain: Domain | None = None
) -> MlsOperator:
    """Φ of :func:`geofrac.mpm.smoothing.smooth` (same fits, same rule for who is fitted).

    A particle with fewer neighbours than basis terms or a moment matrix A whose
    condition estimate tr(A) tr(A⁻¹) is not below :data:`~geofrac.mpm.smoothing.COND_MAX`
    keeps its own value (its row is the identity).

    Args:
        x: this rank's positions, shape=(n, dim).
        h: influence radius.
        ids: global ids, the order of each particle's neighbours, shape=(n,) (default:
            the rows; required with a domain).
        domain: this rank's part of a decomposed grid, or None. Collective with one.
    """
    n = len(x)
    ids = np.arange(n) if ids is None else np.asarray(ids, dtype=np.int64)
    sent = source = None
    if domain is not None:
        sent = domain.ghost_rows(x, h)
        rank = np.full(n, domain.rank, dtype=np.int64)
        gx, gids, source = domain.send_rows(sent, x, ids, rank)
        x, ids = np.concatenate([x, gx]), np.concatenate([ids, gids])
    p, q = neighbour_pairs(x, h, ids)
    mine = p < n  # the ghosts' rows are their owners'
    p, q = p[mine], q[mine]
    counts = np.bincount(p, minlength=n)
    starts = np.concatenate([[0], np.cumsum(counts)])
    F = basis((x[q] - x[p]) / h)  # shape=(k, m)
    m = F.shape[1]
    w = cubic_spline(np.sqrt(np.sum((x[q] - x[p]) ** 2, axis=1)) / h)
    A = np.zeros((n, m, m))
    if len(p):
        A = np.add.reduceat(w[:, None, None] * F[:, :, None] * F[:, None, :], starts[:-1], axis=0)
    ok = counts >= m
    cond = np.full(n, np.inf)
    if np.any(ok):
        lam = np.linalg.eigvalsh(A[ok])  # tr A = Σ λ, tr A⁻¹ = Σ 1/λ
        with np.errstate(divide="ignore"):
            est = np.sum(lam, axis=1) * np.sum(1.0 / lam, axis=1)
        cond[ok] = np.where(lam[:, 0] > 0, est, np.inf)
    ok &= cond < COND_MAX
    g = np.zeros((n, m))
    if np.any(ok):
        e0 = np.zeros((int(ok.sum()), m, 1))
        e0[:, 0] = 1.0
        g[ok] = np.linalg.solve(A[ok], e0)[:, :, 0]
    phi = w * np.sum(F * g[p], axis=1)
    keep = ok[p]
    ident = np.flatnonzero(~ok)
    rows = np.concatenate([p[keep], ident])
    cols = np.concatenate([q[keep], ident])
    phi = np.concatenate([phi[keep], np.ones(len(ident))])
    return MlsOperator(rows, cols, phi, n=n, ids=ids, domain=domain, sent=sent, source=source)
