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
because the thesis is silent on them. The return itself is the shared one,
:class:`geofrac.plasticity.drucker_prager.DruckerPrager` (plane-strain match), which the
finite-element solver uses too (docs/plasticity.md).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, ClassVar, Protocol

import numpy as np

from geofrac.materials import bulk_shear, p_wave_modulus
from geofrac.mpm.elastic import Elastic
from geofrac.mpm.energy import stored
from geofrac.mpm.rotation import rotate_stress, spin_increment
from geofrac.plasticity.drucker_prager import DruckerPrager as SharedDruckerPrager
from geofrac.plasticity.drucker_prager import yield_function

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
        """Check the parameters (the shared law's checks)."""
        _ = self.law

    @property
    def law(self) -> SharedDruckerPrager:
        """The shared law (:mod:`geofrac.plasticity.drucker_prager`, plane-strain match)."""
        return SharedDruckerPrager(
            self.E, self.nu, self.friction_angle, self.cohesion, self.dilatancy_angle
        )

    @property
    def beta(self) -> float:
        """β of eq. 4.42."""
        return self.law.beta

    @property
    def k(self) -> float:
        """The material constant k of eq. 4.43."""
        return self.law.k

    @property
    def beta_psi(self) -> float:
        """β of the plastic potential (eq. 4.42 with ψ)."""
        return self.law.beta_psi

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
        """Elastic trial and return mapping for strain increments (the shared return).

        Args:
            stress: stresses at the start, shape=(n, 3, 3).
            deps: strain increments, shape=(n, 3, 3) (plane strain: zero zz entries).

        Returns:
            The new stresses, shape=(n, 3, 3), and the plastic multipliers Δλ, shape=(n,)
            (0 where the step stayed elastic; the cone's Δλ at the apex).
        """
        ret = self.law.update(stress, deps)
        return ret.stress, ret.multipliers[:, 0]


def from_scene(E: float, nu: float, config: PlasticityParameters) -> DruckerPrager:
    """The Drucker-Prager material of a scene's ``[material]`` and ``[plasticity]``."""
    return DruckerPrager(E, nu, config.friction_angle, config.cohesion, config.dilatancy_angle)
