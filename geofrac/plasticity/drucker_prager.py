"""Drucker-Prager perfect plasticity: yield function, return mapping, consistent tangent.

Yield function f = β I₁ + √J₂ − k (Edo (2016), eq. 4.39; I₁ eq. 4.40, J₂ eq. 4.41;
tension positive). The constants match the cone to Mohr-Coulomb's c and φ
(de Souza Neto, Perić and Owen (2008), 8.1.3, with η = 3β, ξc = k):

- ``plane_strain`` (the default, and MPM's): β = tan φ/√(9 + 12 tan² φ) (eq. 4.42),
  k = 3c/√(9 + 12 tan² φ) (eq. 4.43): the same plane-strain limit loads as Mohr-Coulomb
  with associated flow;
- ``outer``: β = 2 sin φ/(√3 (3 − sin φ)), k = 6c cos φ/(√3 (3 − sin φ)): through the
  compression corners (the uniaxial compressive strength 2c cos φ/(1 − sin φ));
- ``inner``: the same with 3 + sin φ: through the extension corners.

Flow: the potential g = β_ψ I₁ + √J₂ has the dilatancy angle ψ in place of φ (the same
match; ψ = φ is associated flow, ψ = 0 keeps the plastic volume). From the elastic
trial σ* (K, G the bulk and shear moduli, q* = √J₂(σ*), s* its deviator):
Δλ = f(σ*)/(9K β β_ψ + G), σ = σ* − Δλ (3K β_ψ I + G s*/q*), which lands on f = 0
(the cone return). A trial whose return would pass the apex (q* − G Δλ ≤ 0) returns to
the apex σ = k/(3β) I (with β = 0, the von Mises cylinder of radius k = 0: σ = (I₁*/3) I).

The consistent tangent on the cone, with n = s*/q*, A = 9K β β_ψ + G and
𝕀ᵈ = 𝕀ˢʸᵐ − I⊗I/3:

    D = K I⊗I + 2G (1 − G Δλ/q*) 𝕀ᵈ + (G² Δλ/q*) n⊗n − (3K β_ψ I + G n)⊗(3K β I + G n)/A

(not symmetric unless ψ = φ); at the apex D = 0 (a fixed point; K I⊗I when β = 0).
At the apex the multiplier is reported as the cone's Δλ above (the measure MPM
accumulates as ``plastic_strain``); the plastic strain increment C⁻¹:(σ* − σ) is exact.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from geofrac.plasticity.elasticity import ElasticTrial, compliance, elastic_tangent
from geofrac.plasticity.invariants import deviator, first_invariant, sqrt_j2
from geofrac.plasticity.returns import APEX, SMOOTH, Return

__all__ = ["MATCHES", "DruckerPrager", "cone_constants", "yield_function"]

#: The matches of the cone to Mohr-Coulomb.
MATCHES = ("plane_strain", "outer", "inner")


def cone_constants(angle: float, cohesion: float, match: str) -> tuple[float, float]:
    """(β, k) of the cone matched to Mohr-Coulomb.

    Args:
        angle: φ (or ψ, for the potential's β_ψ) in degrees.
        cohesion: c.
        match: one of :data:`MATCHES`.
    """
    if match == "plane_strain":
        t = np.tan(np.radians(angle))
        root = np.sqrt(9 + 12 * t * t)
        return float(t / root), float(3 * cohesion / root)
    if match not in MATCHES:
        raise ValueError(f"match must be one of {MATCHES}, got {match!r}")
    s, c = np.sin(np.radians(angle)), np.cos(np.radians(angle))
    d = np.sqrt(3) * (3 - s if match == "outer" else 3 + s)
    return float(2 * s / d), float(6 * cohesion * c / d)


def yield_function(stress: np.ndarray, beta: float, k: float) -> np.ndarray:
    """The yield f = β I₁ + √J₂ − k (Edo (2016), eq. 4.39), shape=(n, 3, 3) → shape=(n,)."""
    return beta * first_invariant(stress) + sqrt_j2(stress) - k


@dataclass(frozen=True)
class DruckerPrager(ElasticTrial):
    """Drucker-Prager material (isotropic elasticity, perfect plasticity).

    Attributes:
        E: Young's modulus.
        nu: Poisson's ratio.
        friction_angle: φ in degrees.
        cohesion: c (>= 0).
        dilatancy_angle: ψ in degrees (0 <= ψ <= φ; 0: no plastic volume change).
        match: how the cone meets Mohr-Coulomb (:data:`MATCHES`).
    """

    #: One multiplier column: the cone.
    SURFACES: ClassVar[tuple[str, ...]] = ("cone",)

    E: float
    nu: float
    friction_angle: float
    cohesion: float = 0.0
    dilatancy_angle: float = 0.0
    match: str = "plane_strain"

    def __post_init__(self) -> None:
        """Check the parameters."""
        self.check_common()
        if self.match not in MATCHES:
            raise ValueError(f"match must be one of {MATCHES}, got {self.match!r}")

    @property
    def beta(self) -> float:
        """β of the yield function (eq. 4.42 for the plane-strain match)."""
        return cone_constants(self.friction_angle, self.cohesion, self.match)[0]

    @property
    def k(self) -> float:
        """The constant k of the yield function (eq. 4.43 for the plane-strain match)."""
        return cone_constants(self.friction_angle, self.cohesion, self.match)[1]

    @property
    def beta_psi(self) -> float:
        """β_ψ of the plastic potential (the match with ψ)."""
        return cone_constants(self.dilatancy_angle, 0.0, self.match)[0]

    def yield_function(self, stress: np.ndarray) -> np.ndarray:
        """f(σ), shape=(n, 3, 3) → shape=(n,)."""
        return yield_function(stress, self.beta, self.k)

    def return_map(self, trial: np.ndarray, *, tangent: bool = False) -> Return:
        """Return mapping of elastic trial stresses (the module docstring).

        Args:
            trial: elastic trial stresses, shape=(n, 3, 3).
            tangent: also compute the consistent tangent, shape=(n, 3, 3, 3, 3).

        Returns:
            The :class:`~geofrac.plasticity.returns.Return`; multipliers shape=(n, 1).
        """
        K, G = self.moduli()
        eye = np.eye(3)
        f = self.yield_function(trial)
        dlam = np.zeros(len(trial))
        kind = np.zeros(len(trial), dtype=np.int8)
        new = trial.copy()
        plastic = f > 0
        b, bp, k = self.beta, self.beta_psi, self.k
        if np.any(plastic):
            t = trial[plastic]
            i1 = first_invariant(t)
            s = deviator(t)
            q0 = sqrt_j2(t)
            lam = f[plastic] / (9 * K * b * bp + G)
            q = q0 - G * lam  # √J₂ after the return
            cone = q > 0
            out = np.empty_like(t)
            unit = np.where(q0[:, None, None] > 0, s / np.maximum(q0, 1e-300)[:, None, None], 0)
            i1_new = i1 - 9 * K * bp * lam
            out[cone] = (i1_new[cone] / 3)[:, None, None] * eye + q[cone, None, None] * unit[cone]
            apex = ~cone
            if np.any(apex):
                if b > 0:
                    out[apex] = (k / (3 * b)) * eye
                else:  # von Mises limit (φ = 0) with k = 0: the deviator on the cylinder k
                    out[apex] = (i1[apex] / 3)[:, None, None] * eye + k * unit[apex]
            new[plastic] = out
            dlam[plastic] = lam
            kind[plastic] = np.where(cone, SMOOTH, APEX)
        return Return(
            stress=new,
            multipliers=dlam[:, None],
            plastic_strain=compliance(trial - new, K, G),
            kind=kind,
            tangent=self._tangent(trial, dlam, kind) if tangent else None,
        )

    def _tangent(self, trial: np.ndarray, dlam: np.ndarray, kind: np.ndarray) -> np.ndarray:
        """The consistent tangent of each point (module docstring), shape=(n, 3, 3, 3, 3)."""
        K, G = self.moduli()
        b, bp = self.beta, self.beta_psi
        eye = np.eye(3)
        C = elastic_tangent(K, G)
        out = np.broadcast_to(C, (len(trial), 3, 3, 3, 3)).copy()
        cone = kind == SMOOTH
        if np.any(cone):
            q0 = sqrt_j2(trial[cone])
            n = deviator(trial[cone]) / q0[:, None, None]
            lam = dlam[cone]
            ii = np.einsum("ij,kl->ijkl", eye, eye)
            dev4 = (C - K * ii) / (2 * G)  # 𝕀ˢʸᵐ − I⊗I/3
            r = G * lam / q0
            flow = 3 * K * bp * eye + G * n
            normal = 3 * K * b * eye + G * n
            out[cone] = (
                K * ii
                + 2 * G * (1 - r)[:, None, None, None, None] * dev4
                + (G * r)[:, None, None, None, None] * np.einsum("nij,nkl->nijkl", n, n)
                - np.einsum("nij,nkl->nijkl", flow, normal) / (9 * K * b * bp + G)
            )
        apex = kind == APEX
        if np.any(apex):
            out[apex] = K * np.einsum("ij,kl->ijkl", eye, eye) if b == 0 else 0.0
        return out
