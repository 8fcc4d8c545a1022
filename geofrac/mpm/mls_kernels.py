"""Compiled MLS fits (eq. 4.57), one unrolled kernel per dimension. GENERATED FILE.

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


@_jit
def _finish1(
    p: int,
    count: int,
    mom: np.ndarray,
    B: np.ndarray,
    values: np.ndarray,
    cond_max: float,
    out: np.ndarray,
    done: np.ndarray,
) -> None:
    """:func:`finish` for 1D (4 basis terms), with every entry a local."""
    done[p] = False
    out[p, 0] = values[p, 0]
    if count < 4:
        return
    ok = True  # every pivot positive
    ta = 0.0
    ta += mom[0]
    ta += mom[2]
    ta += mom[4]
    ta += mom[6]
    t = mom[0]
    if not t > 0.0:
        ok = False
        t = 1.0
    l0_0 = np.sqrt(t)
    n0_0 = 1.0 / l0_0
    t = mom[1]
    l1_0 = t * n0_0
    t = mom[2]
    t -= l1_0 * l1_0
    if not t > 0.0:
        ok = False
        t = 1.0
    l1_1 = np.sqrt(t)
    n1_1 = 1.0 / l1_1
    t = mom[2]
    l2_0 = t * n0_0
    t = mom[3]
    t -= l2_0 * l1_0
    l2_1 = t * n1_1
    t = mom[4]
    t -= l2_0 * l2_0
    t -= l2_1 * l2_1
    if not t > 0.0:
        ok = False
        t = 1.0
    l2_2 = np.sqrt(t)
    n2_2 = 1.0 / l2_2
    t = mom[3]
    l3_0 = t * n0_0
    t = mom[4]
    t -= l3_0 * l1_0
    l3_1 = t * n1_1
    t = mom[5]
    t -= l3_0 * l2_0
    t -= l3_1 * l2_1
    l3_2 = t * n2_2
    t = mom[6]
    t -= l3_0 * l3_0
    t -= l3_1 * l3_1
    t -= l3_2 * l3_2
    if not t > 0.0:
        ok = False
        t = 1.0
    l3_3 = np.sqrt(t)
    n3_3 = 1.0 / l3_3
    ti = 0.0
    ti += n0_0 * n0_0
    ti += n1_1 * n1_1
    t = 0.0
    t += l1_0 * n0_0
    n1_0 = -t * n1_1
    ti += n1_0 * n1_0
    ti += n2_2 * n2_2
    t = 0.0
    t += l2_0 * n0_0
    t += l2_1 * n1_0
    n2_0 = -t * n2_2
    ti += n2_0 * n2_0
    t = 0.0
    t += l2_1 * n1_1
    n2_1 = -t * n2_2
    ti += n2_1 * n2_1
    ti += n3_3 * n3_3
    t = 0.0
    t += l3_0 * n0_0
    t += l3_1 * n1_0
    t += l3_2 * n2_0
    n3_0 = -t * n3_3
    ti += n3_0 * n3_0
    t = 0.0
    t += l3_1 * n1_1
    t += l3_2 * n2_1
    n3_1 = -t * n3_3
    ti += n3_1 * n3_1
    t = 0.0
    t += l3_2 * n2_2
    n3_2 = -t * n3_3
    ti += n3_2 * n3_2
    if not (ok and ta * ti < cond_max):
        return
    done[p] = True
    t = 0.0
    t += n0_0 * n0_0
    t += n1_0 * n1_0
    t += n2_0 * n2_0
    t += n3_0 * n3_0
    g0 = t
    t = 0.0
    t += n1_1 * n1_0
    t += n2_1 * n2_0
    t += n3_1 * n3_0
    g1 = t
    t = 0.0
    t += n2_2 * n2_0
    t += n3_2 * n3_0
    g2 = t
    t = 0.0
    t += n3_3 * n3_0
    g3 = t
    t = 0.0
    t += g0 * B[0, 0]
    t += g1 * B[1, 0]
    t += g2 * B[2, 0]
    t += g3 * B[3, 0]
    out[p, 0] = t


@_jit_sums
def _sums1(s: np.ndarray, v: np.ndarray, k: int, mom: np.ndarray, B: np.ndarray) -> None:
    """The moments and B v of k neighbours in 1D (the vectorised loop).

    Args:
        s: scaled offsets, then the weights W, shape=(dim + 1, ≥ k).
        v: values, shape=(1, ≥ k).
        k: neighbours.
        mom: out, the 7 moments Σ W x^e, shape=(7,).
        B: out, Σ W F_r v_c, shape=(4, 1).
    """
    m0 = 0.0
    m1 = 0.0
    m2 = 0.0
    m3 = 0.0
    m4 = 0.0
    m5 = 0.0
    m6 = 0.0
    b0_0 = 0.0
    b0_1 = 0.0
    b0_2 = 0.0
    b0_3 = 0.0
    for i in range(k):
        w = s[1, i]
        s0_1 = s[0, i]
        s0_2 = s0_1 * s0_1
        s0_3 = s0_2 * s0_1
        s0_4 = s0_3 * s0_1
        s0_5 = s0_4 * s0_1
        s0_6 = s0_5 * s0_1
        m0 += w
        m1 += w * s0_1
        m2 += w * s0_2
        m3 += w * s0_3
        m4 += w * s0_4
        m5 += w * s0_5
        m6 += w * s0_6
        v0 = v[0, i]
        u0_ = w * v0
        b0_0 += u0_
        b0_1 += u0_ * s0_1
        b0_2 += u0_ * s0_2
        b0_3 += u0_ * s0_3
    mom[0] = m0
    mom[1] = m1
    mom[2] = m2
    mom[3] = m3
    mom[4] = m4
    mom[5] = m5
    mom[6] = m6
    B[0, 0] = b0_0
    B[1, 0] = b0_1
    B[2, 0] = b0_2
    B[3, 0] = b0_3


@_jit
def fit1(
    x: np.ndarray,
    values: np.ndarray,
    h: float,
    starts: np.ndarray,
    nbrs: np.ndarray,
    pair: np.ndarray,
    cond_max: float,
    out: np.ndarray,
    done: np.ndarray,
) -> None:
    """MLS fits in 1D of the first len(out) particles, 1 value column(s).

    Each particle's candidates within h are gathered in the list's order, then
    summed by :func:`_sums1`. Moments in the order of ``np.unique`` of the
    exponent sums (7); ``pair`` maps A_rc to them
    (:func:`geofrac.mpm.smoothing.moment_tables`).
    """
    m = 4
    h2 = h * h
    ih = 1.0 / h  # a product, not a division, per neighbour
    most = 0
    for p in range(out.shape[0]):
        most = max(most, starts[p + 1] - starts[p])
    s = np.zeros((2, most))
    v = np.zeros((1, most))
    mom = np.empty(7)
    B = np.empty((m, 1))
    for p in range(out.shape[0]):
        k = 0
        c0 = x[p, 0]
        for t in range(starts[p], starts[p + 1]):
            q = nbrs[t]
            d0 = x[q, 0] - c0
            r2 = d0 * d0
            if not r2 < h2:
                continue
            s[0, k] = d0 * ih
            s[1, k] = _spline(np.sqrt(r2) * ih)
            v[0, k] = values[q, 0]
            k += 1
        _sums1(s, v, k, mom, B)
        _finish1(p, k, mom, B, values, cond_max, out, done)


@_jit
def _finish2(
    p: int,
    count: int,
    mom: np.ndarray,
    B: np.ndarray,
    values: np.ndarray,
    cond_max: float,
    out: np.ndarray,
    done: np.ndarray,
) -> None:
    """:func:`finish` for 2D (10 basis terms), with every entry a local."""
    done[p] = False
    out[p, 0] = values[p, 0]
    out[p, 1] = values[p, 1]
    out[p, 2] = values[p, 2]
    if count < 10:
        return
    ok = True  # every pivot positive
    ta = 0.0
    ta += mom[0]
    ta += mom[13]
    ta += mom[2]
    ta += mom[22]
    ta += mom[15]
    ta += mom[4]
    ta += mom[27]
    ta += mom[24]
    ta += mom[17]
    ta += mom[6]
    t = mom[0]
    if not t > 0.0:
        ok = False
        t = 1.0
    l0_0 = np.sqrt(t)
    n0_0 = 1.0 / l0_0
    t = mom[7]
    l1_0 = t * n0_0
    t = mom[13]
    t -= l1_0 * l1_0
    if not t > 0.0:
        ok = False
        t = 1.0
    l1_1 = np.sqrt(t)
    n1_1 = 1.0 / l1_1
    t = mom[1]
    l2_0 = t * n0_0
    t = mom[8]
    t -= l2_0 * l1_0
    l2_1 = t * n1_1
    t = mom[2]
    t -= l2_0 * l2_0
    t -= l2_1 * l2_1
    if not t > 0.0:
        ok = False
        t = 1.0
    l2_2 = np.sqrt(t)
    n2_2 = 1.0 / l2_2
    t = mom[13]
    l3_0 = t * n0_0
    t = mom[18]
    t -= l3_0 * l1_0
    l3_1 = t * n1_1
    t = mom[14]
    t -= l3_0 * l2_0
    t -= l3_1 * l2_1
    l3_2 = t * n2_2
    t = mom[22]
    t -= l3_0 * l3_0
    t -= l3_1 * l3_1
    t -= l3_2 * l3_2
    if not t > 0.0:
        ok = False
        t = 1.0
    l3_3 = np.sqrt(t)
    n3_3 = 1.0 / l3_3
    t = mom[8]
    l4_0 = t * n0_0
    t = mom[14]
    t -= l4_0 * l1_0
    l4_1 = t * n1_1
    t = mom[9]
    t -= l4_0 * l2_0
    t -= l4_1 * l2_1
    l4_2 = t * n2_2
    t = mom[19]
    t -= l4_0 * l3_0
    t -= l4_1 * l3_1
    t -= l4_2 * l3_2
    l4_3 = t * n3_3
    t = mom[15]
    t -= l4_0 * l4_0
    t -= l4_1 * l4_1
    t -= l4_2 * l4_2
    t -= l4_3 * l4_3
    if not t > 0.0:
        ok = False
        t = 1.0
    l4_4 = np.sqrt(t)
    n4_4 = 1.0 / l4_4
    t = mom[2]
    l5_0 = t * n0_0
    t = mom[9]
    t -= l5_0 * l1_0
    l5_1 = t * n1_1
    t = mom[3]
    t -= l5_0 * l2_0
    t -= l5_1 * l2_1
    l5_2 = t * n2_2
    t = mom[15]
    t -= l5_0 * l3_0
    t -= l5_1 * l3_1
    t -= l5_2 * l3_2
    l5_3 = t * n3_3
    t = mom[10]
    t -= l5_0 * l4_0
    t -= l5_1 * l4_1
    t -= l5_2 * l4_2
    t -= l5_3 * l4_3
    l5_4 = t * n4_4
    t = mom[4]
    t -= l5_0 * l5_0
    t -= l5_1 * l5_1
    t -= l5_2 * l5_2
    t -= l5_3 * l5_3
    t -= l5_4 * l5_4
    if not t > 0.0:
        ok = False
        t = 1.0
    l5_5 = np.sqrt(t)
    n5_5 = 1.0 / l5_5
    t = mom[18]
    l6_0 = t * n0_0
    t = mom[22]
    t -= l6_0 * l1_0
    l6_1 = t * n1_1
    t = mom[19]
    t -= l6_0 * l2_0
    t -= l6_1 * l2_1
    l6_2 = t * n2_2
    t = mom[25]
    t -= l6_0 * l3_0
    t -= l6_1 * l3_1
    t -= l6_2 * l3_2
    l6_3 = t * n3_3
    t = mom[23]
    t -= l6_0 * l4_0
    t -= l6_1 * l4_1
    t -= l6_2 * l4_2
    t -= l6_3 * l4_3
    l6_4 = t * n4_4
    t = mom[20]
    t -= l6_0 * l5_0
    t -= l6_1 * l5_1
    t -= l6_2 * l5_2
    t -= l6_3 * l5_3
    t -= l6_4 * l5_4
    l6_5 = t * n5_5
    t = mom[27]
    t -= l6_0 * l6_0
    t -= l6_1 * l6_1
    t -= l6_2 * l6_2
    t -= l6_3 * l6_3
    t -= l6_4 * l6_4
    t -= l6_5 * l6_5
    if not t > 0.0:
        ok = False
        t = 1.0
    l6_6 = np.sqrt(t)
    n6_6 = 1.0 / l6_6
    t = mom[14]
    l7_0 = t * n0_0
    t = mom[19]
    t -= l7_0 * l1_0
    l7_1 = t * n1_1
    t = mom[15]
    t -= l7_0 * l2_0
    t -= l7_1 * l2_1
    l7_2 = t * n2_2
    t = mom[23]
    t -= l7_0 * l3_0
    t -= l7_1 * l3_1
    t -= l7_2 * l3_2
    l7_3 = t * n3_3
    t = mom[20]
    t -= l7_0 * l4_0
    t -= l7_1 * l4_1
    t -= l7_2 * l4_2
    t -= l7_3 * l4_3
    l7_4 = t * n4_4
    t = mom[16]
    t -= l7_0 * l5_0
    t -= l7_1 * l5_1
    t -= l7_2 * l5_2
    t -= l7_3 * l5_3
    t -= l7_4 * l5_4
    l7_5 = t * n5_5
    t = mom[26]
    t -= l7_0 * l6_0
    t -= l7_1 * l6_1
    t -= l7_2 * l6_2
    t -= l7_3 * l6_3
    t -= l7_4 * l6_4
    t -= l7_5 * l6_5
    l7_6 = t * n6_6
    t = mom[24]
    t -= l7_0 * l7_0
    t -= l7_1 * l7_1
    t -= l7_2 * l7_2
    t -= l7_3 * l7_3
    t -= l7_4 * l7_4
    t -= l7_5 * l7_5
    t -= l7_6 * l7_6
    if not t > 0.0:
        ok = False
        t = 1.0
    l7_7 = np.sqrt(t)
    n7_7 = 1.0 / l7_7
    t = mom[9]
    l8_0 = t * n0_0
    t = mom[15]
    t -= l8_0 * l1_0
    l8_1 = t * n1_1
    t = mom[10]
    t -= l8_0 * l2_0
    t -= l8_1 * l2_1
    l8_2 = t * n2_2
    t = mom[20]
    t -= l8_0 * l3_0
    t -= l8_1 * l3_1
    t -= l8_2 * l3_2
    l8_3 = t * n3_3
    t = mom[16]
    t -= l8_0 * l4_0
    t -= l8_1 * l4_1
    t -= l8_2 * l4_2
    t -= l8_3 * l4_3
    l8_4 = t * n4_4
    t = mom[11]
    t -= l8_0 * l5_0
    t -= l8_1 * l5_1
    t -= l8_2 * l5_2
    t -= l8_3 * l5_3
    t -= l8_4 * l5_4
    l8_5 = t * n5_5
    t = mom[24]
    t -= l8_0 * l6_0
    t -= l8_1 * l6_1
    t -= l8_2 * l6_2
    t -= l8_3 * l6_3
    t -= l8_4 * l6_4
    t -= l8_5 * l6_5
    l8_6 = t * n6_6
    t = mom[21]
    t -= l8_0 * l7_0
    t -= l8_1 * l7_1
    t -= l8_2 * l7_2
    t -= l8_3 * l7_3
    t -= l8_4 * l7_4
    t -= l8_5 * l7_5
    t -= l8_6 * l7_6
    l8_7 = t * n7_7
    t = mom[17]
    t -= l8_0 * l8_0
    t -= l8_1 * l8_1
    t -= l8_2 * l8_2
    t -= l8_3 * l8_3
    t -= l8_4 * l8_4
    t -= l8_5 * l8_5
    t -= l8_6 * l8_6
    t -= l8_7 * l8_7
    if not t > 0.0:
        ok = False
        t = 1.0
    l8_8 = np.sqrt(t)
    n8_8 = 1.0 / l8_8
    t = mom[3]
    l9_0 = t * n0_0
    t = mom[10]
    t -= l9_0 * l1_0
    l9_1 = t * n1_1
    t = mom[4]
    t -= l9_0 * l2_0
    t -= l9_1 * l2_1
    l9_2 = t * n2_2
    t = mom[16]
    t -= l9_0 * l3_0
    t -= l9_1 * l3_1
    t -= l9_2 * l3_2
    l9_3 = t * n3_3
    t = mom[11]
    t -= l9_0 * l4_0
    t -= l9_1 * l4_1
    t -= l9_2 * l4_2
    t -= l9_3 * l4_3
    l9_4 = t * n4_4
    t = mom[5]
    t -= l9_0 * l5_0
    t -= l9_1 * l5_1
    t -= l9_2 * l5_2
    t -= l9_3 * l5_3
    t -= l9_4 * l5_4
    l9_5 = t * n5_5
    t = mom[21]
    t -= l9_0 * l6_0
    t -= l9_1 * l6_1
    t -= l9_2 * l6_2
    t -= l9_3 * l6_3
    t -= l9_4 * l6_4
    t -= l9_5 * l6_5
    l9_6 = t * n6_6
    t = mom[17]
    t -= l9_0 * l7_0
    t -= l9_1 * l7_1
    t -= l9_2 * l7_2
    t -= l9_3 * l7_3
    t -= l9_4 * l7_4
    t -= l9_5 * l7_5
    t -= l9_6 * l7_6
    l9_7 = t * n7_7
    t = mom[12]
    t -= l9_0 * l8_0
    t -= l9_1 * l8_1
    t -= l9_2 * l8_2
    t -= l9_3 * l8_3
    t -= l9_4 * l8_4
    t -= l9_5 * l8_5
    t -= l9_6 * l8_6
    t -= l9_7 * l8_7
    l9_8 = t * n8_8
    t = mom[6]
    t -= l9_0 * l9_0
    t -= l9_1 * l9_1
    t -= l9_2 * l9_2
    t -= l9_3 * l9_3
    t -= l9_4 * l9_4
    t -= l9_5 * l9_5
    t -= l9_6 * l9_6
    t -= l9_7 * l9_7
    t -= l9_8 * l9_8
    if not t > 0.0:
        ok = False
        t = 1.0
    l9_9 = np.sqrt(t)
    n9_9 = 1.0 / l9_9
    ti = 0.0
    ti += n0_0 * n0_0
    ti += n1_1 * n1_1
    t = 0.0
    t += l1_0 * n0_0
    n1_0 = -t * n1_1
    ti += n1_0 * n1_0
    ti += n2_2 * n2_2
    t = 0.0
    t += l2_0 * n0_0
    t += l2_1 * n1_0
    n2_0 = -t * n2_2
    ti += n2_0 * n2_0
    t = 0.0
    t += l2_1 * n1_1
    n2_1 = -t * n2_2
    ti += n2_1 * n2_1
    ti += n3_3 * n3_3
    t = 0.0
    t += l3_0 * n0_0
    t += l3_1 * n1_0
    t += l3_2 * n2_0
    n3_0 = -t * n3_3
    ti += n3_0 * n3_0
    t = 0.0
    t += l3_1 * n1_1
    t += l3_2 * n2_1
    n3_1 = -t * n3_3
    ti += n3_1 * n3_1
    t = 0.0
    t += l3_2 * n2_2
    n3_2 = -t * n3_3
    ti += n3_2 * n3_2
    ti += n4_4 * n4_4
    t = 0.0
    t += l4_0 * n0_0
    t += l4_1 * n1_0
    t += l4_2 * n2_0
    t += l4_3 * n3_0
    n4_0 = -t * n4_4
    ti += n4_0 * n4_0
    t = 0.0
    t += l4_1 * n1_1
    t += l4_2 * n2_1
    t += l4_3 * n3_1
    n4_1 = -t * n4_4
    ti += n4_1 * n4_1
    t = 0.0
    t += l4_2 * n2_2
    t += l4_3 * n3_2
    n4_2 = -t * n4_4
    ti += n4_2 * n4_2
    t = 0.0
    t += l4_3 * n3_3
    n4_3 = -t * n4_4
    ti += n4_3 * n4_3
    ti += n5_5 * n5_5
    t = 0.0
    t += l5_0 * n0_0
    t += l5_1 * n1_0
    t += l5_2 * n2_0
    t += l5_3 * n3_0
    t += l5_4 * n4_0
    n5_0 = -t * n5_5
    ti += n5_0 * n5_0
    t = 0.0
    t += l5_1 * n1_1
    t += l5_2 * n2_1
    t += l5_3 * n3_1
    t += l5_4 * n4_1
    n5_1 = -t * n5_5
    ti += n5_1 * n5_1
    t = 0.0
    t += l5_2 * n2_2
    t += l5_3 * n3_2
    t += l5_4 * n4_2
    n5_2 = -t * n5_5
    ti += n5_2 * n5_2
    t = 0.0
    t += l5_3 * n3_3
    t += l5_4 * n4_3
    n5_3 = -t * n5_5
    ti += n5_3 * n5_3
    t = 0.0
    t += l5_4 * n4_4
    n5_4 = -t * n5_5
    ti += n5_4 * n5_4
    ti += n6_6 * n6_6
    t = 0.0
    t += l6_0 * n0_0
    t += l6_1 * n1_0
    t += l6_2 * n2_0
    t += l6_3 * n3_0
    t += l6_4 * n4_0
    t += l6_5 * n5_0
    n6_0 = -t * n6_6
    ti += n6_0 * n6_0
    t = 0.0
    t += l6_1 * n1_1
    t += l6_2 * n2_1
    t += l6_3 * n3_1
    t += l6_4 * n4_1
    t += l6_5 * n5_1
    n6_1 = -t * n6_6
    ti += n6_1 * n6_1
    t = 0.0
    t += l6_2 * n2_2
    t += l6_3 * n3_2
    t += l6_4 * n4_2
    t += l6_5 * n5_2
    n6_2 = -t * n6_6
    ti += n6_2 * n6_2
    t = 0.0
    t += l6_3 * n3_3
    t += l6_4 * n4_3
    t += l6_5 * n5_3
    n6_3 = -t * n6_6
    ti += n6_3 * n6_3
    t = 0.0
    t += l6_4 * n4_4
    t += l6_5 * n5_4
    n6_4 = -t * n6_6
    ti += n6_4 * n6_4
    t = 0.0
    t += l6_5 * n5_5
    n6_5 = -t * n6_6
    ti += n6_5 * n6_5
    ti += n7_7 * n7_7
    t = 0.0
    t += l7_0 * n0_0
    t += l7_1 * n1_0
    t += l7_2 * n2_0
    t += l7_3 * n3_0
    t += l7_4 * n4_0
    t += l7_5 * n5_0
    t += l7_6 * n6_0
    n7_0 = -t * n7_7
    ti += n7_0 * n7_0
    t = 0.0
    t += l7_1 * n1_1
    t += l7_2 * n2_1
    t += l7_3 * n3_1
    t += l7_4 * n4_1
    t += l7_5 * n5_1
    t += l7_6 * n6_1
    n7_1 = -t * n7_7
    ti += n7_1 * n7_1
    t = 0.0
    t += l7_2 * n2_2
    t += l7_3 * n3_2
    t += l7_4 * n4_2
    t += l7_5 * n5_2
    t += l7_6 * n6_2
    n7_2 = -t * n7_7
    ti += n7_2 * n7_2
    t = 0.0
    t += l7_3 * n3_3
    t += l7_4 * n4_3
    t += l7_5 * n5_3
    t += l7_6 * n6_3
    n7_3 = -t * n7_7
    ti += n7_3 * n7_3
    t = 0.0
    t += l7_4 * n4_4
    t += l7_5 * n5_4
    t += l7_6 * n6_4
    n7_4 = -t * n7_7
    ti += n7_4 * n7_4
    t = 0.0
    t += l7_5 * n5_5
    t += l7_6 * n6_5
    n7_5 = -t * n7_7
    ti += n7_5 * n7_5
    t = 0.0
    t += l7_6 * n6_6
    n7_6 = -t * n7_7
    ti += n7_6 * n7_6
    ti += n8_8 * n8_8
    t = 0.0
    t += l8_0 * n0_0
    t += l8_1 * n1_0
    t += l8_2 * n2_0
    t += l8_3 * n3_0
    t += l8_4 * n4_0
    t += l8_5 * n5_0
    t += l8_6 * n6_0
    t += l8_7 * n7_0
    n8_0 = -t * n8_8
    ti += n8_0 * n8_0
    t = 0.0
    t += l8_1 * n1_1
    t += l8_2 * n2_1
    t += l8_3 * n3_1
    t += l8_4 * n4_1
    t += l8_5 * n5_1
    t += l8_6 * n6_1
    t += l8_7 * n7_1
    n8_1 = -t * n8_8
    ti += n8_1 * n8_1
    t = 0.0
    t += l8_2 * n2_2
    t += l8_3 * n3_2
    t += l8_4 * n4_2
    t += l8_5 * n5_2
    t += l8_6 * n6_2
    t += l8_7 * n7_2
    n8_2 = -t * n8_8
    ti += n8_2 * n8_2
    t = 0.0
    t += l8_3 * n3_3
    t += l8_4 * n4_3
    t += l8_5 * n5_3
    t += l8_6 * n6_3
    t += l8_7 * n7_3
    n8_3 = -t * n8_8
    ti += n8_3 * n8_3
    t = 0.0
    t += l8_4 * n4_4
    t += l8_5 * n5_4
    t += l8_6 * n6_4
    t += l8_7 * n7_4
    n8_4 = -t * n8_8
    ti += n8_4 * n8_4
    t = 0.0
    t += l8_5 * n5_5
    t += l8_6 * n6_5
    t += l8_7 * n7_5
    n8_5 = -t * n8_8
    ti += n8_5 * n8_5
    t = 0.0
    t += l8_6 * n6_6
    t += l8_7 * n7_6
    n8_6 = -t * n8_8
    ti += n8_6 * n8_6
    t = 0.0
    t += l8_7 * n7_7
    n8_7 = -t * n8_8
    ti += n8_7 * n8_7
    ti += n9_9 * n9_9
    t = 0.0
    t += l9_0 * n0_0
    t += l9_1 * n1_0
    t += l9_2 * n2_0
    t += l9_3 * n3_0
    t += l9_4 * n4_0
    t += l9_5 * n5_0
    t += l9_6 * n6_0
    t += l9_7 * n7_0
    t += l9_8 * n8_0
    n9_0 = -t * n9_9
    ti += n9_0 * n9_0
    t = 0.0
    t += l9_1 * n1_1
    t += l9_2 * n2_1
    t += l9_3 * n3_1
    t += l9_4 * n4_1
    t += l9_5 * n5_1
    t += l9_6 * n6_1
    t += l9_7 * n7_1
    t += l9_8 * n8_1
    n9_1 = -t * n9_9
    ti += n9_1 * n9_1
    t = 0.0
    t += l9_2 * n2_2
    t += l9_3 * n3_2
    t += l9_4 * n4_2
    t += l9_5 * n5_2
    t += l9_6 * n6_2
    t += l9_7 * n7_2
    t += l9_8 * n8_2
    n9_2 = -t * n9_9
    ti += n9_2 * n9_2
    t = 0.0
    t += l9_3 * n3_3
    t += l9_4 * n4_3
    t += l9_5 * n5_3
    t += l9_6 * n6_3
    t += l9_7 * n7_3
    t += l9_8 * n8_3
    n9_3 = -t * n9_9
    ti += n9_3 * n9_3
    t = 0.0
    t += l9_4 * n4_4
    t += l9_5 * n5_4
    t += l9_6 * n6_4
    t += l9_7 * n7_4
    t += l9_8 * n8_4
    n9_4 = -t * n9_9
    ti += n9_4 * n9_4
    t = 0.0
    t += l9_5 * n5_5
    t += l9_6 * n6_5
    t += l9_7 * n7_5
    t += l9_8 * n8_5
    n9_5 = -t * n9_9
    ti += n9_5 * n9_5
    t = 0.0
    t += l9_6 * n6_6
    t += l9_7 * n7_6
    t += l9_8 * n8_6
    n9_6 = -t * n9_9
    ti += n9_6 * n9_6
    t = 0.0
    t += l9_7 * n7_7
    t += l9_8 * n8_7
    n9_7 = -t * n9_9
    ti += n9_7 * n9_7
    t = 0.0
    t += l9_8 * n8_8
    n9_8 = -t * n9_9
    ti += n9_8 * n9_8
    if not (ok and ta * ti < cond_max):
        return
    done[p] = True
    t = 0.0
    t += n0_0 * n0_0
    t += n1_0 * n1_0
    t += n2_0 * n2_0
    t += n3_0 * n3_0
    t += n4_0 * n4_0
    t += n5_0 * n5_0
    t += n6_0 * n6_0
    t += n7_0 * n7_0
    t += n8_0 * n8_0
    t += n9_0 * n9_0
    g0 = t
    t = 0.0
    t += n1_1 * n1_0
    t += n2_1 * n2_0
    t += n3_1 * n3_0
    t += n4_1 * n4_0
    t += n5_1 * n5_0
    t += n6_1 * n6_0
    t += n7_1 * n7_0
    t += n8_1 * n8_0
    t += n9_1 * n9_0
    g1 = t
    t = 0.0
    t += n2_2 * n2_0
    t += n3_2 * n3_0
    t += n4_2 * n4_0
    t += n5_2 * n5_0
    t += n6_2 * n6_0
    t += n7_2 * n7_0
    t += n8_2 * n8_0
    t += n9_2 * n9_0
    g2 = t
    t = 0.0
    t += n3_3 * n3_0
    t += n4_3 * n4_0
    t += n5_3 * n5_0
    t += n6_3 * n6_0
    t += n7_3 * n7_0
    t += n8_3 * n8_0
    t += n9_3 * n9_0
    g3 = t
    t = 0.0
    t += n4_4 * n4_0
    t += n5_4 * n5_0
    t += n6_4 * n6_0
    t += n7_4 * n7_0
    t += n8_4 * n8_0
    t += n9_4 * n9_0
    g4 = t
    t = 0.0
    t += n5_5 * n5_0
    t += n6_5 * n6_0
    t += n7_5 * n7_0
    t += n8_5 * n8_0
    t += n9_5 * n9_0
    g5 = t
    t = 0.0
    t += n6_6 * n6_0
    t += n7_6 * n7_0
    t += n8_6 * n8_0
    t += n9_6 * n9_0
    g6 = t
    t = 0.0
    t += n7_7 * n7_0
    t += n8_7 * n8_0
    t += n9_7 * n9_0
    g7 = t
    t = 0.0
    t += n8_8 * n8_0
    t += n9_8 * n9_0
    g8 = t
    t = 0.0
    t += n9_9 * n9_0
    g9 = t
    t = 0.0
    t += g0 * B[0, 0]
    t += g1 * B[1, 0]
    t += g2 * B[2, 0]
    t += g3 * B[3, 0]
    t += g4 * B[4, 0]
    t += g5 * B[5, 0]
    t += g6 * B[6, 0]
    t += g7 * B[7, 0]
    t += g8 * B[8, 0]
    t += g9 * B[9, 0]
    out[p, 0] = t
    t = 0.0
    t += g0 * B[0, 1]
    t += g1 * B[1, 1]
    t += g2 * B[2, 1]
    t += g3 * B[3, 1]
    t += g4 * B[4, 1]
    t += g5 * B[5, 1]
    t += g6 * B[6, 1]
    t += g7 * B[7, 1]
    t += g8 * B[8, 1]
    t += g9 * B[9, 1]
    out[p, 1] = t
    t = 0.0
    t += g0 * B[0, 2]
    t += g1 * B[1, 2]
    t += g2 * B[2, 2]
    t += g3 * B[3, 2]
    t += g4 * B[4, 2]
    t += g5 * B[5, 2]
    t += g6 * B[6, 2]
    t += g7 * B[7, 2]
    t += g8 * B[8, 2]
    t += g9 * B[9, 2]
    out[p, 2] = t


@_jit_sums
def _sums2(s: np.ndarray, v: np.ndarray, k: int, mom: np.ndarray, B: np.ndarray) -> None:
    """The moments and B v of k neighbours in 2D (the vectorised loop).

    Args:
        s: scaled offsets, then the weights W, shape=(dim + 1, ≥ k).
        v: values, shape=(3, ≥ k).
        k: neighbours.
        mom: out, the 28 moments Σ W x^e, shape=(28,).
        B: out, Σ W F_r v_c, shape=(10, 3).
    """
    m00 = 0.0
    m01 = 0.0
    m02 = 0.0
    m03 = 0.0
    m04 = 0.0
    m05 = 0.0
    m06 = 0.0
    m10 = 0.0
    m11 = 0.0
    m12 = 0.0
    m13 = 0.0
    m14 = 0.0
    m15 = 0.0
    m20 = 0.0
    m21 = 0.0
    m22 = 0.0
    m23 = 0.0
    m24 = 0.0
    m30 = 0.0
    m31 = 0.0
    m32 = 0.0
    m33 = 0.0
    m40 = 0.0
    m41 = 0.0
    m42 = 0.0
    m50 = 0.0
    m51 = 0.0
    m60 = 0.0
    b0_00 = 0.0
    b0_10 = 0.0
    b0_01 = 0.0
    b0_20 = 0.0
    b0_11 = 0.0
    b0_02 = 0.0
    b0_30 = 0.0
    b0_21 = 0.0
    b0_12 = 0.0
    b0_03 = 0.0
    b1_00 = 0.0
    b1_10 = 0.0
    b1_01 = 0.0
    b1_20 = 0.0
    b1_11 = 0.0
    b1_02 = 0.0
    b1_30 = 0.0
    b1_21 = 0.0
    b1_12 = 0.0
    b1_03 = 0.0
    b2_00 = 0.0
    b2_10 = 0.0
    b2_01 = 0.0
    b2_20 = 0.0
    b2_11 = 0.0
    b2_02 = 0.0
    b2_30 = 0.0
    b2_21 = 0.0
    b2_12 = 0.0
    b2_03 = 0.0
    for i in range(k):
        w = s[2, i]
        s0_1 = s[0, i]
        s0_2 = s0_1 * s0_1
        s0_3 = s0_2 * s0_1
        s0_4 = s0_3 * s0_1
        s0_5 = s0_4 * s0_1
        s0_6 = s0_5 * s0_1
        s1_1 = s[1, i]
        s1_2 = s1_1 * s1_1
        s1_3 = s1_2 * s1_1
        s1_4 = s1_3 * s1_1
        s1_5 = s1_4 * s1_1
        s1_6 = s1_5 * s1_1
        w1 = w * s0_1
        w2 = w * s0_2
        w3 = w * s0_3
        w4 = w * s0_4
        w5 = w * s0_5
        w6 = w * s0_6
        m00 += w
        m01 += w * s1_1
        m02 += w * s1_2
        m03 += w * s1_3
        m04 += w * s1_4
        m05 += w * s1_5
        m06 += w * s1_6
        m10 += w1
        m11 += w1 * s1_1
        m12 += w1 * s1_2
        m13 += w1 * s1_3
        m14 += w1 * s1_4
        m15 += w1 * s1_5
        m20 += w2
        m21 += w2 * s1_1
        m22 += w2 * s1_2
        m23 += w2 * s1_3
        m24 += w2 * s1_4
        m30 += w3
        m31 += w3 * s1_1
        m32 += w3 * s1_2
        m33 += w3 * s1_3
        m40 += w4
        m41 += w4 * s1_1
        m42 += w4 * s1_2
        m50 += w5
        m51 += w5 * s1_1
        m60 += w6
        v0 = v[0, i]
        u0_0 = w * v0
        u0_1 = w1 * v0
        u0_2 = w2 * v0
        u0_3 = w3 * v0
        b0_00 += u0_0
        b0_10 += u0_1
        b0_01 += u0_0 * s1_1
        b0_20 += u0_2
        b0_11 += u0_1 * s1_1
        b0_02 += u0_0 * s1_2
        b0_30 += u0_3
        b0_21 += u0_2 * s1_1
        b0_12 += u0_1 * s1_2
        b0_03 += u0_0 * s1_3
        v1 = v[1, i]
        u1_0 = w * v1
        u1_1 = w1 * v1
        u1_2 = w2 * v1
        u1_3 = w3 * v1
        b1_00 += u1_0
        b1_10 += u1_1
        b1_01 += u1_0 * s1_1
        b1_20 += u1_2
        b1_11 += u1_1 * s1_1
        b1_02 += u1_0 * s1_2
        b1_30 += u1_3
        b1_21 += u1_2 * s1_1
        b1_12 += u1_1 * s1_2
        b1_03 += u1_0 * s1_3
        v2 = v[2, i]
        u2_0 = w * v2
        u2_1 = w1 * v2
        u2_2 = w2 * v2
        u2_3 = w3 * v2
        b2_00 += u2_0
        b2_10 += u2_1
        b2_01 += u2_0 * s1_1
        b2_20 += u2_2
        b2_11 += u2_1 * s1_1
        b2_02 += u2_0 * s1_2
        b2_30 += u2_3
        b2_21 += u2_2 * s1_1
        b2_12 += u2_1 * s1_2
        b2_03 += u2_0 * s1_3
    mom[0] = m00
    mom[1] = m01
    mom[2] = m02
    mom[3] = m03
    mom[4] = m04
    mom[5] = m05
    mom[6] = m06
    mom[7] = m10
    mom[8] = m11
    mom[9] = m12
    mom[10] = m13
    mom[11] = m14
    mom[12] = m15
    mom[13] = m20
    mom[14] = m21
    mom[15] = m22
    mom[16] = m23
    mom[17] = m24
    mom[18] = m30
    mom[19] = m31
    mom[20] = m32
    mom[21] = m33
    mom[22] = m40
    mom[23] = m41
    mom[24] = m42
    mom[25] = m50
    mom[26] = m51
    mom[27] = m60
    B[0, 0] = b0_00
    B[1, 0] = b0_10
    B[2, 0] = b0_01
    B[3, 0] = b0_20
    B[4, 0] = b0_11
    B[5, 0] = b0_02
    B[6, 0] = b0_30
    B[7, 0] = b0_21
    B[8, 0] = b0_12
    B[9, 0] = b0_03
    B[0, 1] = b1_00
    B[1, 1] = b1_10
    B[2, 1] = b1_01
    B[3, 1] = b1_20
    B[4, 1] = b1_11
    B[5, 1] = b1_02
    B[6, 1] = b1_30
    B[7, 1] = b1_21
    B[8, 1] = b1_12
    B[9, 1] = b1_03
    B[0, 2] = b2_00
    B[1, 2] = b2_10
    B[2, 2] = b2_01
    B[3, 2] = b2_20
    B[4, 2] = b2_11
    B[5, 2] = b2_02
    B[6, 2] = b2_30
    B[7, 2] = b2_21
    B[8, 2] = b2_12
    B[9, 2] = b2_03


@_jit
def fit2(
    x: np.ndarray,
    values: np.ndarray,
    h: float,
    starts: np.ndarray,
    nbrs: np.ndarray,
    pair: np.ndarray,
    cond_max: float,
    out: np.ndarray,
    done: np.ndarray,
) -> None:
    """MLS fits in 2D of the first len(out) particles, 3 value column(s).

    Each particle's candidates within h are gathered in the list's order, then
    summed by :func:`_sums2`. Moments in the order of ``np.unique`` of the
    exponent sums (28); ``pair`` maps A_rc to them
    (:func:`geofrac.mpm.smoothing.moment_tables`).
    """
    m = 10
    h2 = h * h
    ih = 1.0 / h  # a product, not a division, per neighbour
    most = 0
    for p in range(out.shape[0]):
        most = max(most, starts[p + 1] - starts[p])
    s = np.zeros((3, most))
    v = np.zeros((3, most))
    mom = np.empty(28)
    B = np.empty((m, 3))
    for p in range(out.shape[0]):
        k = 0
        c0 = x[p, 0]
        c1 = x[p, 1]
        for t in range(starts[p], starts[p + 1]):
            q = nbrs[t]
            d0 = x[q, 0] - c0
            d1 = x[q, 1] - c1
            r2 = d0 * d0 + d1 * d1
            if not r2 < h2:
                continue
            s[0, k] = d0 * ih
            s[1, k] = d1 * ih
            s[2, k] = _spline(np.sqrt(r2) * ih)
            v[0, k] = values[q, 0]
            v[1, k] = values[q, 1]
            v[2, k] = values[q, 2]
            k += 1
        _sums2(s, v, k, mom, B)
        _finish2(p, k, mom, B, values, cond_max, out, done)


@_jit_sums
def _sums3(s: np.ndarray, v: np.ndarray, k: int, mom: np.ndarray, B: np.ndarray) -> None:
    """The moments and B v of k neighbours in 3D (the vectorised loop).

    Args:
        s: scaled offsets, then the weights W, shape=(dim + 1, ≥ k).
        v: values, shape=(6, ≥ k).
        k: neighbours.
        mom: out, the 84 moments Σ W x^e, shape=(84,).
        B: out, Σ W F_r v_c, shape=(20, 6).
    """
    m000 = 0.0
    m001 = 0.0
    m002 = 0.0
    m003 = 0.0
    m004 = 0.0
    m005 = 0.0
    m006 = 0.0
    m010 = 0.0
    m011 = 0.0
    m012 = 0.0
    m013 = 0.0
    m014 = 0.0
    m015 = 0.0
    m020 = 0.0
    m021 = 0.0
    m022 = 0.0
    m023 = 0.0
    m024 = 0.0
    m030 = 0.0
    m031 = 0.0
    m032 = 0.0
    m033 = 0.0
    m040 = 0.0
    m041 = 0.0
    m042 = 0.0
    m050 = 0.0
    m051 = 0.0
    m060 = 0.0
    m100 = 0.0
    m101 = 0.0
    m102 = 0.0
    m103 = 0.0
    m104 = 0.0
    m105 = 0.0
    m110 = 0.0
    m111 = 0.0
    m112 = 0.0
    m113 = 0.0
    m114 = 0.0
    m120 = 0.0
    m121 = 0.0
    m122 = 0.0
    m123 = 0.0
    m130 = 0.0
    m131 = 0.0
    m132 = 0.0
    m140 = 0.0
    m141 = 0.0
    m150 = 0.0
    m200 = 0.0
    m201 = 0.0
    m202 = 0.0
    m203 = 0.0
    m204 = 0.0
    m210 = 0.0
    m211 = 0.0
    m212 = 0.0
    m213 = 0.0
    m220 = 0.0
    m221 = 0.0
    m222 = 0.0
    m230 = 0.0
    m231 = 0.0
    m240 = 0.0
    m300 = 0.0
    m301 = 0.0
    m302 = 0.0
    m303 = 0.0
    m310 = 0.0
    m311 = 0.0
    m312 = 0.0
    m320 = 0.0
    m321 = 0.0
    m330 = 0.0
    m400 = 0.0
    m401 = 0.0
    m402 = 0.0
    m410 = 0.0
    m411 = 0.0
    m420 = 0.0
    m500 = 0.0
    m501 = 0.0
    m510 = 0.0
    m600 = 0.0
    b0_000 = 0.0
    b0_100 = 0.0
    b0_010 = 0.0
    b0_001 = 0.0
    b0_200 = 0.0
    b0_110 = 0.0
    b0_101 = 0.0
    b0_020 = 0.0
    b0_011 = 0.0
    b0_002 = 0.0
    b0_300 = 0.0
    b0_210 = 0.0
    b0_201 = 0.0
    b0_120 = 0.0
    b0_111 = 0.0
    b0_102 = 0.0
    b0_030 = 0.0
    b0_021 = 0.0
    b0_012 = 0.0
    b0_003 = 0.0
    b1_000 = 0.0
    b1_100 = 0.0
    b1_010 = 0.0
    b1_001 = 0.0
    b1_200 = 0.0
    b1_110 = 0.0
    b1_101 = 0.0
    b1_020 = 0.0
    b1_011 = 0.0
    b1_002 = 0.0
    b1_300 = 0.0
    b1_210 = 0.0
    b1_201 = 0.0
    b1_120 = 0.0
    b1_111 = 0.0
    b1_102 = 0.0
    b1_030 = 0.0
    b1_021 = 0.0
    b1_012 = 0.0
    b1_003 = 0.0
    b2_000 = 0.0
    b2_100 = 0.0
    b2_010 = 0.0
    b2_001 = 0.0
    b2_200 = 0.0
    b2_110 = 0.0
    b2_101 = 0.0
    b2_020 = 0.0
    b2_011 = 0.0
    b2_002 = 0.0
    b2_300 = 0.0
    b2_210 = 0.0
    b2_201 = 0.0
    b2_120 = 0.0
    b2_111 = 0.0
    b2_102 = 0.0
    b2_030 = 0.0
    b2_021 = 0.0
    b2_012 = 0.0
    b2_003 = 0.0
    b3_000 = 0.0
    b3_100 = 0.0
    b3_010 = 0.0
    b3_001 = 0.0
    b3_200 = 0.0
    b3_110 = 0.0
    b3_101 = 0.0
    b3_020 = 0.0
    b3_011 = 0.0
    b3_002 = 0.0
    b3_300 = 0.0
    b3_210 = 0.0
    b3_201 = 0.0
    b3_120 = 0.0
    b3_111 = 0.0
    b3_102 = 0.0
    b3_030 = 0.0
    b3_021 = 0.0
    b3_012 = 0.0
    b3_003 = 0.0
    b4_000 = 0.0
    b4_100 = 0.0
    b4_010 = 0.0
    b4_001 = 0.0
    b4_200 = 0.0
    b4_110 = 0.0
    b4_101 = 0.0
    b4_020 = 0.0
    b4_011 = 0.0
    b4_002 = 0.0
    b4_300 = 0.0
    b4_210 = 0.0
    b4_201 = 0.0
    b4_120 = 0.0
    b4_111 = 0.0
    b4_102 = 0.0
    b4_030 = 0.0
    b4_021 = 0.0
    b4_012 = 0.0
    b4_003 = 0.0
    b5_000 = 0.0
    b5_100 = 0.0
    b5_010 = 0.0
    b5_001 = 0.0
    b5_200 = 0.0
    b5_110 = 0.0
    b5_101 = 0.0
    b5_020 = 0.0
    b5_011 = 0.0
    b5_002 = 0.0
    b5_300 = 0.0
    b5_210 = 0.0
    b5_201 = 0.0
    b5_120 = 0.0
    b5_111 = 0.0
    b5_102 = 0.0
    b5_030 = 0.0
    b5_021 = 0.0
    b5_012 = 0.0
    b5_003 = 0.0
    for i in range(k):
        w = s[3, i]
        s0_1 = s[0, i]
        s0_2 = s0_1 * s0_1
        s0_3 = s0_2 * s0_1
        s0_4 = s0_3 * s0_1
        s0_5 = s0_4 * s0_1
        s0_6 = s0_5 * s0_1
        s1_1 = s[1, i]
        s1_2 = s1_1 * s1_1
        s1_3 = s1_2 * s1_1
        s1_4 = s1_3 * s1_1
        s1_5 = s1_4 * s1_1
        s1_6 = s1_5 * s1_1
        s2_1 = s[2, i]
        s2_2 = s2_1 * s2_1
        s2_3 = s2_2 * s2_1
        s2_4 = s2_3 * s2_1
        s2_5 = s2_4 * s2_1
        s2_6 = s2_5 * s2_1
        w01 = w * s1_1
        w02 = w * s1_2
        w03 = w * s1_3
        w04 = w * s1_4
        w05 = w * s1_5
        w06 = w * s1_6
        w10 = w * s0_1
        w11 = w10 * s1_1
        w12 = w10 * s1_2
        w13 = w10 * s1_3
        w14 = w10 * s1_4
        w15 = w10 * s1_5
        w20 = w * s0_2
        w21 = w20 * s1_1
        w22 = w20 * s1_2
        w23 = w20 * s1_3
        w24 = w20 * s1_4
        w30 = w * s0_3
        w31 = w30 * s1_1
        w32 = w30 * s1_2
        w33 = w30 * s1_3
        w40 = w * s0_4
        w41 = w40 * s1_1
        w42 = w40 * s1_2
        w50 = w * s0_5
        w51 = w50 * s1_1
        w60 = w * s0_6
        m000 += w
        m001 += w * s2_1
        m002 += w * s2_2
        m003 += w * s2_3
        m004 += w * s2_4
        m005 += w * s2_5
        m006 += w * s2_6
        m010 += w01
        m011 += w01 * s2_1
        m012 += w01 * s2_2
        m013 += w01 * s2_3
        m014 += w01 * s2_4
        m015 += w01 * s2_5
        m020 += w02
        m021 += w02 * s2_1
        m022 += w02 * s2_2
        m023 += w02 * s2_3
        m024 += w02 * s2_4
        m030 += w03
        m031 += w03 * s2_1
        m032 += w03 * s2_2
        m033 += w03 * s2_3
        m040 += w04
        m041 += w04 * s2_1
        m042 += w04 * s2_2
        m050 += w05
        m051 += w05 * s2_1
        m060 += w06
        m100 += w10
        m101 += w10 * s2_1
        m102 += w10 * s2_2
        m103 += w10 * s2_3
        m104 += w10 * s2_4
        m105 += w10 * s2_5
        m110 += w11
        m111 += w11 * s2_1
        m112 += w11 * s2_2
        m113 += w11 * s2_3
        m114 += w11 * s2_4
        m120 += w12
        m121 += w12 * s2_1
        m122 += w12 * s2_2
        m123 += w12 * s2_3
        m130 += w13
        m131 += w13 * s2_1
        m132 += w13 * s2_2
        m140 += w14
        m141 += w14 * s2_1
        m150 += w15
        m200 += w20
        m201 += w20 * s2_1
        m202 += w20 * s2_2
        m203 += w20 * s2_3
        m204 += w20 * s2_4
        m210 += w21
        m211 += w21 * s2_1
        m212 += w21 * s2_2
        m213 += w21 * s2_3
        m220 += w22
        m221 += w22 * s2_1
        m222 += w22 * s2_2
        m230 += w23
        m231 += w23 * s2_1
        m240 += w24
        m300 += w30
        m301 += w30 * s2_1
        m302 += w30 * s2_2
        m303 += w30 * s2_3
        m310 += w31
        m311 += w31 * s2_1
        m312 += w31 * s2_2
        m320 += w32
        m321 += w32 * s2_1
        m330 += w33
        m400 += w40
        m401 += w40 * s2_1
        m402 += w40 * s2_2
        m410 += w41
        m411 += w41 * s2_1
        m420 += w42
        m500 += w50
        m501 += w50 * s2_1
        m510 += w51
        m600 += w60
        v0 = v[0, i]
        u0_00 = w * v0
        u0_01 = w01 * v0
        u0_02 = w02 * v0
        u0_03 = w03 * v0
        u0_10 = w10 * v0
        u0_11 = w11 * v0
        u0_12 = w12 * v0
        u0_20 = w20 * v0
        u0_21 = w21 * v0
        u0_30 = w30 * v0
        b0_000 += u0_00
        b0_100 += u0_10
        b0_010 += u0_01
        b0_001 += u0_00 * s2_1
        b0_200 += u0_20
        b0_110 += u0_11
        b0_101 += u0_10 * s2_1
        b0_020 += u0_02
        b0_011 += u0_01 * s2_1
        b0_002 += u0_00 * s2_2
        b0_300 += u0_30
        b0_210 += u0_21
        b0_201 += u0_20 * s2_1
        b0_120 += u0_12
        b0_111 += u0_11 * s2_1
        b0_102 += u0_10 * s2_2
        b0_030 += u0_03
        b0_021 += u0_02 * s2_1
        b0_012 += u0_01 * s2_2
        b0_003 += u0_00 * s2_3
        v1 = v[1, i]
        u1_00 = w * v1
        u1_01 = w01 * v1
        u1_02 = w02 * v1
        u1_03 = w03 * v1
        u1_10 = w10 * v1
        u1_11 = w11 * v1
        u1_12 = w12 * v1
        u1_20 = w20 * v1
        u1_21 = w21 * v1
        u1_30 = w30 * v1
        b1_000 += u1_00
        b1_100 += u1_10
        b1_010 += u1_01
        b1_001 += u1_00 * s2_1
        b1_200 += u1_20
        b1_110 += u1_11
        b1_101 += u1_10 * s2_1
        b1_020 += u1_02
        b1_011 += u1_01 * s2_1
        b1_002 += u1_00 * s2_2
        b1_300 += u1_30
        b1_210 += u1_21
        b1_201 += u1_20 * s2_1
        b1_120 += u1_12
        b1_111 += u1_11 * s2_1
        b1_102 += u1_10 * s2_2
        b1_030 += u1_03
        b1_021 += u1_02 * s2_1
        b1_012 += u1_01 * s2_2
        b1_003 += u1_00 * s2_3
        v2 = v[2, i]
        u2_00 = w * v2
        u2_01 = w01 * v2
        u2_02 = w02 * v2
        u2_03 = w03 * v2
        u2_10 = w10 * v2
        u2_11 = w11 * v2
        u2_12 = w12 * v2
        u2_20 = w20 * v2
        u2_21 = w21 * v2
        u2_30 = w30 * v2
        b2_000 += u2_00
        b2_100 += u2_10
        b2_010 += u2_01
        b2_001 += u2_00 * s2_1
        b2_200 += u2_20
        b2_110 += u2_11
        b2_101 += u2_10 * s2_1
        b2_020 += u2_02
        b2_011 += u2_01 * s2_1
        b2_002 += u2_00 * s2_2
        b2_300 += u2_30
        b2_210 += u2_21
        b2_201 += u2_20 * s2_1
        b2_120 += u2_12
        b2_111 += u2_11 * s2_1
        b2_102 += u2_10 * s2_2
        b2_030 += u2_03
        b2_021 += u2_02 * s2_1
        b2_012 += u2_01 * s2_2
        b2_003 += u2_00 * s2_3
        v3 = v[3, i]
        u3_00 = w * v3
        u3_01 = w01 * v3
        u3_02 = w02 * v3
        u3_03 = w03 * v3
        u3_10 = w10 * v3
        u3_11 = w11 * v3
        u3_12 = w12 * v3
        u3_20 = w20 * v3
        u3_21 = w21 * v3
        u3_30 = w30 * v3
        b3_000 += u3_00
        b3_100 += u3_10
        b3_010 += u3_01
        b3_001 += u3_00 * s2_1
        b3_200 += u3_20
        b3_110 += u3_11
        b3_101 += u3_10 * s2_1
        b3_020 += u3_02
        b3_011 += u3_01 * s2_1
        b3_002 += u3_00 * s2_2
        b3_300 += u3_30
        b3_210 += u3_21
        b3_201 += u3_20 * s2_1
        b3_120 += u3_12
        b3_111 += u3_11 * s2_1
        b3_102 += u3_10 * s2_2
        b3_030 += u3_03
        b3_021 += u3_02 * s2_1
        b3_012 += u3_01 * s2_2
        b3_003 += u3_00 * s2_3
        v4 = v[4, i]
        u4_00 = w * v4
        u4_01 = w01 * v4
        u4_02 = w02 * v4
        u4_03 = w03 * v4
        u4_10 = w10 * v4
        u4_11 = w11 * v4
        u4_12 = w12 * v4
        u4_20 = w20 * v4
        u4_21 = w21 * v4
        u4_30 = w30 * v4
        b4_000 += u4_00
        b4_100 += u4_10
        b4_010 += u4_01
        b4_001 += u4_00 * s2_1
        b4_200 += u4_20
        b4_110 += u4_11
        b4_101 += u4_10 * s2_1
        b4_020 += u4_02
        b4_011 += u4_01 * s2_1
        b4_002 += u4_00 * s2_2
        b4_300 += u4_30
        b4_210 += u4_21
        b4_201 += u4_20 * s2_1
        b4_120 += u4_12
        b4_111 += u4_11 * s2_1
        b4_102 += u4_10 * s2_2
        b4_030 += u4_03
        b4_021 += u4_02 * s2_1
        b4_012 += u4_01 * s2_2
        b4_003 += u4_00 * s2_3
        v5 = v[5, i]
        u5_00 = w * v5
        u5_01 = w01 * v5
        u5_02 = w02 * v5
        u5_03 = w03 * v5
        u5_10 = w10 * v5
        u5_11 = w11 * v5
        u5_12 = w12 * v5
        u5_20 = w20 * v5
        u5_21 = w21 * v5
        u5_30 = w30 * v5
        b5_000 += u5_00
        b5_100 += u5_10
        b5_010 += u5_01
        b5_001 += u5_00 * s2_1
        b5_200 += u5_20
        b5_110 += u5_11
        b5_101 += u5_10 * s2_1
        b5_020 += u5_02
        b5_011 += u5_01 * s2_1
        b5_002 += u5_00 * s2_2
        b5_300 += u5_30
        b5_210 += u5_21
        b5_201 += u5_20 * s2_1
        b5_120 += u5_12
        b5_111 += u5_11 * s2_1
        b5_102 += u5_10 * s2_2
        b5_030 += u5_03
        b5_021 += u5_02 * s2_1
        b5_012 += u5_01 * s2_2
        b5_003 += u5_00 * s2_3
    mom[0] = m000
    mom[1] = m001
    mom[2] = m002
    mom[3] = m003
    mom[4] = m004
    mom[5] = m005
    mom[6] = m006
    mom[7] = m010
    mom[8] = m011
    mom[9] = m012
    mom[10] = m013
    mom[11] = m014
    mom[12] = m015
    mom[13] = m020
    mom[14] = m021
    mom[15] = m022
    mom[16] = m023
    mom[17] = m024
    mom[18] = m030
    mom[19] = m031
    mom[20] = m032
    mom[21] = m033
    mom[22] = m040
    mom[23] = m041
    mom[24] = m042
    mom[25] = m050
    mom[26] = m051
    mom[27] = m060
    mom[28] = m100
    mom[29] = m101
    mom[30] = m102
    mom[31] = m103
    mom[32] = m104
    mom[33] = m105
    mom[34] = m110
    mom[35] = m111
    mom[36] = m112
    mom[37] = m113
    mom[38] = m114
    mom[39] = m120
    mom[40] = m121
    mom[41] = m122
    mom[42] = m123
    mom[43] = m130
    mom[44] = m131
    mom[45] = m132
    mom[46] = m140
    mom[47] = m141
    mom[48] = m150
    mom[49] = m200
    mom[50] = m201
    mom[51] = m202
    mom[52] = m203
    mom[53] = m204
    mom[54] = m210
    mom[55] = m211
    mom[56] = m212
    mom[57] = m213
    mom[58] = m220
    mom[59] = m221
    mom[60] = m222
    mom[61] = m230
    mom[62] = m231
    mom[63] = m240
    mom[64] = m300
    mom[65] = m301
    mom[66] = m302
    mom[67] = m303
    mom[68] = m310
    mom[69] = m311
    mom[70] = m312
    mom[71] = m320
    mom[72] = m321
    mom[73] = m330
    mom[74] = m400
    mom[75] = m401
    mom[76] = m402
    mom[77] = m410
    mom[78] = m411
    mom[79] = m420
    mom[80] = m500
    mom[81] = m501
    mom[82] = m510
    mom[83] = m600
    B[0, 0] = b0_000
    B[1, 0] = b0_100
    B[2, 0] = b0_010
    B[3, 0] = b0_001
    B[4, 0] = b0_200
    B[5, 0] = b0_110
    B[6, 0] = b0_101
    B[7, 0] = b0_020
    B[8, 0] = b0_011
    B[9, 0] = b0_002
    B[10, 0] = b0_300
    B[11, 0] = b0_210
    B[12, 0] = b0_201
    B[13, 0] = b0_120
    B[14, 0] = b0_111
    B[15, 0] = b0_102
    B[16, 0] = b0_030
    B[17, 0] = b0_021
    B[18, 0] = b0_012
    B[19, 0] = b0_003
    B[0, 1] = b1_000
    B[1, 1] = b1_100
    B[2, 1] = b1_010
    B[3, 1] = b1_001
    B[4, 1] = b1_200
    B[5, 1] = b1_110
    B[6, 1] = b1_101
    B[7, 1] = b1_020
    B[8, 1] = b1_011
    B[9, 1] = b1_002
    B[10, 1] = b1_300
    B[11, 1] = b1_210
    B[12, 1] = b1_201
    B[13, 1] = b1_120
    B[14, 1] = b1_111
    B[15, 1] = b1_102
    B[16, 1] = b1_030
    B[17, 1] = b1_021
    B[18, 1] = b1_012
    B[19, 1] = b1_003
    B[0, 2] = b2_000
    B[1, 2] = b2_100
    B[2, 2] = b2_010
    B[3, 2] = b2_001
    B[4, 2] = b2_200
    B[5, 2] = b2_110
    B[6, 2] = b2_101
    B[7, 2] = b2_020
    B[8, 2] = b2_011
    B[9, 2] = b2_002
    B[10, 2] = b2_300
    B[11, 2] = b2_210
    B[12, 2] = b2_201
    B[13, 2] = b2_120
    B[14, 2] = b2_111
    B[15, 2] = b2_102
    B[16, 2] = b2_030
    B[17, 2] = b2_021
    B[18, 2] = b2_012
    B[19, 2] = b2_003
    B[0, 3] = b3_000
    B[1, 3] = b3_100
    B[2, 3] = b3_010
    B[3, 3] = b3_001
    B[4, 3] = b3_200
    B[5, 3] = b3_110
    B[6, 3] = b3_101
    B[7, 3] = b3_020
    B[8, 3] = b3_011
    B[9, 3] = b3_002
    B[10, 3] = b3_300
    B[11, 3] = b3_210
    B[12, 3] = b3_201
    B[13, 3] = b3_120
    B[14, 3] = b3_111
    B[15, 3] = b3_102
    B[16, 3] = b3_030
    B[17, 3] = b3_021
    B[18, 3] = b3_012
    B[19, 3] = b3_003
    B[0, 4] = b4_000
    B[1, 4] = b4_100
    B[2, 4] = b4_010
    B[3, 4] = b4_001
    B[4, 4] = b4_200
    B[5, 4] = b4_110
    B[6, 4] = b4_101
    B[7, 4] = b4_020
    B[8, 4] = b4_011
    B[9, 4] = b4_002
    B[10, 4] = b4_300
    B[11, 4] = b4_210
    B[12, 4] = b4_201
    B[13, 4] = b4_120
    B[14, 4] = b4_111
    B[15, 4] = b4_102
    B[16, 4] = b4_030
    B[17, 4] = b4_021
    B[18, 4] = b4_012
    B[19, 4] = b4_003
    B[0, 5] = b5_000
    B[1, 5] = b5_100
    B[2, 5] = b5_010
    B[3, 5] = b5_001
    B[4, 5] = b5_200
    B[5, 5] = b5_110
    B[6, 5] = b5_101
    B[7, 5] = b5_020
    B[8, 5] = b5_011
    B[9, 5] = b5_002
    B[10, 5] = b5_300
    B[11, 5] = b5_210
    B[12, 5] = b5_201
    B[13, 5] = b5_120
    B[14, 5] = b5_111
    B[15, 5] = b5_102
    B[16, 5] = b5_030
    B[17, 5] = b5_021
    B[18, 5] = b5_012
    B[19, 5] = b5_003


@_jit
def fit3(
    x: np.ndarray,
    values: np.ndarray,
    h: float,
    starts: np.ndarray,
    nbrs: np.ndarray,
    pair: np.ndarray,
    cond_max: float,
    out: np.ndarray,
    done: np.ndarray,
) -> None:
    """MLS fits in 3D of the first len(out) particles, 6 value column(s).

    Each particle's candidates within h are gathered in the list's order, then
    summed by :func:`_sums3`. Moments in the order of ``np.unique`` of the
    exponent sums (84); ``pair`` maps A_rc to them
    (:func:`geofrac.mpm.smoothing.moment_tables`).
    """
    m = 20
    h2 = h * h
    ih = 1.0 / h  # a product, not a division, per neighbour
    most = 0
    for p in range(out.shape[0]):
        most = max(most, starts[p + 1] - starts[p])
    s = np.zeros((4, most))
    v = np.zeros((6, most))
    mom = np.empty(84)
    B = np.empty((m, 6))
    work = np.empty(3 * m * (m + 1) // 2)
    for p in range(out.shape[0]):
        k = 0
        c0 = x[p, 0]
        c1 = x[p, 1]
        c2 = x[p, 2]
        for t in range(starts[p], starts[p + 1]):
            q = nbrs[t]
            d0 = x[q, 0] - c0
            d1 = x[q, 1] - c1
            d2 = x[q, 2] - c2
            r2 = d0 * d0 + d1 * d1 + d2 * d2
            if not r2 < h2:
                continue
            s[0, k] = d0 * ih
            s[1, k] = d1 * ih
            s[2, k] = d2 * ih
            s[3, k] = _spline(np.sqrt(r2) * ih)
            v[0, k] = values[q, 0]
            v[1, k] = values[q, 1]
            v[2, k] = values[q, 2]
            v[3, k] = values[q, 3]
            v[4, k] = values[q, 4]
            v[5, k] = values[q, 5]
            k += 1
        _sums3(s, v, k, mom, B)
        finish(p, k, mom, pair, B, values, cond_max, work, out, done)
