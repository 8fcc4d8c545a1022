"""A circular opening in Mohr-Coulomb rock: plastic radius and radial displacement.

Salençon (1969) and Carranza-Torres and Fairhurst (1999) (their "ground reaction curve"):
a cylindrical opening of radius a, plane strain, in an elastic-perfectly plastic
Mohr-Coulomb material (c, φ, dilatancy ψ, E, ν) under hydrostatic in-situ stress p₀,
internal pressure pᵢ lowered from p₀. Written here for a thick ring a ≤ r ≤ b with the
outer pressure p₀ held (b → ∞ is Salençon's opening; the method is theirs, only the
elastic zone is the finite Lamé ring of Timoshenko and Goodier (1970), §28). Pressures
are compressive positive in this module; the displacement u_r is positive outwards and
measured from the uniform state σ = −p₀ I (so it is negative: the wall converges).

With K_p = (1 + sin φ)/(1 − sin φ), σ_c = 2c cos φ/(1 − sin φ), A = c cot φ, the yield
condition in the plastic zone a ≤ r ≤ ρ is σ_θ = K_p σ_r + σ_c (σ_z intermediate), and
equilibrium dσ_r/dr = (σ_θ − σ_r)/r gives

    σ_r + A = (pᵢ + A) (r/a)^(K_p − 1).

In the elastic zone ρ ≤ r ≤ b the stresses are Lamé's, σ_r = P + Q/r², σ_θ = P − Q/r²
with σ_r(b) = p₀, σ_r(ρ) = p_ρ; the elastic zone is at yield at ρ, 2P − p_ρ = K_p p_ρ +
σ_c, which fixes ρ (one root). For b → ∞: p_ρ = p_cr = (2p₀ − σ_c)/(1 + K_p) and
ρ = a [2(p₀ + A)/((1 + K_p)(pᵢ + A))]^(1/(K_p − 1)) (Salençon (1969)). No plastic zone
when pᵢ ≥ p_cr (the elastic ring, Lamé).

Displacement in the plastic zone: the flow rule of the main plane gives
εᵖ_r + K_ψ εᵖ_θ = 0, K_ψ = (1 + sin ψ)/(1 − sin ψ) (εᵖ_z = 0), so with ε_r = du/dr,
ε_θ = u/r and the elastic strains of the known stresses, d(u r^K_ψ)/dr = r^K_ψ (εᵉ_r +
K_ψ εᵉ_θ), integrated in closed form from u(ρ) (the elastic zone's) inwards. This is
Carranza-Torres and Fairhurst's (1999) solution with the elastic strains of the whole
stress change from p₀ (their eq. 30ff. use the same flow rule).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

__all__ = ["MohrCoulombOpening"]


@dataclass(frozen=True)
class MohrCoulombOpening:
    """The ring a ≤ r ≤ b (b = inf: the opening in an infinite medium).

    Attributes:
        a: opening radius.
        b: outer radius (> a), or ``math.inf``.
        p0: in-situ (and outer) pressure, compressive positive.
        pi: internal pressure, 0 ≤ pᵢ ≤ p₀.
        E: Young's modulus.
        nu: Poisson's ratio.
        cohesion: c.
        friction_angle: φ in degrees, > 0.
        dilatancy_angle: ψ in degrees, 0 ≤ ψ ≤ φ.
    """

    a: float
    b: float
    p0: float
    pi: float
    E: float
    nu: float
    cohesion: float
    friction_angle: float
    dilatancy_angle: float = 0.0

    def __post_init__(self) -> None:
        """Refuse impossible data (ValueError)."""
        if not 0.0 < self.a < self.b:
            raise ValueError(f"needs 0 < a < b, got a = {self.a!r}, b = {self.b!r}")
        if not 0.0 < self.friction_angle < 90.0:
            raise ValueError(
                f"friction_angle must be in (0, 90) degrees, got {self.friction_angle}"
            )
        if not 0.0 <= self.dilatancy_angle <= self.friction_angle:
            raise ValueError("dilatancy_angle must be in [0, friction_angle]")
        if not 0.0 <= self.pi <= self.p0:
            raise ValueError(f"needs 0 <= pi <= p0, got pi = {self.pi}, p0 = {self.p0}")

    @property
    def kp(self) -> float:
        """K_p = (1 + sin φ)/(1 − sin φ)."""
        s = math.sin(math.radians(self.friction_angle))
        return (1 + s) / (1 - s)

    @property
    def kpsi(self) -> float:
        """K_ψ = (1 + sin ψ)/(1 − sin ψ)."""
        s = math.sin(math.radians(self.dilatancy_angle))
        return (1 + s) / (1 - s)

    @property
    def sigma_c(self) -> float:
        """Uniaxial compressive strength 2c cos φ/(1 − sin φ)."""
        phi = math.radians(self.friction_angle)
        return 2 * self.cohesion * math.cos(phi) / (1 - math.sin(phi))

    @property
    def attraction(self) -> float:
        """A = c cot φ."""
        return self.cohesion / math.tan(math.radians(self.friction_angle))

    def _plastic_radial(self, r: float) -> float:
        """σ_r (compressive) at r in the plastic zone."""
        A = self.attraction
        return (self.pi + A) * (r / self.a) ** (self.kp - 1) - A

    def _lame(self, rho: float, p_rho: float) -> tuple[float, float]:
        """(P, Q) of the elastic zone ρ ≤ r ≤ b with σ_r(ρ) = p_ρ, σ_r(b) = p₀."""
        if math.isinf(self.b):
            return self.p0, (p_rho - self.p0) * rho * rho
        b2, r2 = self.b * self.b, rho * rho
        P = (self.p0 * b2 - p_rho * r2) / (b2 - r2)
        return P, (self.p0 - P) * b2

    def _yield_gap(self, rho: float) -> float:
        """σ_θ − (K_p σ_r + σ_c) of the elastic zone at ρ (zero at the plastic radius)."""
        p_rho = self._plastic_radial(rho)
        P, _ = self._lame(rho, p_rho)
        return (2 * P - p_rho) - (self.kp * p_rho + self.sigma_c)

    @property
    def plastic_radius(self) -> float:
        """ρ, the radius of the plastic zone (a when the ring stays elastic)."""
        if self._yield_gap(self.a) <= 0.0:
            return self.a
        if math.isinf(self.b):
            A, kp = self.attraction, self.kp
            ratio = 2 * (self.p0 + A) / ((1 + kp) * (self.pi + A))
            return self.a * ratio ** (1 / (kp - 1))
        lo, hi = self.a, self.b * (1 - 1e-12)
        if self._yield_gap(hi) > 0.0:
            raise ValueError("the whole ring yields: no elastic zone")
        for _ in range(200):  # bisection to round-off
            mid = 0.5 * (lo + hi)
            lo, hi = (mid, hi) if self._yield_gap(mid) > 0.0 else (lo, mid)
        return 0.5 * (lo + hi)

    def _elastic_u(self, r: float, rho: float) -> float:
        """u_r in the elastic zone (from the uniform state −p₀ I)."""
        p_rho = self._plastic_radial(rho) if rho > self.a else self.pi
        P, Q = self._lame(rho, p_rho)
        return (1 + self.nu) / self.E * (-(1 - 2 * self.nu) * (P - self.p0) * r + Q / r)

    def radial_displacement(self, r: float) -> float:
        """u_r at a ≤ r ≤ b (outward positive; negative: the opening converges)."""
        rho = self.plastic_radius
        if r >= rho:
            return self._elastic_u(r, rho)
        E, nu, kp, kq = self.E, self.nu, self.kp, self.kpsi
        A, m = self.attraction, kp - 1
        B = (self.pi + A) * self.a ** (-m)
        # tension-positive stress changes: Δσ_r = (A + p₀) − B s^m, Δσ_θ = (A + p₀) − K_p B s^m
        c0 = (1 + nu) / E * (A + self.p0) * (1 - 2 * nu) * (1 + kq)
        c1 = -(1 + nu) / E * B * ((1 - nu) - nu * kp + kq * ((1 - nu) * kp - nu))

        def primitive(s: float) -> float:
            """∫ s^K_ψ (c0 + c1 s^m) ds."""
            return c0 * s ** (kq + 1) / (kq + 1) + c1 * s ** (kq + kp) / (kq + kp)

        u_rho = self._elastic_u(rho, rho)
        return float((rho**kq * u_rho - (primitive(rho) - primitive(r))) / r**kq)

    @property
    def wall_displacement(self) -> float:
        """u_r(a)."""
        return self.radial_displacement(self.a)

    def stresses(self, r: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(σ_r, σ_θ) compressive positive at radii r, shape=(n,) each."""
        r = np.asarray(r, dtype=float)
        rho = self.plastic_radius
        A, kp = self.attraction, self.kp
        plastic = r < rho
        sr_p = (self.pi + A) * (r / self.a) ** (kp - 1) - A
        p_rho = self._plastic_radial(rho) if rho > self.a else self.pi
        P, Q = self._lame(rho, p_rho)
        sr = np.where(plastic, sr_p, P + Q / r**2)
        st = np.where(plastic, kp * sr_p + self.sigma_c, P - Q / r**2)
        return sr, st
