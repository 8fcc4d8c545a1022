"""MLS smoothing of particle strain increments (seed 4.4.1, eqs. 4.50-4.58).

Each particle's strain increment is replaced by the moving-least-squares fit of its
neighbours' increments evaluated at the particle (4.57): with the complete cubic basis
F (4.52; 4, 10 and 20 terms in 1D, 2D and 3D) in coordinates centred on the particle
and scaled by the radius h,

    Δε_p ← F(0)ᵀ A⁻¹ B Δε_I,   A = Σ_I W(r_I, h) F(x_I) F(x_I)ᵀ,   B = [W(r_I, h) F(x_I)]

(4.53-4.56), over the neighbours I with r_I = |x_I − x_p| < h, the particle itself
included. W is the cubic spline (4.51): the seed prints its first branch as
2/3 − 4s + 4s³, which is negative at s = 1/2 and does not meet the second branch; we use
the standard cubic spline 2/3 − 4s² + 4s³ that the second branch continues. A particle
keeps its own increment when it has fewer neighbours than basis terms (the seed's
"fewer than 4" for the 1D cubic) or when its moment matrix A is singular (neighbours on
a line in 2D, say). The fit reproduces any cubic field, so linear strain increments
exactly.
"""

from __future__ import annotations

import numpy as np

__all__ = ["basis", "cubic_spline", "exponents", "neighbour_pairs", "smooth"]

#: Pairs handled per batch of fits (bounds the memory of the moment matrices).
BATCH_PAIRS = 50_000


def cubic_spline(s: np.ndarray) -> np.ndarray:
    """Eq. 4.51 (standard first branch), W(s) for s = r/h, same shape."""
    s = np.abs(s)
    return np.where(
        s < 0.5,
        2 / 3 - 4 * s**2 + 4 * s**3,
        np.where(s < 1.0, 4 / 3 - 4 * s + 4 * s**2 - 4 / 3 * s**3, 0.0),
    )


def exponents(dim: int) -> np.ndarray:
    """The exponents of the basis' monomials, shape=(m, dim), the constant first.

    Then the monomials of degree 1, 2 and 3 (in a fixed order).
    """
    exps = [e for e in np.ndindex(*(4,) * dim) if 0 < sum(e) <= 3]
    exps.sort(key=lambda e: (sum(e), [-v for v in e]))
    return np.array([(0,) * dim, *exps], dtype=np.int64)


def basis(dx: np.ndarray) -> np.ndarray:
    """Complete cubic polynomial basis at scaled offsets, dx shape=(k, dim) → (k, m).

    Columns: the monomials of :func:`exponents`.
    """
    k, dim = dx.shape
    powers = [[np.ones(k), dx[:, d], dx[:, d] ** 2, dx[:, d] ** 3] for d in range(dim)]
    cols = [np.ones(k)]
    for e in exponents(dim)[1:]:
        col = powers[0][e[0]]
        for d in range(1, dim):
            col = col * powers[d][e[d]]
        cols.append(col)
    return np.stack(cols, axis=1)


def neighbour_pairs(x: np.ndarray, h: float) -> tuple[np.ndarray, np.ndarray]:
    """All (p, I) with |x_I − x_p| < h, self included, sorted by p.

    Cell binning with cells of size h: only the 3^dim neighbouring bins are searched.

    Args:
        x: positions, shape=(n, dim).
        h: radius.

    Returns:
        p and I, each shape=(pairs,).
    """
    n, dim = x.shape
    key = np.floor((x - x.min(axis=0)) / h).astype(np.int64)
    dims = key.max(axis=0) + 3
    flat = np.ravel_multi_index(tuple((key + 1).T), dims)
    order = np.argsort(flat, kind="stable")
    sorted_flat = flat[order]
    ps, Is = [], []
    for off in np.ndindex(*(3,) * dim):
        nb = np.ravel_multi_index(tuple((key + 1 + np.array(off) - 1).T), dims)
        lo = np.searchsorted(sorted_flat, nb, side="left")
        hi = np.searchsorted(sorted_flat, nb, side="right")
        counts = hi - lo
        p = np.repeat(np.arange(n), counts)
        starts = np.repeat(lo - np.cumsum(counts) + counts, counts)
        nb_ids = order[starts + np.arange(counts.sum())]
        ps.append(p)
        Is.append(nb_ids)
    p, q = np.concatenate(ps), np.concatenate(Is)
    keep = np.sum((x[q] - x[p]) ** 2, axis=1) < h * h
    p, q = p[keep], q[keep]
    o = np.lexsort((q, p))
    return p[o], q[o]


def smooth(
    x: np.ndarray, values: np.ndarray, h: float, backend: str = "numpy"
) -> tuple[np.ndarray, np.ndarray]:
    """MLS values at each particle from its neighbours' (eq. 4.57).

    Args:
        x: positions, shape=(n, dim).
        values: per-particle values (strain increment components), shape=(n, c).
        h: influence radius.
        backend: ``numpy`` (the reference) or ``numba`` (compiled neighbour search and
            sums, :mod:`~geofrac.mpm.kernels`; the same fits to round-off).

    Returns:
        The smoothed values, shape=(n, c), and which particles were smoothed, shape=(n,)
        (the others keep their own values).
    """
    if backend == "numba":
        return _smooth_compiled(x, values, h)
    n, dim = x.shape
    p, q = neighbour_pairs(x, h)
    counts = np.bincount(p, minlength=n)
    m = basis(np.zeros((1, dim))).shape[1]
    out = values.astype(float, copy=True)
    done = np.zeros(n, dtype=bool)
    starts = np.concatenate([[0], np.cumsum(counts)])
    first = 0
    while first < n:
        last = first
        while last < n and starts[last + 1] - starts[first] <= BATCH_PAIRS:
            last += 1
        last = max(last, first + 1)
        a, b = starts[first], starts[last]
        pp, qq = p[a:b], q[a:b]
        F = basis((x[qq] - x[pp]) / h)  # shape=(k, m)
        w = cubic_spline(np.sqrt(np.sum((x[qq] - x[pp]) ** 2, axis=1)) / h)
        local = pp - first
        seg = starts[first:last] - a  # every particle has a pair (itself): no empty segment
        A = np.add.reduceat(w[:, None, None] * F[:, :, None] * F[:, None, :], seg, axis=0)
        enough = counts[first:last] >= m
        cond = np.full(last - first, np.inf)
        cond[enough] = np.linalg.cond(A[enough])
        ok = enough & (cond < 1e12)
        if np.any(ok):
            e0 = np.zeros((int(ok.sum()), m))
            e0[:, 0] = 1.0
            # row of A⁻¹ at the particle: solve A g = e0 (A symmetric), then Φ_I = w_I g·F_I
            g = np.zeros((last - first, m))
            g[ok] = np.linalg.solve(A[ok], e0[:, :, None])[:, :, 0]
            phi = w * np.sum(F * g[local], axis=1)  # zero for particles not smoothed
            acc = np.add.reduceat(phi[:, None] * values[qq], seg, axis=0)
            out[first:last][ok] = acc[ok]
            done[first:last] = ok
        first = last
    return out, done


#: Particles per batch of compiled fits (bounds the memory of the moment matrices).
BATCH_PARTICLES = 4096


def _fit_rows(A: np.ndarray, counts: np.ndarray, m: int) -> tuple[np.ndarray, np.ndarray]:
    """Which moment matrices are fitted, shape=(b,), and A⁻¹ e₀ of those, shape=(b, m).

    The reference's rule, enough neighbours and cond(A) < 1e12, with the condition
    number of the symmetric A from its eigenvalues, λ_max/λ_min (the reference's SVD
    gives the same to round-off, ~1e-12 relative, at twice the cost).
    """
    enough = counts >= m
    cond = np.full(len(A), np.inf)
    if np.any(enough):
        lam = np.linalg.eigvalsh(A[enough])
        cond[enough] = np.where(lam[:, 0] > 0, lam[:, -1] / np.maximum(lam[:, 0], 1e-300), np.inf)
    ok = enough & (cond < 1e12)
    g = np.zeros((len(A), m))
    if np.any(ok):
        e0 = np.zeros((int(ok.sum()), m, 1))
        e0[:, 0] = 1.0
        g[ok] = np.linalg.solve(A[ok], e0)[:, :, 0]
    return ok, g


def _smooth_compiled(x: np.ndarray, values: np.ndarray, h: float) -> tuple[np.ndarray, np.ndarray]:
    """:func:`smooth` with the neighbour search and the sums compiled.

    The small dense solves (condition number, A⁻¹ e₀) stay in numpy's batched LAPACK.
    """
    from geofrac.mpm import kernels

    n, dim = x.shape
    x = np.ascontiguousarray(x, dtype=float)
    values = np.ascontiguousarray(values, dtype=float)
    starts, nbrs = kernels.bin_neighbours(x, float(h))
    counts = np.diff(starts)
    exps = exponents(dim)
    m = len(exps)
    out = values.copy()
    done = np.zeros(n, dtype=bool)
    for first in range(0, n, BATCH_PARTICLES):
        last = min(n, first + BATCH_PARTICLES)
        A = np.empty((last - first, m, m))
        kernels.mls_moments(x, float(h), starts, nbrs, exps, first, A)
        ok, g = _fit_rows(A, counts[first:last], m)
        kernels.mls_sums(x, values, float(h), starts, nbrs, exps, first, g, ok, out)
        done[first:last] = ok
    return out, done
