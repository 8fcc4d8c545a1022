"""Writes :mod:`geofrac.mpm.mls_kernels`, the compiled MLS fits unrolled per dimension.

The fit of one particle sums, over its neighbours, the distinct moments Σ W x^e of the
moment matrix A (eq. 4.54; 7, 28 and 84 monomials of degree ≤ 6 in 1D, 2D and 3D) and
the products Σ W F_r v_c of B v (4.55-4.56). Written as loops over small arrays,
numba keeps these sums in memory and does not vectorise them: ~100 ms for the 50k
particles of one rank of the 2D block (about 46 neighbours each). With one local
variable per sum, in a loop over the gathered neighbours that the compiler may
vectorise (reassociation allowed in that loop only), they take ~13 ms, plus ~19 ms to
gather the neighbours within h and ~11 ms for the unrolled 10×10 solves. So the
kernels are generated with every sum spelt out, once, and committed
(``python -m geofrac.mpm.mls_codegen`` rewrites them; a test checks they are current).

Within a particle the neighbours are gathered in the order of their rows in ``nbrs``
(sorted by global id) and summed by one loop whose grouping of the partial sums the
compiler fixes from the number of neighbours alone: the same operations in the same
order on any number of ranks, for a reused neighbour list as for a fresh one.
"""

from __future__ import annotations

import sys
from pathlib import Path

from geofrac.mpm.smoothing import components, exponents

__all__ = ["UNROLLED", "module_source"]

#: Dimensions whose solve is unrolled too (3D's 20×20 would be ~4000 lines; it loops).
UNROLLED = (1, 2)

HEADER = '''"""Compiled MLS fits (eq. 4.57), one unrolled kernel per dimension. GENERATED FILE.

Written by :mod:`geofrac.mpm.mls_codegen` (``python -m geofrac.mpm.mls_codegen``); do not
edit by hand. ``fit1``, ``fit2`` and ``fit3`` fit the first ``len(out)`` particles from
their candidate neighbours (``nbrs``, those with r < h are used) and the
``components(dim)`` columns of ``values``; :func:`finish` makes the fit or keeps the
particle's value (:func:`geofrac.mpm.smoothing.smooth` gives the rules).
"""

from __future__ import annotations

import numba
import numpy as np

from geofrac.mpm.kernels import _spline

__all__ = ["finish", "fit1", "fit2", "fit3"]

_jit = numba.njit(cache=True)

#: The neighbour sums may be reassociated (and so vectorised): their grouping is the
#: compiler's, a fixed function of the number of neighbours, the same on every rank.
_jit_sums = numba.njit(cache=True, fastmath={"reassoc"})


@_jit
def finish(
    p: int,
    count: int,
    mom: np.ndarray,
    pair: np.ndarray,
    B: np.ndarray,
    values: np.ndarray,
    cond_max: float,
    work: np.ndarray,
    out: np.ndarray,
    done: np.ndarray,
) -> None:
    """Particle p's fit (A⁻¹ e₀)·(B v) from its moments, or its own value.

    A = L Lᵀ (Cholesky, packed rows), then L⁻¹: the fit is made when every pivot is
    positive and tr(A) tr(A⁻¹) < cond_max (tr A⁻¹ = ‖L⁻¹‖²_F); A⁻¹ e₀ = L⁻ᵀ L⁻¹ e₀.

    Args:
        p: the particle.
        count: its neighbours within h.
        mom: the moments Σ W x^e, shape=(M,).
        pair: the moment of each A_rc, shape=(m, m).
        B: Σ W F_r v_c, shape=(m, c).
        values: the values, shape=(n, c).
        cond_max: the largest accepted tr(A) tr(A⁻¹).
        work: scratch, shape=(≥ m (m + 1) + m,).
        out: the fits, shape=(k, c).
        done: whether p was fitted, shape=(k,).
    """
    m = pair.shape[0]
    nc = B.shape[1]
    done[p] = False
    for c in range(nc):
        out[p, c] = values[p, c]
    if count < m:
        return
    t = m * (m + 1) // 2
    Lp = work[:t]  # L, row i at i (i + 1)/2
    Mp = work[t : 2 * t]  # L⁻¹, same layout
    ta = 0.0  # tr A
    for r in range(m):
        ta += mom[pair[r, r]]
    for i in range(m):
        oi = i * (i + 1) // 2
        for j in range(i + 1):
            oj = j * (j + 1) // 2
            acc = mom[pair[i, j]]
            for k in range(j):
                acc -= Lp[oi + k] * Lp[oj + k]
            if i == j:
                if not acc > 0.0:
                    return
                Lp[oi + i] = np.sqrt(acc)
            else:
                Lp[oi + j] = acc / Lp[oj + j]
    ti = 0.0  # tr A⁻¹ = ‖L⁻¹‖²_F
    for i in range(m):  # L⁻¹ row by row: M_ij = −(Σ_{j ≤ k < i} L_ik M_kj) / L_ii
        oi = i * (i + 1) // 2
        d = Lp[oi + i]
        Mp[oi + i] = 1.0 / d
        ti += Mp[oi + i] * Mp[oi + i]
        for j in range(i):
            acc = 0.0
            for k in range(j, i):
                acc += Lp[oi + k] * Mp[k * (k + 1) // 2 + j]
            Mp[oi + j] = -acc / d
            ti += Mp[oi + j] * Mp[oi + j]
    if not ta * ti < cond_max:
        return
    for i in range(m):  # g = A⁻¹ e₀ = L⁻ᵀ (L⁻¹ e₀): g_i = Σ_{k ≥ i} M_ki M_k0
        acc = 0.0
        for k in range(i, m):
            ok = k * (k + 1) // 2
            acc += Mp[ok + i] * Mp[ok]
        work[2 * t + i] = acc
    done[p] = True
    for c in range(nc):
        acc = 0.0
        for r in range(m):
            acc += work[2 * t + r] * B[r, c]
        out[p, c] = acc
'''


def _name(prefix: str, e: tuple[int, ...]) -> str:
    return prefix + "".join(str(v) for v in e)


def _finish(dim: int) -> list[str]:
    """The source lines of ``_finish{dim}``: :func:`finish` unrolled for m basis terms."""
    exps = [tuple(int(v) for v in e) for e in exponents(dim)]
    moms = sorted({tuple(a + b for a, b in zip(r, c, strict=True)) for r in exps for c in exps})
    index = {e: i for i, e in enumerate(moms)}
    m, nc = len(exps), components(dim)
    L: list[str] = []
    add = L.append
    add("")
    add("")
    add("@_jit")
    add(f"def _finish{dim}(")
    add("    p: int,")
    add("    count: int,")
    add("    mom: np.ndarray,")
    add("    B: np.ndarray,")
    add("    values: np.ndarray,")
    add("    cond_max: float,")
    add("    out: np.ndarray,")
    add("    done: np.ndarray,")
    add(") -> None:")
    add(f'    """:func:`finish` for {dim}D ({m} basis terms), with every entry a local."""')
    add("    done[p] = False")
    for c in range(nc):
        add(f"    out[p, {c}] = values[p, {c}]")
    add(f"    if count < {m}:")
    add("        return")
    add("    ok = True  # every pivot positive")
    add("    ta = 0.0")
    for r in range(m):
        e = tuple(2 * v for v in exps[r])
        add(f"    ta += mom[{index[e]}]")
    for i in range(m):
        for j in range(i + 1):
            e = tuple(a + b for a, b in zip(exps[i], exps[j], strict=True))
            add(f"    t = mom[{index[e]}]")
            for k in range(j):
                add(f"    t -= l{i}_{k} * l{j}_{k}")
            if i == j:
                add("    if not t > 0.0:")
                add("        ok = False")
                add("        t = 1.0")
                add(f"    l{i}_{i} = np.sqrt(t)")
                add(f"    n{i}_{i} = 1.0 / l{i}_{i}")
            else:
                add(f"    l{i}_{j} = t * n{j}_{j}")
    add("    ti = 0.0")
    for i in range(m):  # L⁻¹, with the reciprocal pivots n_ii of the factorisation
        add(f"    ti += n{i}_{i} * n{i}_{i}")
        for j in range(i):
            add("    t = 0.0")
            for k in range(j, i):
                add(f"    t += l{i}_{k} * n{k}_{j}")
            add(f"    n{i}_{j} = -t * n{i}_{i}")
            add(f"    ti += n{i}_{j} * n{i}_{j}")
    add("    if not (ok and ta * ti < cond_max):")
    add("        return")
    add("    done[p] = True")
    for i in range(m):
        add("    t = 0.0")
        for k in range(i, m):
            add(f"    t += n{k}_{i} * n{k}_0")
        add(f"    g{i} = t")
    for c in range(nc):
        add("    t = 0.0")
        for r in range(m):
            add(f"    t += g{r} * B[{r}, {c}]")
        add(f"    out[p, {c}] = t")
    return L


def _kernel(dim: int) -> list[str]:
    """The source lines of ``_sums{dim}`` and ``fit{dim}``."""
    return _sums_source(dim) + _fit_source(dim)


def _sums_source(dim: int) -> list[str]:
    """The source lines of ``_sums{dim}``: the moments and B v of the neighbours, unrolled."""
    exps = [tuple(int(v) for v in e) for e in exponents(dim)]
    nc = components(dim)
    moms = sorted({tuple(a + b for a, b in zip(r, c, strict=True)) for r in exps for c in exps})
    pre6 = sorted({e[:-1] for e in moms})  # prefixes (axes 0 … dim−2) of the moments
    pre3 = sorted({e[:-1] for e in exps})

    def wname(pre: tuple[int, ...]) -> str:
        return "w" if all(v == 0 for v in pre) else _name("w", pre)

    L: list[str] = []
    add = L.append
    add("")
    add("")
    add("@_jit_sums")
    add(
        f"def _sums{dim}(s: np.ndarray, v: np.ndarray, k: int, mom: np.ndarray, "
        "B: np.ndarray) -> None:"
    )
    add(f'    """The moments and B v of k neighbours in {dim}D (the vectorised loop).')
    add("")
    add("    Args:")
    add("        s: scaled offsets, then the weights W, shape=(dim + 1, ≥ k).")
    add(f"        v: values, shape=({nc}, ≥ k).")
    add("        k: neighbours.")
    add(f"        mom: out, the {len(moms)} moments Σ W x^e, shape=({len(moms)},).")
    add(f"        B: out, Σ W F_r v_c, shape=({len(exps)}, {nc}).")
    add('    """')
    for e in moms:
        add(f"    {_name('m', e)} = 0.0")
    for c in range(nc):
        for e in exps:
            add(f"    {_name(f'b{c}_', e)} = 0.0")
    add("    for i in range(k):")
    add(f"        w = s[{dim}, i]")
    for a in range(dim):
        add(f"        s{a}_1 = s[{a}, i]")
        for j in range(2, 7):
            add(f"        s{a}_{j} = s{a}_{j - 1} * s{a}_1")
    # weighted prefixes w_<e> = w Π_{a < dim-1} s_a^e_a, built axis by axis
    for pre in pre6:
        if all(v == 0 for v in pre):
            continue
        last = max(i for i, v in enumerate(pre) if v > 0)
        base = pre[:last] + (0,) * (len(pre) - last)
        add(f"        {_name('w', pre)} = {wname(base)} * s{last}_{pre[last]}")
    for e in moms:
        pre, j = e[:-1], e[-1]
        term = wname(pre) + (f" * s{dim - 1}_{j}" if j else "")
        add(f"        {_name('m', e)} += {term}")
    for c in range(nc):
        add(f"        v{c} = v[{c}, i]")
        for pre in pre3:
            add(f"        {_name(f'u{c}_', pre)} = {wname(pre)} * v{c}")
        for e in exps:
            pre, j = e[:-1], e[-1]
            term = _name(f"u{c}_", pre) + (f" * s{dim - 1}_{j}" if j else "")
            add(f"        {_name(f'b{c}_', e)} += {term}")
    for i, e in enumerate(moms):
        add(f"    mom[{i}] = {_name('m', e)}")
    for c in range(nc):
        for r, e in enumerate(exps):
            add(f"    B[{r}, {c}] = {_name(f'b{c}_', e)}")
    return L


def _fit_source(dim: int) -> list[str]:
    """The source lines of ``fit{dim}``: gather each particle's neighbours, sum, solve."""
    exps = [tuple(int(v) for v in e) for e in exponents(dim)]
    nc = components(dim)
    moms = sorted({tuple(a + b for a, b in zip(r, c, strict=True)) for r in exps for c in exps})
    L: list[str] = []
    add = L.append
    add("")
    add("")
    add("@_jit")
    add(f"def fit{dim}(")
    add("    x: np.ndarray,")
    add("    values: np.ndarray,")
    add("    h: float,")
    add("    starts: np.ndarray,")
    add("    nbrs: np.ndarray,")
    add("    pair: np.ndarray,")
    add("    cond_max: float,")
    add("    out: np.ndarray,")
    add("    done: np.ndarray,")
    add(") -> None:")
    add(f'    """MLS fits in {dim}D of the first len(out) particles, {nc} value column(s).')
    add("")
    add("    Each particle's candidates within h are gathered in the list's order, then")
    add(f"    summed by :func:`_sums{dim}`. Moments in the order of ``np.unique`` of the")
    add(f"    exponent sums ({len(moms)}); ``pair`` maps A_rc to them")
    add("    (:func:`geofrac.mpm.smoothing.moment_tables`).")
    add('    """')
    add(f"    m = {len(exps)}")
    add("    h2 = h * h")
    add("    ih = 1.0 / h  # a product, not a division, per neighbour")
    add("    most = 0")
    add("    for p in range(out.shape[0]):")
    add("        most = max(most, starts[p + 1] - starts[p])")
    add(f"    s = np.zeros(({dim + 1}, most))")
    add(f"    v = np.zeros(({nc}, most))")
    add(f"    mom = np.empty({len(moms)})")
    add(f"    B = np.empty((m, {nc}))")
    if dim not in UNROLLED:
        add("    work = np.empty(3 * m * (m + 1) // 2)")
    add("    for p in range(out.shape[0]):")
    add("        k = 0")
    for a in range(dim):
        add(f"        c{a} = x[p, {a}]")
    add("        for t in range(starts[p], starts[p + 1]):")
    add("            q = nbrs[t]")
    for a in range(dim):
        add(f"            d{a} = x[q, {a}] - c{a}")
    add("            r2 = " + " + ".join(f"d{a} * d{a}" for a in range(dim)))
    add("            if not r2 < h2:")
    add("                continue")
    for a in range(dim):
        add(f"            s[{a}, k] = d{a} * ih")
    add(f"            s[{dim}, k] = _spline(np.sqrt(r2) * ih)")
    for c in range(nc):
        add(f"            v[{c}, k] = values[q, {c}]")
    add("            k += 1")
    add(f"        _sums{dim}(s, v, k, mom, B)")
    if dim in UNROLLED:
        add(f"        _finish{dim}(p, k, mom, B, values, cond_max, out, done)")
    else:
        add("        finish(p, k, mom, pair, B, values, cond_max, work, out, done)")
    return L


def module_source() -> str:
    """The text of :mod:`geofrac.mpm.mls_kernels`."""
    lines = [HEADER.rstrip("\n")]
    for dim in (1, 2, 3):
        if dim in UNROLLED:
            lines += _finish(dim)
        lines += _kernel(dim)
    return "\n".join(lines) + "\n"


def main() -> None:
    """Rewrite geofrac/mpm/mls_kernels.py."""
    path = Path(__file__).with_name("mls_kernels.py")
    path.write_text(module_source(), encoding="utf-8")
    print(f"wrote {path}", file=sys.stderr)


if __name__ == "__main__":
    main()
