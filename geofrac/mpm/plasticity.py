"""Drucker-Prager plasticity with return mapping: the MPM model ``plasticity``.

A :class:`~geofrac.mpm.constitutive.ConstitutiveModel` selected by the scene's
``plasticity`` effect (its table is validated by :mod:`geofrac.effects.plasticity`).
The return mapping works on full 3×3 stress tensors (plane strain keeps σ_zz), in numpy
for either backend (Edo (2016), 4.3.2, App. D):

- yield function f = β I₁ + √J₂ − k (4.39) with I₁ = tr σ (4.40), J₂ = ½ s:s (4.41),
  β = tan φ / √(9 + 12 tan² φ) (4.42) and k = 3c / √(9 + 12 tan² φ) (4.43), φ the
  friction angle and c the cohesion (the plane-strain match to Mohr-Coulomb);
- elastic-perfectly plastic return mapping from the elastic trial stress: the plastic
  potential g = β_ψ I₁ + √J₂ has the dilatancy angle ψ in place of φ (ψ = φ is
  associated flow; the default ψ = 0 keeps the plastic volume); the return is
  σ = σ* − Δλ (3K β_ψ I + G s*/√J₂*) with Δλ = f(σ*)/(9K β β_ψ + G), which lands on
  f = 0; a trial stress beyond the apex returns to the apex σ = k/(3β) I (σ = 0 for a
  cohesionless soil: no tension).

The Jaumann rotation (D.30-D.31) that precedes every stress update, elastic or
plastic, is :func:`geofrac.mpm.rotation.rotate_stress`. The energy the return takes out
(``budget.plastic``, :mod:`~geofrac.mpm.energy`) is the stored energy of the rotated
elastic trial minus that after the return.

Edo (2016) gives the yield function only; the flow rule and the apex treatment are the
standard ones (e.g. de Souza Neto, Perić and Owen, ch. 8) and are documented here
because the thesis is silent on them.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, ClassVar, Protocol

import numpy as np

from geofrac.materials import bulk_shear, p_wave_modulus
from geofrac.mpm.elastic import Elastic
from geofrac.mpm.energy import stored
from geofrac.mpm.rotation import rotate_stress, spin_increment

if TYPE_CHECKING:
    from geofrac.mpm.energy import StepBudget
    from geofrac.mpm.particles import Particles

__all__ = ["DruckerPrager", "PlasticityParameters", "from_scene", "yield_function"]


class PlasticityParameters(Protocol):
    """The validated ``[plasticity]`` table (:class:`geofrac.effects.plasticity.PlasticityConfig`).

    Attributes:
        friction_angle: φ in degrees.
        cohesion: c.
        dilatancy_angle: ψ in degrees.
    """

    @property
    def friction_angle(self) -> float: ...  # noqa: D102

    @property
    def cohesion(self) -> float: ...  # noqa: D102

    @property
    def dilatancy_angle(self) -> float: ...  # noqa: D102


@dataclass(frozen=True)
class DruckerPrager:
    """Drucker-Prager material (isotropic elasticity, perfect plasticity).

    Attributes:
        E: Young's modulus.
        nu: Poisson's ratio.
        friction_angle: φ in degrees.
        cohesion: c (>= 0).
        dilatancy_angle: ψ in degrees (0 <= ψ <= φ; 0: no plastic volume change).
    """

    name: ClassVar[str] = "plasticity"
    dims: ClassVar[tuple[int, ...]] = (2, 3)
    state: ClassVar[tuple[str, ...]] = ("stress", "stress_zz", "plastic")
    compiled: ClassVar[bool] = False

    E: float
    nu: float
    friction_angle: float
    cohesion: float = 0.0
    dilatancy_angle: float = 0.0

    def __post_init__(self) -> None:
        """Check the parameters."""
        if not self.E > 0 or not -1 < self.nu < 0.5:
            raise ValueError(f"need E > 0 and -1 < nu < 0.5, got E={self.E}, nu={self.nu}")
        if (
            not 0 <= self.friction_angle < 90
            or not 0 <= self.dilatancy_angle <= self.friction_angle
        ):
            raise ValueError("need 0 <= dilatancy_angle <= friction_angle < 90 (degrees)")
        if self.cohesion < 0:
            raise ValueError(f"cohesion must be >= 0, got {self.cohesion}")

    @property
    def beta(self) -> float:
        """β of eq. 4.42."""
        t = np.tan(np.radians(self.friction_angle))
        return float(t / np.sqrt(9 + 12 * t * t))

    @property
    def k(self) -> float:
        """The material constant k of eq. 4.43."""
        t = np.tan(np.radians(self.friction_angle))
        return float(3 * self.cohesion / np.sqrt(9 + 12 * t * t))

    @property
    def beta_psi(self) -> float:
        """β of the plastic potential (eq. 4.42 with ψ)."""
        t = np.tan(np.radians(self.dilatancy_angle))
        return float(t / np.sqrt(9 + 12 * t * t))

    def moduli(self) -> tuple[float, float]:
        """(bulk modulus K, shear modulus G) (:func:`geofrac.materials.bulk_shear`)."""
        return bulk_shear(self.E, self.nu)

    def wave_speed(self, density: float, dim: int) -> float:
        """The elastic P-wave speed c of eq. 4.72 (the return only slows waves)."""
        return float(np.sqrt(p_wave_modulus(self.E, self.nu, dim) / density))

    def stored_energy(self, p: Particles) -> np.ndarray:
        """½ V_p σ_p : D⁻¹ : σ_p per particle (the elastic part), shape=(n,)."""
        return stored(p.stress, p.stress_zz, p.volume, E=self.E, nu=self.nu)

    def results(self) -> dict[str, float]:
        """``friction_angle_deg``: φ, the parameter a landslide sweep varies."""
        return {"friction_angle_deg": self.friction_angle}

    def stress_update(
        self,
        p: Particles,
        deps: np.ndarray,
        L: np.ndarray,
        *,
        dt: float,
        backend: str,
        budget: StepBudget | None,
    ) -> None:
        """Jaumann rotation (D.30-D.31) and the return (4.39-4.43) on 3×3 stresses, in place.

        Plane strain in 2D: the strain increment has no zz part, σ_zz is the stored one.
        ``p.plastic`` gathers the multipliers Δλ. numpy for either ``backend``.

        Args:
            p: the particles, shape of their stresses (n, dim, dim), dim 2 or 3.
            deps: strain increments, shape=(n, dim, dim).
            L: velocity gradients, shape=(n, dim, dim).
            dt: the step of this update.
            backend: unused (one implementation).
            budget: add the dissipation U(rotated trial) − U(returned) to ``budget.plastic``.
        """
        n, d = p.n, p.dim
        el = Elastic(self.E, self.nu)
        tr = np.trace(deps, axis1=1, axis2=2)
        volume = p.volume * (1.0 + tr)  # the volume after this update (D.9)
        if budget is not None:  # stored energy of the elastic trial σ + D:Δε
            zz = p.stress_zz + (el.lame()[0] * tr if d == 2 else 0.0)
            trial = float(
                np.sum(stored(p.stress + el.increment(deps), zz, volume, E=self.E, nu=self.nu))
            )
        full = np.zeros((n, 3, 3))
        full[:, :d, :d] = p.stress
        if d == 2:
            full[:, 2, 2] = p.stress_zz
        spin = np.zeros((n, 3, 3))
        spin[:, :d, :d] = spin_increment(L, dt)
        deps3 = np.zeros((n, 3, 3))
        deps3[:, :d, :d] = deps
        rotated = rotate_stress(full, spin)
        if budget is not None:  # the rotation's change of the trial's stored energy
            zero = np.zeros(n)
            budget.plastic += float(
                np.sum(
                    stored(rotated + el.increment(deps3), zero, volume, E=self.E, nu=self.nu)
                    - stored(full + el.increment(deps3), zero, volume, E=self.E, nu=self.nu)
                )
            )  # the return starts from the rotated trial
        new, dlam = self.update(rotated, deps3)
        p.stress = new[:, :d, :d].copy()
        if d == 2:
            p.stress_zz = new[:, 2, 2].copy()
        p.plastic += dlam
        if budget is not None:
            after = stored(p.stress, p.stress_zz, volume, E=self.E, nu=self.nu)
            budget.plastic += trial - float(np.sum(after))

    def update(self, stress: np.ndarray, deps: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Elastic trial and return mapping for strain increments.

        Args:
            stress: stresses at the start, shape=(n, 3, 3).
            deps: strain increments, shape=(n, 3, 3) (plane strain: zero zz entries).

        Returns:
            The new stresses, shape=(n, 3, 3), and the plastic multipliers Δλ, shape=(n,)
            (0 where the step stayed elastic).
        """
        K, G = self.moduli()
        eye = np.eye(3)
        tr = np.trace(deps, axis1=1, axis2=2)
        dev = deps - tr[:, None, None] / 3 * eye
        trial = stress + K * tr[:, None, None] * eye + 2 * G * dev
        f = yield_function(trial, self.beta, self.k)
        dlam = np.zeros(len(stress))
        plastic = f > 0
        if not np.any(plastic):
            return trial, dlam
        t = trial[plastic]
        i1 = np.trace(t, axis1=1, axis2=2)
        s = t - i1[:, None, None] / 3 * eye
        sqrt_j2 = np.sqrt(0.5 * np.sum(s * s, axis=(1, 2)))
        b, bp = self.beta, self.beta_psi
        lam = f[plastic] / (9 * K * b * bp + G)
        q = sqrt_j2 - G * lam  # √J₂ after the return
        cone = q > 0
        out = np.empty_like(t)
        unit = np.where(
            sqrt_j2[:, None, None] > 0, s / np.maximum(sqrt_j2, 1e-300)[:, None, None], 0
        )
        i1_new = i1 - 9 * K * bp * lam
        out[cone] = (i1_new[cone] / 3)[:, None, None] * eye + q[cone, None, None] * unit[cone]
        # beyond the apex: the apex (√J₂ = 0, β I₁ = k)
        apex = ~cone
        if np.any(apex):
            if b > 0:
                out[apex] = (self.k / (3 * b)) * eye
            else:  # von Mises limit (φ = 0): the deviator on the cylinder k
                out[apex] = (i1[apex] / 3)[:, None, None] * eye + self.k * unit[apex]
        new = trial.copy()
        new[plastic] = out
        dlam[plastic] = lam
        return new, dlam


def yield_function(stress: np.ndarray, beta: float, k: float) -> np.ndarray:
    """The yield function f = β I₁ + √J₂ − k (eq. 4.39), shape=(n, 3, 3) → shape=(n,)."""
    i1 = np.trace(stress, axis1=1, axis2=2)
    s = stress - i1[:, None, None] / 3 * np.eye(3)
    return beta * i1 + np.sqrt(0.5 * np.sum(s * s, axis=(1, 2))) - k


def from_scene(E: float, nu: float, config: PlasticityParameters) -> DruckerPrager:
    """The Drucker-Prager material of a scene's ``[material]`` and ``[plasticity]``."""
    return DruckerPrager(E, nu, config.friction_angle, config.cohesion, config.dilatancy_angle)
