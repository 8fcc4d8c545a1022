"""Critical load factors under a constant load plus a scaled one (pure numpy).

Sequentially linear analysis under non-proportional loading (DeJong, Hendriks and Rots
(2008), Eng. Fract. Mech. 75): the stress at a crack site is σ = σ_c + λ σ_v, σ_c of
the constant load and σ_v of the variable load at unit factor, both solved on the
current crack state. The event's factor is the least λ ≥ 0 at which a site reaches
its strength. Each function below returns, per site,

- λ: that factor (``inf`` where the variable load never brings the site to its
  strength, 0 where the constant load alone already does: the site is *overstressed*);
- the *overstress ratio* f(σ_c)/strength, ≥ 1 exactly where λ = 0 (sites over their
  strength under the constant load crack first, largest ratio first).

The tension functions also return the *equivalent drive* f_t/λ, the σ1 a proportional
run would need to crack the site at λ, so that the event criteria, which take a drive
per site (r = f_t/drive), choose among the sites unchanged. Where σ_c is zero it is
exactly the proportional drive, so a run whose constant load is zero repeats the
proportional run's arithmetic.

A drive whose asymptotic slope (the variable stress's own drive, the proportional drive
of σ_v) does not exceed ``floor`` gives λ = inf: a drive at round-off is no drive
(docs/cracking.md, "Decisions and their scales").
"""

from __future__ import annotations

import numpy as np

__all__ = [
    "NEWTON_STEPS",
    "principal_factors",
    "shear_factors_affine",
    "traction_factors",
]

#: Most Newton steps of :func:`principal_factors` (it converges quadratically; steps
#: stop when λ changes by less than 4 ulp).
NEWTON_STEPS = 60


def _centre_radius(s: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(p, q, τ) of (σ_xx, σ_yy, σ_xy), shape=(..., 3): σ1 = p + hypot(q, τ)."""
    return 0.5 * (s[..., 0] + s[..., 1]), 0.5 * (s[..., 0] - s[..., 1]), s[..., 2]


def principal_factors(
    sc: np.ndarray,
    sv: np.ndarray,
    weights: np.ndarray,
    *,
    tensile_strength: float,
    floor: float = 0.0,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Least λ ≥ 0 at which the weighted mean of σ1 over each site's cells reaches f_t.

    f(λ) = Σ_j w_j σ1(σ_c,j + λ σ_v,j) − f_t is convex in λ (σ1 is the largest
    eigenvalue, convex, of a stress affine in λ), so with f(0) < 0 it has at most one
    root and it exists iff its asymptotic slope D_v = Σ_j w_j σ1(σ_v,j) (the
    proportional drive of σ_v) is positive. Since hypot(a + λb) ≥ λ|b| − |a|, the
    root lies below λ_hi = (f_t − Σ_j w_j σ2(σ_c,j)) / D_v (σ2 the smaller principal
    stress), with equality when every σ_c,j is isotropic (a zero constant stress
    included): then λ_hi is the root, in closed form. Otherwise Newton's method from
    λ_hi, which on a convex function approaches the root from above, monotonically.

    Args:
        sc: constant stress (σ_xx, σ_yy, σ_xy) of each site's cells, shape=(k, m, 3).
        sv: variable stress at λ = 1, shape=(k, m, 3).
        weights: each cell's weight in its site's mean (each row sums to 1; a padding
            cell has weight 0), shape=(k, m).
        tensile_strength: f_t > 0.
        floor: D_v must exceed it (≥ 0).

    Returns:
        (λ, equivalent drive f_t/λ, overstress ratio Σ_j w_j σ1(σ_c,j)/f_t), each
        shape=(k,). The drive is 0 where λ = inf and inf where λ = 0.
    """
    ft = float(tensile_strength)
    pc, qc, tc = _centre_radius(sc)
    pv, qv, tv = _centre_radius(sv)
    rc = np.hypot(qc, tc)
    d_v = np.sum(weights * (pv + np.hypot(qv, tv)), axis=1)
    ratio = np.sum(weights * (pc + rc), axis=1) / ft
    lam = np.full(len(sc), np.inf)
    drive = np.zeros(len(sc))
    over = ratio >= 1.0
    lam[over], drive[over] = 0.0, np.inf
    go = ~over & (d_v > max(floor, 0.0))
    gap = ft - np.sum(weights * (pc - rc), axis=1)  # f_t − Σ w σ2(σ_c) ≥ f_t − Σ w σ1 > 0
    lam[go] = gap[go] / d_v[go]
    drive[go] = d_v[go] / (gap[go] / ft)  # exactly D_v where σ_c = 0 (gap = f_t)
    exact = np.all((rc == 0.0) | (weights == 0.0), axis=1)
    newton = np.flatnonzero(go & ~exact)
    x = lam[newton]
    w = weights[newton]
    a, b = (pc[newton], qc[newton], tc[newton]), (pv[newton], qv[newton], tv[newton])
    live = np.ones(len(newton), dtype=bool)
    for _ in range(NEWTON_STEPS):
        if not live.any():
            break
        xl = x[live][:, None]
        q = a[1][live] + xl * b[1][live]
        t = a[2][live] + xl * b[2][live]
        r = np.hypot(q, t)
        f = np.sum(w[live] * (a[0][live] + xl * b[0][live] + r), axis=1) - ft
        slope_r = np.divide(q * b[1][live] + t * b[2][live], r, out=np.zeros_like(r), where=r > 0)
        g = np.sum(w[live] * (b[0][live] + slope_r), axis=1)  # a subgradient, > 0 here
        step = np.where(f > 0.0, f / g, 0.0)
        x_new = x[live] - step
        idx = np.flatnonzero(live)
        x[idx] = x_new
        live[idx] = step > 4.0 * np.finfo(float).eps * np.abs(x_new)
    lam[newton] = x
    drive[newton] = ft / x
    return lam, drive, ratio


def traction_factors(
    tn_c: np.ndarray, tn_v: np.ndarray, tensile_strength: float, *, floor: float = 0.0
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Least λ ≥ 0 at which the normal traction t_c + λ t_v reaches f_t (linear).

    Args:
        tn_c: constant normal traction n·σ_c·n per site, shape=(k,).
        tn_v: variable normal traction at λ = 1, shape=(k,).
        tensile_strength: f_t > 0.
        floor: t_v must exceed it (≥ 0).

    Returns:
        (λ, equivalent drive f_t/λ, overstress ratio t_c/f_t), each shape=(k,).
    """
    ft = float(tensile_strength)
    ratio = tn_c / ft
    lam = np.full(len(tn_c), np.inf)
    drive = np.zeros(len(tn_c))
    over = ratio >= 1.0
    lam[over], drive[over] = 0.0, np.inf
    go = ~over & (tn_v > max(floor, 0.0))
    gap = ft - tn_c[go]
    lam[go] = gap / tn_v[go]
    drive[go] = tn_v[go] / (gap / ft)  # exactly t_v where t_c = 0
    return lam, drive, ratio


def shear_factors_affine(
    sn: tuple[np.ndarray, np.ndarray],
    tau: tuple[np.ndarray, np.ndarray],
    cohesion: float,
    *,
    friction_angle: float,
    floor: float = 0.0,
) -> tuple[np.ndarray, np.ndarray]:
    """Least λ ≥ 0 of Mohr-Coulomb failure |τ_c + λ τ_v| + (σ_c + λ σ_v) tan φ = c.

    g(λ) = |τ| + σn tan φ − c is the larger of two lines ±τ + σn tan φ − c, so its
    least root with g(0) < 0 is the least root of the lines of positive slope. With
    σ_c = τ_c = 0 this is c / (|τ_v| + σ_v tan φ), the proportional factor
    (:func:`~geofrac.fracture.contact.shear_factors`).

    Args:
        sn: (constant, variable) normal tractions (tension > 0), each shape=(k,).
        tau: (constant, variable) shear tractions, each shape=(k,).
        cohesion: c > 0.
        friction_angle: φ in degrees.
        floor: the variable drive |τ_v| + σ_v tan φ must exceed it (≥ 0).

    Returns:
        (λ, overstress ratio (|τ_c| + σ_c tan φ)/c), each shape=(k,).
    """
    mu = np.tan(np.radians(friction_angle))
    (sn_c, sn_v), (tau_c, tau_v) = sn, tau
    ratio = (np.abs(tau_c) + sn_c * mu) / cohesion
    lam = np.full(len(tau_c), np.inf)
    over = ratio >= 1.0
    lam[over] = 0.0
    go = ~over & (np.abs(tau_v) + sn_v * mu > max(floor, 0.0))
    for sign in (1.0, -1.0):
        slope = sign * tau_v + sn_v * mu
        up = go & (slope > 0.0)
        root = (cohesion - (sign * tau_c[up] + sn_c[up] * mu)) / slope[up]
        lam[up] = np.minimum(lam[up], root)
    return lam, ratio
