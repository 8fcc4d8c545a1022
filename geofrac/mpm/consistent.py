"""Energy-consistent MLS smoothing (docs/mpm_energy.md).

The seed's fit of the strain increments, and its adjoint applied to the stresses that
make the grid forces.

The seed's smoothing (Edo 2016, eqs. 4.57, 4.66) replaces each particle's strain
increment by a linear combination of its neighbours', Δε̃_p = Σ_I Φ_pI Δε_I. The stored
energy then changes by Σ_p V_p σ_p : Δε̃_p to first order, while the grid forces
f_i = −Σ_p V_p σ_p ∇φ_ip take Σ_p V_p σ_p : Δε_p(v) out of the kinetic energy: the two
differ, and the difference is energy the smoothing creates or destroys every step. With
the internal forces made from the V-weighted adjoint of the same operator,

    σ̃_I = (1 / V_I) Σ_p V_p Φ_pI σ_p,     f_i = −Σ_I V_I σ̃_I ∇φ_iI,

the force work is −Σ_I V_I σ̃_I : Δε_I(v) = −Σ_p V_p σ_p : Σ_I Φ_pI Δε_I(v) = −Σ_p V_p
σ_p : Δε̃_p(v): what the kinetic energy loses is what the stress gains, as in MPM without
smoothing, whatever Φ is. The operator is built once per step at the particles' positions
at the step's start and used for both. One process only (the adjoint of a ghost's row
would need the ghost's own neighbours).
"""

from __future__ import annotations

import numpy as np

from geofrac.mpm.smoothing import COND_MAX, basis, cubic_spline, neighbour_pairs

__all__ = ["MlsOperator", "mls_operator"]


class MlsOperator:
    """The sparse MLS operator Φ of eq. 4.57 at fixed positions.

    Attributes:
        rows: p of each entry, shape=(k,).
        cols: I of each entry, shape=(k,).
        phi: Φ_pI, shape=(k,).
        n: particles.
    """

    def __init__(self, rows: np.ndarray, cols: np.ndarray, phi: np.ndarray, n: int) -> None:
        """Hold the entries."""
        self.rows, self.cols, self.phi, self.n = rows, cols, phi, n

    def apply(self, values: np.ndarray) -> np.ndarray:
        """Σ_I Φ_pI values_I, values shape=(n, c) → shape=(n, c)."""
        return np.stack(
            [
                np.bincount(self.rows, self.phi * values[self.cols, c], minlength=self.n)
                for c in range(values.shape[1])
            ],
            axis=1,
        )

    def adjoint(self, values: np.ndarray, volume: np.ndarray) -> np.ndarray:
        """(1/V_I) Σ_p V_p Φ_pI values_p, values shape=(n, c), volume shape=(n,) → (n, c)."""
        w = self.phi * volume[self.rows]
        return (
            np.stack(
                [
                    np.bincount(self.cols, w * values[self.rows, c], minlength=self.n)
                    for c in range(values.shape[1])
                ],
                axis=1,
            )
            / volume[:, None]
        )


def mls_operator(x: np.ndarray, h: float, ids: np.ndarray | None = None) -> MlsOperator:
    """Φ of :func:`geofrac.mpm.smoothing.smooth` (same fits, same rule for who is fitted).

    A particle with fewer neighbours than basis terms or a moment matrix A whose
    condition estimate tr(A) tr(A⁻¹) is not below :data:`~geofrac.mpm.smoothing.COND_MAX`
    keeps its own value (its row is the identity).

    Args:
        x: positions, shape=(n, dim).
        h: influence radius.
        ids: global ids, the order of each particle's neighbours, shape=(n,) (default:
            the rows).
    """
    n = len(x)
    p, q = neighbour_pairs(x, h, ids)
    counts = np.bincount(p, minlength=n)
    starts = np.concatenate([[0], np.cumsum(counts)])
    F = basis((x[q] - x[p]) / h)  # shape=(k, m)
    m = F.shape[1]
    w = cubic_spline(np.sqrt(np.sum((x[q] - x[p]) ** 2, axis=1)) / h)
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
    return MlsOperator(rows, cols, np.concatenate([phi[keep], np.ones(len(ident))]), n)
