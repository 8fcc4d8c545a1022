"""Joint slip around a circular opening: Kirsch's stresses and Coulomb's criterion (pure numpy).

The closed form of the check "joint slip around an opening" (issue 45): Kirsch's stresses
with Coulomb's criterion on a plane of weakness of known dip, as Brady and Brown (2004),
Rock Mechanics for Underground Mining, 3rd ed., treat planes of weakness around openings,
and Jaeger, Cook and Zimmerman (2007), Fundamentals of Rock Mechanics, 4th ed., §4.7
(the single plane of weakness). Sign convention of rock mechanics: compressive stress is
positive.

Plane problem: a circular opening of radius a centred at the origin in an infinite
elastic medium under the far-field stresses σ_yy = σ_v (vertical) and σ_xx = K σ_v
(horizontal), σ_xy = 0. Polar angle θ counterclockwise from the +x axis (θ = 0: the
sidewall, θ = 90°: the crown). Kirsch (1898), as Brady and Brown (2004) write it with θ
measured from the horizontal:

    σ_rr = σ_v/2 [(1 + K)(1 − a²/r²) − (1 − K)(1 − 4a²/r² + 3a⁴/r⁴) cos 2θ]
    σ_θθ = σ_v/2 [(1 + K)(1 + a²/r²) + (1 − K)(1 + 3a⁴/r⁴) cos 2θ]
    σ_rθ = σ_v/2 (1 − K)(1 + 2a²/r² − 3a⁴/r⁴) sin 2θ

so that on the wall σ_rr = σ_rθ = 0 and σ_θθ = σ_v [(1 + K) + 2 (1 − K) cos 2θ]
(3 − K at the sidewall, 3K − 1 at the crown).

*Relaxation.* As in the convergence-confinement method, the stress at relaxation
fraction α ∈ [0, 1] is the in-situ state plus α times the excavation's change:
σ(α) = σ₀ + α (σ_Kirsch − σ₀); α = 0 is the unexcavated rock, α = 1 the fully excavated
opening, and on the wall σ_rr(α) = (1 − α) σ₀_rr (a fictitious support pressure).

*Joints.* One set of straight joints whose trace makes the angle δ (the *dip*, degrees,
counterclockwise from +x) with the horizontal: tangent t = (cos δ, sin δ), normal
n = (−sin δ, cos δ). On a joint through a point the normal stress is σn = n·σ n
(compression > 0) and the shear stress τ = t·σ n. The joint slips (Coulomb) where

    F = |τ| − μ σn − c ≥ 0,

with c the cohesion and μ = tan φ the friction coefficient. F ≥ 0 with σn < 0 (tension
across the joint) is the joint opening rather than sliding; both count as the joint's
failure here, as in Brady and Brown.

Because σ is linear in α, σn and τ are too, and F(α) = max(F₊, F₋) is the largest of two
linear functions (τ ≥ 0 and τ ≤ 0): the least α ∈ [0, 1] at which a point's F reaches
zero is a root of one of them (:meth:`JointedOpening.slip_fraction`). The first slip on
the wall is the least of these over θ (:meth:`JointedOpening.first_slip`).

Hand-derivable case (the tests): K = 1 (σ_v = p). On the wall σ_rr = (1 − α) p,
σ_θθ = (1 + α) p, σ_rθ = 0; a joint making the angle β with the wall's tangent carries
σn = p (1 − α cos 2β) and |τ| = α p |sin 2β|, so it slips at

    α* = (c/p + μ) cos φ / sin(2|β| + φ),

least at |β| = 45° − φ/2, where α* = c cos φ / p + sin φ.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

__all__ = ["FirstSlip", "JointedOpening"]

#: Samples of the wall's polar angle over 360° before the minima are refined.
WALL_SAMPLES = 3600
#: Golden-section steps of each refined minimum (the bracket shrinks by 0.618 per step:
#: 80 steps take one sample's width, 0.1°, below 1e-15 rad).
REFINE_STEPS = 80


@dataclass(frozen=True)
class FirstSlip:
    """Where and when the joints first slip on the wall.

    Attributes:
        alpha: the least relaxation fraction at which a wall point slips (0: the in-situ
            state already violates the criterion somewhere; inf: no slip up to α = 1).
        theta: the polar angles (degrees, in [0, 360)) of the wall points where that
            least α is reached, sorted, shape=(k,); empty when alpha is inf.
    """

    alpha: float
    theta: np.ndarray


@dataclass(frozen=True)
class JointedOpening:
    """A circular opening under biaxial in-situ stress, crossed by one joint set.

    Attributes:
        sigma_v: far-field vertical stress σ_v (compression > 0).
        k: ratio K = σ_h / σ_v of the far-field horizontal stress.
        radius: the opening's radius a.
        dip: the joints' trace angle δ from the horizontal, degrees (counterclockwise).
        cohesion: the joints' cohesion c (≥ 0).
        friction: the joints' friction coefficient μ = tan φ (≥ 0).
    """

    sigma_v: float
    k: float
    radius: float
    dip: float
    cohesion: float
    friction: float

    def __post_init__(self) -> None:
        """Refuse a radius that is not positive and negative strengths."""
        if not self.radius > 0.0:
            raise ValueError(f"radius = {self.radius} must be positive")
        if self.cohesion < 0.0 or self.friction < 0.0:
            raise ValueError(
                f"cohesion = {self.cohesion} and friction = {self.friction} must be ≥ 0"
            )

    def kirsch(self, r: ArrayLike, theta: ArrayLike) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Kirsch's polar stresses (σ_rr, σ_θθ, σ_rθ) after full excavation (α = 1).

        Args:
            r: distances from the centre, ≥ radius, any shape.
            theta: polar angles, degrees, broadcastable with ``r``.

        Returns:
            the three components, each of the broadcast shape.
        """
        r, th = np.broadcast_arrays(np.asarray(r, dtype=float), np.radians(theta))
        if np.any(r < self.radius * (1.0 - 1e-12)):
            raise ValueError("kirsch: r must not be inside the opening (r ≥ radius)")
        p, k = self.sigma_v, self.k
        q2 = (self.radius / r) ** 2
        c2, s2 = np.cos(2.0 * th), np.sin(2.0 * th)
        srr = 0.5 * p * ((1 + k) * (1 - q2) - (1 - k) * (1 - 4 * q2 + 3 * q2**2) * c2)
        stt = 0.5 * p * ((1 + k) * (1 + q2) + (1 - k) * (1 + 3 * q2**2) * c2)
        srt = 0.5 * p * (1 - k) * (1 + 2 * q2 - 3 * q2**2) * s2
        return srr, stt, srt

    def stress(
        self, r: ArrayLike, theta: ArrayLike, alpha: ArrayLike
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Cartesian (σ_xx, σ_yy, σ_xy) at relaxation α: σ₀ + α (σ_Kirsch − σ₀).

        Args:
            r: distances from the centre, ≥ radius, any shape.
            theta: polar angles, degrees, broadcastable with ``r``.
            alpha: relaxation fractions, broadcastable with ``r``.

        Returns:
            the three components, each of the broadcast shape.
        """
        r, th, a = np.broadcast_arrays(
            np.asarray(r, dtype=float), np.asarray(theta, dtype=float), np.asarray(alpha)
        )
        srr, stt, srt = self.kirsch(r, th)
        c, s = np.cos(np.radians(th)), np.sin(np.radians(th))
        # polar -> Cartesian: σ = R diag-form Rᵀ with e_r = (c, s), e_θ = (−s, c)
        kxx = srr * c * c + stt * s * s - 2.0 * srt * s * c
        kyy = srr * s * s + stt * c * c + 2.0 * srt * s * c
        kxy = (srr - stt) * s * c + srt * (c * c - s * s)
        sxx0, syy0 = self.k * self.sigma_v, self.sigma_v
        return sxx0 + a * (kxx - sxx0), syy0 + a * (kyy - syy0), a * kxy

    def tractions(
        self, r: ArrayLike, theta: ArrayLike, alpha: ArrayLike
    ) -> tuple[np.ndarray, np.ndarray]:
        """Normal stress σn (compression > 0) and shear stress τ on the joint plane.

        Args:
            r: distances from the centre, ≥ radius, any shape.
            theta: polar angles, degrees, broadcastable with ``r``.
            alpha: relaxation fractions, broadcastable with ``r``.

        Returns:
            (σn, τ), each of the broadcast shape; τ = t·σ n with t = (cos δ, sin δ),
            n = (−sin δ, cos δ).
        """
        sxx, syy, sxy = self.stress(r, theta, alpha)
        d = math.radians(self.dip)
        t = (math.cos(d), math.sin(d))
        n = (-t[1], t[0])
        fx = sxx * n[0] + sxy * n[1]
        fy = sxy * n[0] + syy * n[1]
        return fx * n[0] + fy * n[1], fx * t[0] + fy * t[1]

    def margin(self, r: ArrayLike, theta: ArrayLike, alpha: ArrayLike) -> np.ndarray:
        """Coulomb's F = |τ| − μ σn − c on the joint plane (≥ 0: the joint slips).

        Args:
            r: distances from the centre, ≥ radius, any shape.
            theta: polar angles, degrees, broadcastable with ``r``.
            alpha: relaxation fractions, broadcastable with ``r``.

        Returns:
            F, of the broadcast shape.
        """
        sn, tau = self.tractions(r, theta, alpha)
        return np.abs(tau) - self.friction * sn - self.cohesion

    def slip_fraction(self, r: ArrayLike, theta: ArrayLike) -> np.ndarray:
        """The least α ∈ [0, 1] at which the joint through (r, θ) slips (inf: none).

        F(α) = max(F₊(α), F₋(α)) with F± = ±τ(α) − μ σn(α) − c linear in α (module
        docstring): 0 where F(0) ≥ 0, else the least positive root of F₊ or F₋ that is
        at most 1.

        Args:
            r: distances from the centre, ≥ radius, any shape.
            theta: polar angles, degrees, broadcastable with ``r``.

        Returns:
            α*, of the broadcast shape.
        """
        sn0, t0 = self.tractions(r, theta, 0.0)
        sn1, t1 = self.tractions(r, theta, 1.0)
        mu, c = self.friction, self.cohesion
        out = np.full(np.shape(sn0), np.inf)
        for sign in (1.0, -1.0):
            f0 = sign * t0 - mu * sn0 - c
            slope = sign * (t1 - t0) - mu * (sn1 - sn0)
            rising = (f0 < 0.0) & (slope > 0.0)
            root = np.full(np.shape(f0), np.inf)
            root[rising] = -f0[rising] / slope[rising]
            root[f0 >= 0.0] = 0.0
            out = np.minimum(out, np.where(root <= 1.0, root, np.inf))
        return out

    def first_slip(self, *, samples: int = WALL_SAMPLES, rtol: float = 1e-9) -> FirstSlip:
        """The least α at which a wall point slips, and every wall point that reaches it.

        The wall's α*(θ) is sampled at ``samples`` angles over 360°; each sampled local
        minimum within 1e-6 (relative) of the least is refined by golden section over
        the neighbouring samples, and the refined minima within ``rtol`` (relative, and
        1e-12 absolute) of the least are returned. Where α* is 0 over a range (the
        in-situ state already fails there) the range's sampled angles are returned.

        Args:
            samples: sampled angles over the wall (≥ 8).
            rtol: refined minima this close to the least are first slips too.
        """
        theta = np.arange(samples) * (360.0 / samples)
        alpha = self.slip_fraction(self.radius, theta)
        least = float(alpha.min())
        if math.isinf(least):
            return FirstSlip(math.inf, np.zeros(0))
        if least == 0.0:
            return FirstSlip(0.0, theta[alpha == 0.0])
        prev, nxt = np.roll(alpha, 1), np.roll(alpha, -1)
        local = (alpha <= prev) & (alpha <= nxt) & (alpha <= least * (1.0 + 1e-6) + 1e-12)
        step = 360.0 / samples
        found = [self._refine(float(t) - step, float(t) + step) for t in theta[local]]
        best = min(a for _, a in found)
        keep = sorted({round(t % 360.0, 9) for t, a in found if a <= best * (1.0 + rtol) + 1e-12})
        return FirstSlip(best, np.array(keep))

    def _refine(self, lo: float, hi: float) -> tuple[float, float]:
        """(θ, α*) at the minimum of the wall's α*(θ) in [lo, hi] (golden section)."""
        g = 0.5 * (math.sqrt(5.0) - 1.0)

        def f(t: float) -> float:
            return float(self.slip_fraction(self.radius, t))

        a, b = lo, hi
        x1, x2 = b - g * (b - a), a + g * (b - a)
        f1, f2 = f(x1), f(x2)
        for _ in range(REFINE_STEPS):
            if f1 <= f2:
                b, x2, f2 = x2, x1, f1
                x1 = b - g * (b - a)
                f1 = f(x1)
            else:
                a, x1, f1 = x1, x2, f2
                x2 = a + g * (b - a)
                f2 = f(x2)
        t = 0.5 * (a + b)
        return t, f(t)
