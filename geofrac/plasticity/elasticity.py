"""Isotropic linear elasticity on arrays of 3×3 tensors (pure numpy), for the returns.

The elastic trial σ* = σₙ + K tr(Δε) I + 2G dev(Δε), the compliance C⁻¹ that turns
σ* − σ into the plastic strain increment, the stored energy density ½ σ:C⁻¹:σ, the
elasticity tensor C and the Voigt form of fourth-order tangents (order xx, yy, zz, yz,
xz, xy with engineering shear strains, as :func:`geofrac.materials.d_matrix`).
"""

from __future__ import annotations

import numpy as np

from geofrac.materials import bulk_shear
from geofrac.plasticity.returns import Return

__all__ = [
    "VOIGT",
    "ElasticTrial",
    "compliance",
    "elastic_tangent",
    "elastic_trial",
    "energy_density",
    "to_voigt",
]

#: The (i, j) index pairs of the Voigt order xx, yy, zz, yz, xz, xy.
VOIGT = ((0, 0), (1, 1), (2, 2), (1, 2), (0, 2), (0, 1))


def elastic_trial(stress: np.ndarray, deps: np.ndarray, *, K: float, G: float) -> np.ndarray:
    """σ* = σ + K tr(Δε) I + 2G dev(Δε).

    Args:
        stress: stresses at the start of the step, shape=(n, 3, 3).
        deps: strain increments, shape=(n, 3, 3) (plane strain: zero zz, xz, yz entries).
        K: bulk modulus.
        G: shear modulus.

    Returns:
        The elastic trial stresses, shape=(n, 3, 3).
    """
    eye = np.eye(3)
    tr = np.trace(deps, axis1=1, axis2=2)
    dev = deps - tr[:, None, None] / 3 * eye
    return stress + K * tr[:, None, None] * eye + 2 * G * dev


def compliance(stress: np.ndarray, K: float, G: float) -> np.ndarray:
    """C⁻¹:σ = tr σ/(9K) I + dev σ/(2G), shape=(n, 3, 3) → shape=(n, 3, 3)."""
    tr = np.trace(stress, axis1=1, axis2=2)[:, None, None]
    return tr / (9 * K) * np.eye(3) + (stress - tr / 3 * np.eye(3)) / (2 * G)


def energy_density(stress: np.ndarray, K: float, G: float) -> np.ndarray:
    """½ σ:C⁻¹:σ, shape=(n, 3, 3) → shape=(n,)."""
    return 0.5 * np.sum(stress * compliance(stress, K, G), axis=(1, 2))


def elastic_tangent(K: float, G: float) -> np.ndarray:
    """C = K I⊗I + 2G (𝕀ˢʸᵐ − I⊗I/3), shape=(3, 3, 3, 3)."""
    eye = np.eye(3)
    ii = np.einsum("ij,kl->ijkl", eye, eye)
    sym = 0.5 * (np.einsum("ik,jl->ijkl", eye, eye) + np.einsum("il,jk->ijkl", eye, eye))
    return K * ii + 2 * G * (sym - ii / 3)


def to_voigt(tangent: np.ndarray) -> np.ndarray:
    """A minor-symmetric tangent in Voigt form, shape=(n, 3, 3, 3, 3) → shape=(n, 6, 6).

    Rows and columns in :data:`VOIGT` order; with engineering shear strains
    (γ_xy = 2ε_xy) the entries are the tensor components, D[I, J] = C[i, j, k, l].
    Plane strain takes rows and columns (0, 1, 5).
    """
    rows = [i for i, _ in VOIGT]
    cols = [j for _, j in VOIGT]
    return tangent[:, rows, cols][:, :, rows, cols]


class ElasticTrial:
    """What every law shares: the common parameter checks, moduli, the trial, the update.

    A law (a frozen dataclass with ``E`` and ``nu``) inherits these and implements
    :meth:`return_map`.
    """

    E: float
    nu: float
    friction_angle: float
    dilatancy_angle: float
    cohesion: float

    def check_common(self) -> None:
        """Check the parameters every law has (E, ν, φ, ψ, c).

        Raises:
            ValueError: naming the parameter out of its range.
        """
        if not self.E > 0 or not -1 < self.nu < 0.5:
            raise ValueError(f"need E > 0 and -1 < nu < 0.5, got E={self.E}, nu={self.nu}")
        if (
            not 0 <= self.friction_angle < 90
            or not 0 <= self.dilatancy_angle <= self.friction_angle
        ):
            raise ValueError("need 0 <= dilatancy_angle <= friction_angle < 90 (degrees)")
        if self.cohesion < 0:
            raise ValueError(f"cohesion must be >= 0, got {self.cohesion}")

    def moduli(self) -> tuple[float, float]:
        """(bulk modulus K, shear modulus G) (:func:`geofrac.materials.bulk_shear`)."""
        return bulk_shear(self.E, self.nu)

    def trial(self, stress: np.ndarray, deps: np.ndarray) -> np.ndarray:
        """The elastic trial σ + C:Δε, shapes=(n, 3, 3) → shape=(n, 3, 3)."""
        K, G = self.moduli()
        return elastic_trial(stress, deps, K=K, G=G)

    def update(self, stress: np.ndarray, deps: np.ndarray, *, tangent: bool = False) -> Return:
        """Elastic trial and return for strain increments, shapes=(n, 3, 3)."""
        return self.return_map(self.trial(stress, deps), tangent=tangent)

    def return_map(self, trial: np.ndarray, *, tangent: bool = False) -> Return:
        """Return mapping of elastic trial stresses, shape=(n, 3, 3) (the law's own)."""
        raise NotImplementedError
