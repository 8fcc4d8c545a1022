"""Davis's associated equivalent of a non-associated Mohr-Coulomb material (pure numpy).

With ψ < φ and perfect plasticity the consistent tangent loses ellipticity
(:mod:`geofrac.plasticity.ellipticity`): the rate problem is ill-posed, its solution need
not be unique, and Newton's method can stall on a fine mesh well below the collapse load
(docs/plasticity.md, "Zero dilatancy on fine meshes"). Davis (1968) replaced the
non-associated material, for plane-strain limit loads, by an *associated* one whose
strength on the velocity characteristics is that of the non-associated material's
shear bands:

    β = cos φ cos ψ / (1 − sin φ sin ψ),    c* = β c,    tan φ* = β tan φ,    ψ* = φ*,

used in strength reduction with the factored parameters (c/F, atan(tan φ/F), atan(tan ψ/F))
at each trial factor (Tschuchnigg, Schweiger and Sloan (2015), Computers and
Geotechnics 70, "Davis approach B"). β = 1 for ψ = φ (the material is unchanged); for
ψ = 0, β = cos φ. The tension cut-off T is kept (c* cot φ* = c cot φ, so T stays within
its bound). The result is an approximation of the non-associated limit load, on the
safe side for the cases Tschuchnigg et al. compared with finite-element limit analysis.

:class:`Davis` holds the *given* (c, φ, ψ) as its fields, so
:func:`~geofrac.plasticity.strength_reduction.reduce_strength` reduces them like any
law's, and builds the associated law from them when it maps.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from geofrac.plasticity.drucker_prager import MATCHES, DruckerPrager
from geofrac.plasticity.elasticity import ElasticTrial
from geofrac.plasticity.mohr_coulomb import MohrCoulomb
from geofrac.plasticity.returns import Return

__all__ = ["Davis", "davis_factor"]


def davis_factor(friction_angle: float, dilatancy_angle: float) -> float:
    """β = cos φ cos ψ / (1 − sin φ sin ψ) (angles in degrees; 0 < β <= 1)."""
    phi, psi = math.radians(friction_angle), math.radians(dilatancy_angle)
    return math.cos(phi) * math.cos(psi) / (1.0 - math.sin(phi) * math.sin(psi))


@dataclass(frozen=True)
class Davis(ElasticTrial):
    """A law with the given (c, φ, ψ) that maps as Davis's associated equivalent.

    Attributes:
        E: Young's modulus.
        nu: Poisson's ratio.
        friction_angle: the given φ in degrees.
        cohesion: the given c.
        dilatancy_angle: the given ψ in degrees (0 <= ψ <= φ).
        law: ``"mohr_coulomb"`` or ``"drucker_prager"``, the surface of the equivalent.
        tension: Mohr-Coulomb's tension cut-off T, or None.
        match: Drucker-Prager's match.
    """

    E: float
    nu: float
    friction_angle: float
    cohesion: float = 0.0
    dilatancy_angle: float = 0.0
    law: str = "mohr_coulomb"
    tension: float | None = None
    match: str = "plane_strain"

    def __post_init__(self) -> None:
        """Check the parameters (the equivalent law checks the rest when built)."""
        self.check_common()
        if self.law not in ("mohr_coulomb", "drucker_prager"):
            raise ValueError(f"law must be mohr_coulomb or drucker_prager, got {self.law!r}")
        if self.law == "drucker_prager" and self.tension is not None:
            raise ValueError("a tension cut-off is Mohr-Coulomb's")
        if self.match not in MATCHES:
            raise ValueError(f"match must be one of {MATCHES}, got {self.match!r}")
        self.equivalent()

    @property
    def beta(self) -> float:
        """Davis's factor β of the given φ and ψ."""
        return davis_factor(self.friction_angle, self.dilatancy_angle)

    def equivalent(self) -> MohrCoulomb | DruckerPrager:
        """The associated law with c* = β c, tan φ* = β tan φ, ψ* = φ*."""
        beta = self.beta
        phi = math.degrees(math.atan(beta * math.tan(math.radians(self.friction_angle))))
        c = beta * self.cohesion
        if self.law == "mohr_coulomb":
            return MohrCoulomb(self.E, self.nu, phi, c, phi, self.tension)
        return DruckerPrager(self.E, self.nu, phi, c, phi, self.match)

    def return_map(self, trial: np.ndarray, *, tangent: bool = False) -> Return:
        """The equivalent law's return of trial stresses, shape=(n, 3, 3)."""
        return self.equivalent().return_map(trial, tangent=tangent)
