"""The linear elastic MPM material (Edo (2016), eqs. 4.34, D.8): model ``elastic``.

The default :class:`~geofrac.mpm.constitutive.ConstitutiveModel` of an MPM scene: in 1D
the bar law Δσ = E Δε, in 2D plane strain (σ_zz kept, Δσ_zz = λ tr Δε), in 3D
isotropic, after the Jaumann rotation (D.30-D.31). The compiled update is
:func:`geofrac.mpm.kernels.elastic_update`; the numpy one is the reference.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, ClassVar

import numpy as np

from geofrac.materials import lame, p_wave_modulus
from geofrac.mpm.energy import stored
from geofrac.mpm.rotation import rotate_stress, spin_increment

if TYPE_CHECKING:
    from geofrac.mpm.energy import StepBudget
    from geofrac.mpm.particles import Particles

__all__ = ["Elastic", "from_scene"]


@dataclass(frozen=True)
class Elastic:
    """Linear elastic increments Δσ = D : Δε (eqs. 4.34, D.8).

    In 1D the bar law Δσ = E Δε; in 2D plane strain; in 3D isotropic.

    Attributes:
        E: Young's modulus.
        nu: Poisson's ratio (unused in 1D).
    """

    name: ClassVar[str] = "elastic"
    dims: ClassVar[tuple[int, ...]] = (1, 2, 3)
    state: ClassVar[tuple[str, ...]] = ("stress", "stress_zz")
    compiled: ClassVar[bool] = True

    E: float
    nu: float = 0.0

    def lame(self) -> tuple[float, float]:
        """(λ, μ) of 3D and plane strain (:func:`geofrac.materials.lame`)."""
        return lame(self.E, self.nu, 3)

    def increment(self, deps: np.ndarray) -> np.ndarray:
        """Δσ of strain increments, both shape=(n, dim, dim)."""
        if deps.shape[1] == 1:
            return self.E * deps
        lam, mu = self.lame()
        tr = np.trace(deps, axis1=1, axis2=2)
        return lam * tr[:, None, None] * np.eye(deps.shape[1]) + 2 * mu * deps

    def wave_speed(self, density: float, dim: int) -> float:
        """The elastic wave speed c of eq. 4.72 (the P wave in 2D and 3D)."""
        return float(np.sqrt(p_wave_modulus(self.E, self.nu, dim) / density))

    def stored_energy(self, p: Particles) -> np.ndarray:
        """½ V_p σ_p : D⁻¹ : σ_p per particle, shape=(n,) (plane strain: with σ_zz)."""
        return stored(p.stress, p.stress_zz, p.volume, E=self.E, nu=self.nu)

    def results(self) -> dict[str, float]:
        """Nothing: E and ν are in the scene."""
        return {}

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
        """Jaumann rotation (2D, 3D) and Δσ = D : Δε, in place; dissipates nothing.

        Args:
            p: the particles.
            deps: strain increments, shape=(n, dim, dim).
            L: velocity gradients, shape=(n, dim, dim).
            dt: the step of this update.
            backend: ``numba`` or ``numpy``.
            budget: unused (an elastic update dissipates nothing).
        """
        d = p.dim
        if backend == "numba":
            from geofrac.mpm import kernels

            lam, mu = self.lame() if d > 1 else (0.0, 0.0)
            kernels.elastic_update(deps, L, dt, self.E, lam, mu, p.stress, p.stress_zz)
            return
        if d > 1:
            p.stress = rotate_stress(p.stress, spin_increment(L, dt))
        p.stress += self.increment(deps)
        if d == 2:
            p.stress_zz += self.lame()[0] * np.trace(deps, axis1=1, axis2=2)


def from_scene(E: float, nu: float, config: None) -> Elastic:
    """The elastic material of a scene's ``[material]`` (no effect configures it)."""
    return Elastic(E, nu)
