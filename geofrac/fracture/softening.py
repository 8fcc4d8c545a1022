"""Energy-matched saw-tooth softening of cohesive crack faces (pure numpy).

A cracked edge's faces stay joined by springs (per unit area) of stiffness k_i, normal
and tangential, which drop tooth by tooth: the sequentially linear saw-tooth of Rots and
co-workers (Rots & Invernizzi (2004); Rots, Belletti & Invernizzi (2008), Eng. Fract.
Mech. 75, "ripple band"), here on the traction t and opening w of a discrete crack rather
than on a smeared stress-strain law. The envelope is linear softening,

    σ(w) = f_t (1 − (w − w₀)/(w_c − w₀))  for w₀ ≤ w ≤ w_c,

after the first tooth's elastic branch t = k₀ w up to f_t at w₀ = f_t/k₀, with
w_c = 2 G_f / f_t so that the law's whole area ½ f_t w_c is the fracture energy G_f.

Tooth i (i = 1..N) is a secant line t = k_i w through the origin and ends at its peak
(w_i, f_i = k_i w_i); the event that reaches it drops the traction at w_i to k_{i+1} w_i
(k_{N+1} = 0: the faces are then traction-free) and dissipates the area between the two
secants, ½ w_i² (k_i − k_{i+1}) per unit area. Construction (:func:`saw_tooth`):

- tooth 1: k_1 = k₀ (the edge's regularised initial stiffness), peak (w₀, f_t);
- a *stretched* envelope σ̃(w) = f_t (1 − (w − w₀)/s) (s ≥ w_c − w₀) and a band p f_t
  below it: each valley lies on the lower line, k_{i+1} w_i = σ̃(w_i) − p f_t, and the
  next peak where that secant meets σ̃ (so f_i ≤ f_t: no tooth is stronger than the
  intact edge);
- p is such that the N-th valley is zero exactly (N teeth end on the lower line);
- s (the stretch) is such that the teeth dissipate G_f exactly:
  Σ ½ w_i² (k_i − k_{i+1}) = G_f. Rots et al.'s ripple band lays the teeth between
  σ ± p f_t and chooses p for the energy; with N given here the band is fixed by N and
  the envelope is stretched instead (an adaptation, not their exact construction).

Both are found with Brent's method to round-off. The stretched envelope lies above σ
(the saw-tooth below σ̃ encloses G_f), so the teeth straddle σ: peaks above, valleys
below, all within p f_t of it. The secants through the origin make early teeth
geometric in w (valleys at (1 − p) of the peaks), so p falls slowly with N: about
0.4-0.57 for N = 10 and 0.11-0.18 for N = 40 at w_c/w₀ = 100-2000. The dissipated
energy is G_f for every N; the load-displacement curve's ripple scales with p.

A saw-tooth exists only for G_f > ½ f_t w₀ (the first tooth's elastic energy):
k₀ > f_t² / (2 G_f).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.optimize import brentq

__all__ = ["MIN_TEETH", "SawTooth", "dissipation", "saw_tooth"]

#: Fewest teeth: one tooth drops from f_t to nothing at w₀ and dissipates ½ f_t w₀.
MIN_TEETH = 2
#: Root-finding tolerances of s and p (relative; brentq's smallest).
_TOL = {"xtol": 1e-300, "rtol": 1e-15}


@dataclass(frozen=True)
class SawTooth:
    """The teeth of m crack faces.

    Attributes:
        k: secant stiffness of each tooth per unit area, shape=(m, N).
        f: peak traction of each tooth, shape=(m, N).
        w: peak opening f / k of each tooth, shape=(m, N).
        p: ripple band half-width / f_t, shape=(m,).
        s: stretched softening length, shape=(m,).
    """

    k: np.ndarray
    f: np.ndarray
    w: np.ndarray
    p: np.ndarray
    s: np.ndarray

    @property
    def energy(self) -> np.ndarray:
        """Energy per unit area dissipated by each tooth's drop, shape=(m, N)."""
        return dissipation(self.k, self.w)


def dissipation(k: np.ndarray, w: np.ndarray) -> np.ndarray:
    """½ w_i² (k_i − k_{i+1}) per tooth with k_{N+1} = 0, shape=(m, N).

    Args:
        k: secant stiffnesses, shape=(m, N).
        w: peak openings, shape=(m, N).
    """
    k_next = np.concatenate([k[:, 1:], np.zeros((len(k), 1))], axis=1)
    return 0.5 * w * w * (k - k_next)


def _teeth(
    k0: float, s: float, p: float, ft: float, n: int
) -> tuple[np.ndarray, np.ndarray, float]:
    """(k, w, last valley / f_t) of the band construction, shapes (N,), (N,).

    A valley that reaches zero before tooth N gives the last valley −1 (p too large).
    """
    w0 = ft / k0
    k, w = np.zeros(n), np.zeros(n)
    k[0], w[0] = k0, w0
    for i in range(n - 1):
        valley = 1.0 - (w[i] - w0) / s - p  # the lower band at w_i, units of f_t
        if valley <= 0.0:
            return k, w, -1.0
        k[i + 1] = ft * valley / w[i]
        w[i + 1] = ft * (1.0 + w0 / s) / (k[i + 1] + ft / s)  # the next secant meets σ̃
    return k, w, 1.0 - (w[-1] - w0) / s - p


def _one(k0: float, ft: float, gf: float, n: int) -> tuple[np.ndarray, np.ndarray, float, float]:
    """(k, w, p, s) of one face pair (see the module docstring)."""

    def band(s: float) -> float:
        return float(brentq(lambda p: _teeth(k0, s, p, ft, n)[2], 0.0, 1.0, **_TOL))

    def excess(s: float) -> float:
        k, w, _ = _teeth(k0, s, band(s), ft, n)
        return float(dissipation(k[None], w[None]).sum()) - gf

    wc = 2.0 * gf / ft
    lo, hi = 1e-9 * wc, wc
    while excess(hi) < 0.0:  # the teeth lie below σ̃: s ≥ w_c - w₀ holds them all
        lo, hi = hi, 2.0 * hi
    s = float(brentq(excess, lo, hi, **_TOL))
    p = band(s)
    k, w, _ = _teeth(k0, s, p, ft, n)
    return k, w, p, s


def saw_tooth(k0: np.ndarray, *, ft: float, gf: float, n: int) -> SawTooth:
    """The energy-matched saw-tooth of face pairs with first-tooth stiffness ``k0``.

    Args:
        k0: first tooth's stiffness per unit area of each face pair, shape=(m,).
        ft: tensile strength f_t (> 0).
        gf: fracture energy G_f per unit area (> ½ f_t² / k0).
        n: number of teeth N ≥ :data:`MIN_TEETH`.

    Returns:
        the teeth; their dissipation sums to ``gf`` per pair to round-off (brentq to
        a relative 1e-15 on s and p).

    Raises:
        ValueError: n < :data:`MIN_TEETH`, or G_f ≤ ½ f_t² / k0 (the first tooth alone
            stores more than G_f: the cells are too large for this G_f).
    """
    k0 = np.atleast_1d(np.asarray(k0, dtype=float))
    if n < MIN_TEETH:
        raise ValueError(f"a saw-tooth needs at least {MIN_TEETH} teeth, got {n}")
    elastic = 0.5 * ft * ft / k0
    if np.any(elastic >= gf):
        raise ValueError(
            f"G_f = {gf:g} is not above the first tooth's elastic energy ½ f_t²/k₀ = "
            f"{float(elastic.max()):g}: the first tooth alone would dissipate more"
        )
    m = len(k0)
    k, w, p, s = np.zeros((m, n)), np.zeros((m, n)), np.zeros(m), np.zeros(m)
    for j in range(m):
        k[j], w[j], p[j], s[j] = _one(float(k0[j]), ft, gf, n)
    return SawTooth(k=k, f=k * w, w=w, p=p, s=s)
