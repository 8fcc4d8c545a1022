"""MLS smoothing of particle strain increments (Edo (2016), §4.4.1, eqs. 4.50-4.58).

Each particle's strain increment is replaced by the moving-least-squares fit of its
neighbours' increments evaluated at the particle (4.57): with the complete cubic basis
F (4.52; 4, 10 and 20 terms in 1D, 2D and 3D) in coordinates centred on the particle
and scaled by the radius h,

    Δε_p ← F(0)ᵀ A⁻¹ B Δε_I,   A = Σ_I W(r_I, h) F(x_I) F(x_I)ᵀ,   B = [W(r_I, h) F(x_I)]

(4.53-4.56), over the neighbours I with r_I = |x_I − x_p| < h, the particle itself
included. W is the cubic spline (4.51): the thesis prints its first branch as
2/3 − 4s + 4s³, which is negative at s = 1/2 and does not meet the second branch; we use
the standard cubic spline 2/3 − 4s² + 4s³ that the second branch continues. A particle
keeps its own increment when it has fewer neighbours than basis terms (the thesis's
"fewer than 4" for the 1D cubic) or when its moment matrix A is singular or
ill-conditioned (neighbours on a line in 2D, say): the fit is made when
κ_T(A) = tr(A) tr(A⁻¹) is below :data:`COND_MAX`. For the symmetric positive definite
A, with eigenvalues λ, tr A = Σ λ lies between λ_max and m λ_max and tr A⁻¹ = Σ 1/λ
between 1/λ_min and m/λ_min, so κ₂ ≤ κ_T ≤ m² κ₂: every A with κ₂ ≥ 1e12 is refused,
and some with κ₂ down to 1e12/m². The compiled fit gets tr A⁻¹ from its Cholesky
factor A = L Lᵀ as ‖L⁻¹‖²_F (L⁻¹ gives A⁻¹ e₀ too), where κ₂ would need eigenvalues; a
singular A fails the factorisation (a pivot ≤ 0) or gives a huge tr A⁻¹. The reference
computes the same κ_T from the eigenvalues. The fit reproduces any cubic field, so
linear strain increments exactly.

Each particle's neighbours are summed in the order of their global ids (``ids``), so a
fit does not depend on how the particles are stored or split over MPI ranks: on any
number of ranks it is the same floating-point operations in the same order.

The compiled fit (:func:`smooth_particles`, ``backend="numba"``) keeps its neighbour
lists between steps (Verlet lists): they are built with the radius h (1 + margin) and
reused while no particle, ghosts included, has moved more than margin·h/2 since the
build; each use keeps the candidates with r < h at the current positions, so the fits
are those of a fresh search, bit for bit.
"""

from __future__ import annotations

import time
import weakref
from dataclasses import dataclass
from functools import lru_cache
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from geofrac.mpm.parallel import Domain

__all__ = [
    "COND_MAX",
    "MARGIN",
    "basis",
    "components",
    "cubic_spline",
    "exponents",
    "moment_tables",
    "neighbour_pairs",
    "neighbour_stats",
    "smooth",
    "smooth_particles",
    "smooth_strain",
]

#: Pairs handled per batch of fits (bounds the memory of the moment matrices).
BATCH_PAIRS = 50_000

#: The largest tr(A) tr(A⁻¹) (a bound on the condition number) of a fitted moment matrix.
COND_MAX = 1e12

#: The Verlet margin of the compiled fit's neighbour lists, as a fraction of the radius.
MARGIN = 0.05


def cubic_spline(s: np.ndarray) -> np.ndarray:
    """Eq. 4.51 (standard first branch), W(s) for s = r/h, same shape."""
    s = np.abs(s)
    return np.where(
        s < 0.5,
        2 / 3 - 4 * s**2 + 4 * s**3,
        np.where(s < 1.0, 4 / 3 - 4 * s + 4 * s**2 - 4 / 3 * s**3, 0.0),
    )


def components(dim: int) -> int:
    """Columns each compiled fit takes: the independent components of a symmetric dim×dim."""
    return dim * (dim + 1) // 2


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


def neighbour_pairs(
    x: np.ndarray, h: float, ids: np.ndarray | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """All (p, I) with |x_I − x_p| < h, self included, sorted by p, then by ids[I].

    Cell binning with cells of size h: only the 3^dim neighbouring bins are searched.

    Args:
        x: positions, shape=(n, dim).
        h: radius.
        ids: global ids, shape=(n,) (default: the rows).

    Returns:
        p and I, each shape=(pairs,).
    """
    n, dim = x.shape
    if n == 0:
        return np.zeros(0, np.int64), np.zeros(0, np.int64)
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
    o = np.lexsort((q if ids is None else np.asarray(ids)[q], p))
    return p[o], q[o]


def smooth(
    x: np.ndarray,
    values: np.ndarray,
    h: float,
    *,
    backend: str = "numpy",
    ids: np.ndarray | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """MLS values at each particle from its neighbours' (eq. 4.57).

    Args:
        x: positions, shape=(n, dim).
        values: per-particle values (strain increment components), shape=(n, c).
        h: influence radius.
        backend: ``numpy`` (the reference) or ``numba`` (compiled neighbour search and
            fits, :mod:`~geofrac.mpm.kernels`; the same fits to round-off).
        ids: global ids, the order of each particle's neighbour sums, shape=(n,)
            (default: the rows).

    Returns:
        The smoothed values, shape=(n, c), and which particles were smoothed, shape=(n,)
        (the others keep their own values).
    """
    if backend == "numba":
        return _smooth_compiled(x, values, h, ids)
    n, dim = x.shape
    p, q = neighbour_pairs(x, h, ids)
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
        lam = np.linalg.eigvalsh(A[enough])  # tr A = Σ λ, tr A⁻¹ = Σ 1/λ
        with np.errstate(divide="ignore"):
            est = np.sum(lam, axis=1) * np.sum(1.0 / lam, axis=1)
        cond[enough] = np.where(lam[:, 0] > 0, est, np.inf)
        ok = enough & (cond < COND_MAX)
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


@lru_cache(maxsize=4)
def moment_tables(dim: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The basis' exponents and the distinct monomials of its moment matrix.

    Returns:
        exps, shape=(m, dim) (:func:`exponents`); mexps, the exponents of degree ≤ 6
        that are sums exps[r] + exps[c], shape=(M, dim) (28 in 2D for m = 10, 84 in 3D
        for m = 20); pair, with mexps[pair[r, c]] = exps[r] + exps[c], shape=(m, m).
    """
    exps = exponents(dim)
    sums = exps[:, None, :] + exps[None, :, :]
    mexps, pair = np.unique(sums.reshape(-1, dim), axis=0, return_inverse=True)
    return exps, np.ascontiguousarray(mexps), pair.reshape(len(exps), len(exps)).astype(np.int64)


def _smooth_compiled(
    x: np.ndarray, values: np.ndarray, h: float, ids: np.ndarray | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """:func:`smooth` with the neighbour search and the fits compiled (fresh lists)."""
    from geofrac.mpm import kernels

    n = len(x)
    x = np.ascontiguousarray(x, dtype=float)
    ids = np.arange(n, dtype=np.int64) if ids is None else np.asarray(ids, dtype=np.int64)
    starts, nbrs = kernels.neighbour_lists(x, ids, float(h), n)
    return _fit(x, values, h, starts, nbrs, n)


def _fit(
    x: np.ndarray, values: np.ndarray, h: float, starts: np.ndarray, nbrs: np.ndarray, n: int
) -> tuple[np.ndarray, np.ndarray]:
    """The compiled fits of the first n rows of x (candidates in CSR): (fits, done).

    The kernels (:mod:`~geofrac.mpm.mls_kernels`) fit dim (dim + 1)/2 columns at a time;
    other column counts are fitted in chunks of that many (zero-padded).
    """
    from geofrac.mpm import mls_kernels

    dim = x.shape[1]
    kernel = {1: mls_kernels.fit1, 2: mls_kernels.fit2, 3: mls_kernels.fit3}[dim]
    pair = moment_tables(dim)[2]
    values = np.asarray(values, dtype=float)
    nc, k = values.shape[1], components(dim)
    done = np.empty(n, dtype=bool)
    if nc == k:
        out = np.empty((n, k))
        kernel(x, np.ascontiguousarray(values), float(h), starts, nbrs, pair, COND_MAX, out, done)
        return out, done
    chunks = -(-nc // k)
    padded = np.zeros((len(values), chunks * k))
    padded[:, :nc] = values
    out = np.empty((n, chunks * k))
    for i in range(chunks):
        cols = np.ascontiguousarray(padded[:, i * k : (i + 1) * k])
        part = np.empty((n, k))
        kernel(x, cols, float(h), starts, nbrs, pair, COND_MAX, part, done)
        out[:, i * k : (i + 1) * k] = part
    return out[:, :nc], done


@dataclass
class _Lists:
    """Verlet lists of one particle set (one rank's, with its ghosts).

    Attributes:
        h: the fit radius.
        radius: the search radius h (1 + margin).
        ids: the own particles' ids at the build, shape=(n,).
        x: their positions at the build, shape=(n, dim).
        rows: per rank, the own rows sent to it as ghosts (None without a domain).
        starts: CSR starts of the own particles' candidates, shape=(n + 1,).
        nbrs: candidate rows into [own, ghosts], sorted by id per particle.
    """

    h: float
    radius: float
    ids: np.ndarray
    x: np.ndarray
    rows: list[np.ndarray] | None
    starts: np.ndarray
    nbrs: np.ndarray


#: The lists of the serial run ([None] until built) and of each domain.
_SERIAL: list[_Lists | None] = [None]
_BY_DOMAIN: weakref.WeakKeyDictionary[Domain, _Lists] = weakref.WeakKeyDictionary()

#: Builds of Verlet lists and their wall seconds in this process (for the bench).
_STATS = {"builds": 0, "build_seconds": 0.0, "uses": 0}


def neighbour_stats(*, reset: bool = False) -> dict[str, float]:
    """How often this process built and used Verlet lists, and the builds' wall seconds.

    Args:
        reset: set the counts back to zero (after reading them).
    """
    out = dict(_STATS)
    if reset:
        _STATS.update(builds=0, build_seconds=0.0, uses=0)
    return out


def _stale(lists: _Lists | None, x: np.ndarray, ids: np.ndarray, h: float, margin: float) -> bool:
    """Whether this rank's lists cannot serve positions x of particles ids (radius h)."""
    if lists is None or lists.h != h or lists.radius != h * (1 + margin):
        return True
    if lists.x.shape != x.shape or not np.array_equal(lists.ids, ids):
        return True  # particles arrived or left (migration), or another particle set
    if len(ids) == 0:
        return False
    moved2 = np.max(np.sum((x - lists.x) ** 2, axis=1))
    return bool(moved2 > (0.5 * margin * h) ** 2)


def smooth_particles(
    x: np.ndarray,
    ids: np.ndarray,
    values: np.ndarray,
    *,
    h: float,
    backend: str = "numba",
    domain: Domain | None = None,
    margin: float = MARGIN,
) -> np.ndarray:
    """The MLS fits (eq. 4.57) of a step's particles, with other ranks' as ghosts.

    The compiled backend reuses its neighbour lists between calls (see the module's
    docstring); the decision to rebuild is collective (every rank rebuilds when one
    rank's particles changed or one particle moved more than margin·h/2), as the
    ghosts' rows must stay those of the build. The numpy reference searches afresh.

    Args:
        x: this rank's positions at the step's start, shape=(n, dim).
        ids: their global ids, shape=(n,).
        values: their values, shape=(n, c).
        h: the radius.
        backend: ``numba`` or ``numpy``.
        domain: this rank's part of a decomposed grid, or None. Collective with one.
        margin: the Verlet margin as a fraction of h.

    Returns:
        The fits, or a particle's own values where it is not fitted, shape=(n, c).
    """
    n = len(x)
    ids = np.asarray(ids, dtype=np.int64)
    if backend != "numba":
        if domain is not None:
            gx, gv, gids = domain.ghosts(x, values, h, ids=ids)
            x, values = np.concatenate([x, gx]), np.concatenate([values, gv])
            ids = np.concatenate([ids, gids])
        if n == 0:
            return values[:0]
        return smooth(x, values, h, backend=backend, ids=ids)[0][:n]
    from geofrac.mpm import kernels

    lists = _SERIAL[0] if domain is None else _BY_DOMAIN.get(domain)
    stale = _stale(lists, x, ids, h, margin)
    if domain is not None:
        stale = domain.any(local=stale)
    if stale:
        t0 = time.perf_counter()
        radius = h * (1 + margin)
        rows = None
        xa, ida = x, ids
        if domain is not None:
            rows = domain.ghost_rows(x, radius)
            gx, gids = domain.send_rows(rows, x, ids)
            xa, ida = np.concatenate([x, gx]), np.concatenate([ids, gids])
        xa = np.ascontiguousarray(xa, dtype=float)
        starts, nbrs = kernels.neighbour_lists(xa, ida, float(radius), n)
        lists = _Lists(h, radius, ids.copy(), np.array(x, dtype=float), rows, starts, nbrs)
        if domain is None:
            _SERIAL[0] = lists
        else:
            _BY_DOMAIN[domain] = lists
        _STATS["builds"] += 1
        _STATS["build_seconds"] += time.perf_counter() - t0
    _STATS["uses"] += 1
    assert lists is not None  # built above unless the kept lists were fresh
    if domain is not None:
        assert lists.rows is not None  # built with this domain
        gx, gv = domain.send_rows(lists.rows, x, values)
        x, values = np.concatenate([x, gx]), np.concatenate([values, gv])
    x = np.ascontiguousarray(x, dtype=float)
    return _fit(x, values, h, lists.starts, lists.nbrs, n)[0]


def smooth_strain(
    deps: np.ndarray,
    x: np.ndarray,
    ids: np.ndarray,
    *,
    h: float,
    backend: str = "numba",
    domain: Domain | None = None,
) -> np.ndarray:
    """MLS-smoothed strain increments (eqs. 4.57, 4.66), shape=(n, dim, dim).

    Only the dim (dim + 1)/2 independent components of the symmetric increments are
    fitted (3 in 2D, 6 in 3D); the fit is linear in the values, so the result is the
    fit of all dim² components.

    Args:
        deps: strain increments, symmetric, shape=(n, dim, dim).
        x: positions at the step's start, shape=(n, dim).
        ids: global ids, shape=(n,).
        h: the radius.
        backend: ``numba`` or ``numpy``.
        domain: this rank's part of a decomposed grid, or None (collective with one).
    """
    n, d = len(deps), deps.shape[1]
    a, b = np.triu_indices(d)
    fits = smooth_particles(x, ids, deps[:, a, b], h=h, backend=backend, domain=domain)
    out = np.empty((n, d, d))
    out[:, a, b] = fits
    out[:, b, a] = fits
    return out
