"""Statistics for checking fracture networks: KS tests, quantiles, axial data, intervals.

Pure numpy and the standard library (no scipy): used by the tests of the sampler and
reported by the benchmark, so the formulas and their accuracy are documented here.

Axial data: a fracture at angle θ is the same as one at θ + 180°, so orientations are
folded to [0, 180) and their mean is taken on the circle of doubled angles
(:func:`axial_mean_deg`); spreads are measured by deviations folded to [-90, 90)
(:func:`axial_deviation_deg`).
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
from numpy.typing import ArrayLike

from geofrac.dfn.errors import DfnError

__all__ = [
    "axial_deviation_deg",
    "axial_mean_deg",
    "chi2_cdf",
    "chi2_quantile",
    "fold_axial_deg",
    "ks_pvalue",
    "ks_statistic",
    "mean_ci",
    "normal_quantile",
    "orientation_summary",
    "t_quantile",
    "variance_ci",
]


def _samples(samples: ArrayLike, minimum: int, what: str) -> np.ndarray:
    """Finite 1-D float samples, shape=(n,), with at least ``minimum`` entries."""
    x = np.asarray(samples, dtype=float).ravel()
    if len(x) < minimum:
        raise DfnError(f"{what}: needs at least {minimum} samples, got {len(x)}")
    if not np.all(np.isfinite(x)):
        raise DfnError(f"{what}: samples must be finite")
    return x


def _probability(p: float, what: str) -> float:
    p = float(p)
    if not 0.0 < p < 1.0:
        raise DfnError(f"{what}: probability must be in (0, 1), got {p}")
    return p


def _level(level: float, what: str) -> float:
    level = float(level)
    if not 0.0 < level < 1.0:
        raise DfnError(f"{what}: confidence level must be in (0, 1), got {level}")
    return level


# ----------------------------------------------------------------- Kolmogorov–Smirnov


def ks_statistic(samples: ArrayLike, cdf: Callable[[np.ndarray], np.ndarray]) -> float:
    """One-sample Kolmogorov–Smirnov statistic D = sup |F_n(x) − F(x)|.

    Args:
        samples: observations, shape=(n,), n >= 1.
        cdf: the hypothesised CDF, vectorised: shape=(n,) -> shape=(n,).

    Returns:
        D in [0, 1].
    """
    x = np.sort(_samples(samples, 1, "ks_statistic"))
    n = len(x)
    f = np.asarray(cdf(x), dtype=float)
    if f.shape != x.shape:
        raise DfnError(f"ks_statistic: cdf returned shape {f.shape} for input {x.shape}")
    i = np.arange(1, n + 1)
    return float(max(np.max(i / n - f), np.max(f - (i - 1) / n)))


def ks_pvalue(d: float, n: int) -> float:
    """Asymptotic p-value P(D > d) of the one-sample KS statistic of n observations.

    Uses the Kolmogorov distribution at λ = (√n + 0.12 + 0.11/√n)·d (Stephens'
    correction), Q(λ) = 2 Σ_{k≥1} (−1)^{k−1} exp(−2k²λ²). For λ < 1.18, where that series
    converges slowly, the equivalent Jacobi form Q = 1 − √(2π)/λ Σ_{k≥1}
    exp(−(2k−1)²π²/(8λ²)) is summed instead. Accurate to about 1e-3 in p for n >= 35
    (the correction's accuracy), to machine precision in Q(λ) itself.

    Args:
        d: the statistic, >= 0.
        n: number of observations, >= 1.

    Returns:
        p in [0, 1], decreasing in d.
    """
    if n < 1:
        raise DfnError(f"ks_pvalue: n must be >= 1, got {n}")
    if not (d >= 0.0 and math.isfinite(d)):
        raise DfnError(f"ks_pvalue: d must be finite and >= 0, got {d}")
    sn = math.sqrt(n)
    lam = (sn + 0.12 + 0.11 / sn) * d
    if lam <= 0.0:
        return 1.0
    if lam < 1.18:
        s = sum(
            math.exp(-((2 * k - 1) ** 2) * math.pi**2 / (8.0 * lam * lam)) for k in range(1, 20)
        )
        q = 1.0 - math.sqrt(2.0 * math.pi) / lam * s
    else:
        q = 2.0 * sum((-1) ** (k - 1) * math.exp(-2.0 * k * k * lam * lam) for k in range(1, 101))
    return min(1.0, max(0.0, q))


# ----------------------------------------------------------------------------- quantiles

# Acklam's rational approximation of the normal quantile (relative error < 1.15e-9),
# refined below by one Halley step on math.erfc to about machine precision.
_A = (
    -3.969683028665376e01,
    2.209460984245205e02,
    -2.759285104469687e02,
    1.383577518672690e02,
    -3.066479806614716e01,
    2.506628277459239e00,
)
_B = (
    -5.447609879822406e01,
    1.615858368580409e02,
    -1.556989798598866e02,
    6.680131188771972e01,
    -1.328068155288572e01,
)
_C = (
    -7.784894002430293e-03,
    -3.223964580411365e-01,
    -2.400758277161838e00,
    -2.549732539343734e00,
    4.374664141464968e00,
    2.938163982698783e00,
)
_D = (
    7.784695709041462e-03,
    3.224671290700398e-01,
    2.445134137142996e00,
    3.754408661907416e00,
)


def _lower_normal_quantile(q: float) -> float:
    """Normal quantile for 0 < q <= 0.5 (a non-positive value)."""
    if q < 0.02425:
        r = math.sqrt(-2.0 * math.log(q))
        c, d = _C, _D
        x = (((((c[0] * r + c[1]) * r + c[2]) * r + c[3]) * r + c[4]) * r + c[5]) / (
            (((d[0] * r + d[1]) * r + d[2]) * r + d[3]) * r + 1.0
        )
    else:
        r = q - 0.5
        s = r * r
        a, b = _A, _B
        x = (
            (((((a[0] * s + a[1]) * s + a[2]) * s + a[3]) * s + a[4]) * s + a[5])
            * r
            / (((((b[0] * s + b[1]) * s + b[2]) * s + b[3]) * s + b[4]) * s + 1.0)
        )
    e = 0.5 * math.erfc(-x / math.sqrt(2.0)) - q
    u = e * math.sqrt(2.0 * math.pi) * math.exp(0.5 * x * x)
    return x - u / (1.0 + 0.5 * x * u)


def normal_quantile(p: float) -> float:
    """Quantile of the standard normal distribution.

    Acklam's rational approximation refined by one Halley step (with ``math.erfc``);
    absolute error below 1e-12 for p in [1e-300, 1 − 1e-16]. The upper half is computed
    as −quantile(1 − p), so small tail probabilities keep their relative precision.

    Args:
        p: probability in (0, 1).
    """
    p = _probability(p, "normal_quantile")
    if p <= 0.5:
        return _lower_normal_quantile(p)
    return -_lower_normal_quantile(1.0 - p)


def _gamma_pq(a: float, x: float) -> tuple[float, float]:
    """Regularised incomplete gamma functions (P(a, x), Q(a, x)), a > 0, x >= 0.

    Series for x < a + 1, Lentz's continued fraction otherwise (Numerical Recipes 6.2);
    the smaller of P and Q is computed directly, so each keeps its relative precision.
    """
    if x <= 0.0:
        return 0.0, 1.0
    log_front = -x + a * math.log(x) - math.lgamma(a)
    if x < a + 1.0:
        term = total = 1.0 / a
        ap = a
        for _ in range(100_000):
            ap += 1.0
            term *= x / ap
            total += term
            if abs(term) < abs(total) * 1e-17:
                break
        p = total * math.exp(log_front)
        return p, 1.0 - p
    tiny = 1e-300
    b = x + 1.0 - a
    c = 1.0 / tiny
    d = 1.0 / b
    h = d
    for i in range(1, 100_000):
        an = -i * (i - a)
        b += 2.0
        d = an * d + b
        d = tiny if abs(d) < tiny else d
        c = b + an / c
        c = tiny if abs(c) < tiny else c
        d = 1.0 / d
        delta = d * c
        h *= delta
        if abs(delta - 1.0) < 1e-16:
            break
    q = math.exp(log_front) * h
    return 1.0 - q, q


def chi2_cdf(x: float, dof: float) -> float:
    """CDF of the chi-square distribution, P(dof/2, x/2), to about 1e-14.

    Args:
        x: argument (values <= 0 give 0).
        dof: degrees of freedom, > 0.
    """
    if not dof > 0.0:
        raise DfnError(f"chi2_cdf: dof must be > 0, got {dof}")
    return _gamma_pq(0.5 * dof, 0.5 * max(float(x), 0.0))[0]


def _solve_increasing(
    residual: Callable[[float], float],
    slope: Callable[[float], float],
    x: float,
    lo: float,
    hi: float,
) -> float:
    """Root of an increasing function bracketed by [lo, hi]: Newton, bisecting when unsafe.

    Args:
        residual: increasing function, residual(lo) <= 0 <= residual(hi).
        slope: its derivative (>= 0).
        x: starting value.
        lo: lower end of the bracket.
        hi: upper end of the bracket.

    Returns:
        The root to a relative accuracy of about 1e-14.
    """
    if not lo < x < hi:
        x = 0.5 * (lo + hi)
    for _ in range(400):
        f = residual(x)
        if f == 0.0:
            return x
        if f < 0.0:
            lo = x
        else:
            hi = x
        g = slope(x)
        x_new = x - f / g if g > 0.0 else math.nan
        if not lo < x_new < hi:
            x_new = 0.5 * (lo + hi)
        if abs(x_new - x) <= 1e-14 * abs(x) or hi - lo <= 1e-15 * abs(hi):
            return x_new
        x = x_new
    return x


def chi2_quantile(p: float, dof: float) -> float:
    """Quantile of the chi-square distribution with ``dof`` degrees of freedom.

    The Wilson–Hilferty approximation dof·(1 − 2/(9 dof) + z √(2/(9 dof)))³ (relative
    error below about 1e-3 for dof >= 100 at 0.5 % <= p <= 99.5 %) is only the start of a
    safeguarded Newton iteration on :func:`chi2_cdf` (bisection whenever a step leaves the
    bracket), which converges to a relative accuracy of about 1e-12 for any dof > 0.

    Args:
        p: probability in (0, 1).
        dof: degrees of freedom, > 0.
    """
    p = _probability(p, "chi2_quantile")
    dof = float(dof)
    if not (dof > 0.0 and math.isfinite(dof)):
        raise DfnError(f"chi2_quantile: dof must be finite and > 0, got {dof}")
    a = 0.5 * dof
    upper = p > 0.5  # solve Q = 1 - p in the upper half, P = p in the lower half
    target = 1.0 - p if upper else p

    def residual(x: float) -> float:
        pp, qq = _gamma_pq(a, 0.5 * x)
        return (target - qq) if upper else (pp - target)

    def density(x: float) -> float:
        if x <= 0.0:
            return 0.0
        return math.exp((a - 1.0) * math.log(x) - 0.5 * x - a * math.log(2.0) - math.lgamma(a))

    h = 2.0 / (9.0 * dof)
    x0 = dof * (1.0 - h + normal_quantile(p) * math.sqrt(h)) ** 3
    lo, hi = 0.0, max(2.0 * dof, 1.0)
    while residual(hi) < 0.0:
        lo, hi = hi, 2.0 * hi
    return _solve_increasing(residual, density, x0, lo, hi)


def _beta_cf(a: float, b: float, x: float) -> float:
    """Continued fraction of the incomplete beta function (Numerical Recipes 6.4)."""
    tiny = 1e-300
    c = 1.0
    d = 1.0 - (a + b) * x / (a + 1.0)
    d = 1.0 / (tiny if abs(d) < tiny else d)
    h = d
    for m in range(1, 100_000):
        m2 = 2 * m
        for aa in (
            m * (b - m) * x / ((a - 1.0 + m2) * (a + m2)),
            -(a + m) * (a + b + m) * x / ((a + m2) * (a + 1.0 + m2)),
        ):
            d = 1.0 + aa * d
            d = 1.0 / (tiny if abs(d) < tiny else d)
            c = 1.0 + aa / c
            c = tiny if abs(c) < tiny else c
            h *= d * c
        if abs(d * c - 1.0) < 1e-16:
            break
    return h


def _beta_inc(a: float, b: float, x: float, y: float) -> float:
    """Regularised incomplete beta I_x(a, b), with y = 1 − x given separately."""
    if x <= 0.0:
        return 0.0
    if y <= 0.0:
        return 1.0
    front = math.exp(
        math.lgamma(a + b) - math.lgamma(a) - math.lgamma(b) + a * math.log(x) + b * math.log(y)
    )
    if x < (a + 1.0) / (a + b + 2.0):
        return front * _beta_cf(a, b, x) / a
    return 1.0 - front * _beta_cf(b, a, y) / b


def t_quantile(p: float, dof: float) -> float:
    """Quantile of Student's t distribution with ``dof`` degrees of freedom.

    Starts from the Cornish–Fisher expansion of Abramowitz & Stegun 26.7.5 (fourth order
    in 1/dof) and refines it by a safeguarded Newton iteration on the exact tail
    probability ½·I_{dof/(dof+t²)}(dof/2, 1/2) (regularised incomplete beta by its
    continued fraction), to a relative accuracy of about 1e-12 for any dof > 0.

    Args:
        p: probability in (0, 1).
        dof: degrees of freedom, > 0.
    """
    p = _probability(p, "t_quantile")
    dof = float(dof)
    if not (dof > 0.0 and math.isfinite(dof)):
        raise DfnError(f"t_quantile: dof must be finite and > 0, got {dof}")
    if p == 0.5:
        return 0.0
    q = min(p, 1.0 - p)  # solve P(T > t) = q for t > 0, then restore the sign
    z = -normal_quantile(q)
    z2 = z * z
    g1 = (z2 + 1.0) * z / 4.0
    g2 = ((5.0 * z2 + 16.0) * z2 + 3.0) * z / 96.0
    g3 = (((3.0 * z2 + 19.0) * z2 + 17.0) * z2 - 15.0) * z / 384.0
    g4 = ((((79.0 * z2 + 776.0) * z2 + 1482.0) * z2 - 1920.0) * z2 - 945.0) * z / 92160.0
    v = 1.0 / dof
    t0 = z + v * (g1 + v * (g2 + v * (g3 + v * g4)))
    log_norm = (
        math.lgamma(0.5 * (dof + 1.0)) - math.lgamma(0.5 * dof) - 0.5 * math.log(dof * math.pi)
    )

    def residual(t: float) -> float:  # q − P(T > t), increasing in t
        return q - 0.5 * _beta_inc(0.5 * dof, 0.5, dof / (dof + t * t), t * t / (dof + t * t))

    def density(t: float) -> float:
        return math.exp(log_norm - 0.5 * (dof + 1.0) * math.log1p(t * t / dof))

    hi = max(2.0 * z, 1.0)
    while residual(hi) < 0.0:
        hi *= 2.0
    t = _solve_increasing(residual, density, t0, 0.0, hi)
    return t if p > 0.5 else -t


# ---------------------------------------------------------------------------- axial data


def fold_axial_deg(angles_deg: ArrayLike) -> np.ndarray:
    """Fold axial angles to [0, 180) degrees (180 itself and round-off to 180 become 0).

    Args:
        angles_deg: angles in degrees, any shape.

    Returns:
        Folded angles, same shape.
    """
    a = np.mod(np.asarray(angles_deg, dtype=float), 180.0)
    return np.where(a >= 180.0, 0.0, a)


def axial_deviation_deg(angles_deg: ArrayLike, centre_deg: float) -> np.ndarray:
    """Signed difference between axial angles and a centre, folded to [-90, 90).

    Args:
        angles_deg: angles in degrees, any shape.
        centre_deg: reference angle in degrees.

    Returns:
        ``angle − centre`` modulo 180, in [-90, 90), same shape as ``angles_deg``.
    """
    return fold_axial_deg(np.asarray(angles_deg, dtype=float) - float(centre_deg) + 90.0) - 90.0


def _doubled_resultant(angles_deg: np.ndarray) -> tuple[float, float]:
    """Mean of exp(2iθ): (length R in [0, 1], direction 2θ̄ in radians)."""
    two = np.deg2rad(2.0 * angles_deg)
    c, s = float(np.mean(np.cos(two))), float(np.mean(np.sin(two)))
    return math.hypot(c, s), math.atan2(s, c)


def axial_mean_deg(angles_deg: ArrayLike) -> float:
    """Mean direction of axial data: half the circular mean of the doubled angles.

    Args:
        angles_deg: angles in degrees, shape=(n,).

    Returns:
        Mean angle in [0, 180).

    Raises:
        DfnError: no samples, or the doubled angles have no mean direction (resultant
            length below 1e-12, e.g. two perpendicular fractures).
    """
    x = _samples(angles_deg, 1, "axial_mean_deg")
    r, direction = _doubled_resultant(x)
    if r < 1e-12:
        raise DfnError("axial_mean_deg: the angles have no mean direction (zero resultant)")
    return float(fold_axial_deg(math.degrees(direction) / 2.0))


def orientation_summary(angles_deg: ArrayLike) -> dict[str, float | int]:
    """Axial mean, spread and count of fracture orientations.

    Args:
        angles_deg: angles in degrees, shape=(n,), n >= 2.

    Returns:
        ``{"mean": axial mean in [0, 180), "std": sample standard deviation (ddof=1) of
        the deviations about that mean, "n": n, "resultant": mean resultant length of the
        doubled angles}``.
    """
    x = _samples(angles_deg, 2, "orientation_summary")
    mean = axial_mean_deg(x)
    dev = axial_deviation_deg(x, mean)
    return {
        "mean": mean,
        "std": float(np.std(dev, ddof=1)),
        "n": len(x),
        "resultant": _doubled_resultant(x)[0],
    }


# ---------------------------------------------------------------------------- intervals


def mean_ci(samples: ArrayLike, level: float = 0.99) -> tuple[float, float]:
    """Two-sided confidence interval of the mean: x̄ ± t_{(1+level)/2, n−1} s/√n.

    Args:
        samples: observations, shape=(n,), n >= 2.
        level: confidence level in (0, 1).

    Returns:
        (low, high).
    """
    x = _samples(samples, 2, "mean_ci")
    level = _level(level, "mean_ci")
    n = len(x)
    half = t_quantile(0.5 * (1.0 + level), n - 1) * float(np.std(x, ddof=1)) / math.sqrt(n)
    m = float(np.mean(x))
    return m - half, m + half


def variance_ci(samples: ArrayLike, level: float = 0.99) -> tuple[float, float]:
    """Two-sided chi-square confidence interval of the variance of a normal sample.

    ``[(n−1)s²/χ²_{(1+level)/2}, (n−1)s²/χ²_{(1−level)/2}]`` with n − 1 degrees of freedom.

    Args:
        samples: observations, shape=(n,), n >= 2.
        level: confidence level in (0, 1).

    Returns:
        (low, high).
    """
    x = _samples(samples, 2, "variance_ci")
    level = _level(level, "variance_ci")
    dof = len(x) - 1
    ss = dof * float(np.var(x, ddof=1))
    alpha = 1.0 - level
    return ss / chi2_quantile(1.0 - 0.5 * alpha, dof), ss / chi2_quantile(0.5 * alpha, dof)
