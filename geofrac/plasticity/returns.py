"""The result of a return mapping and the codes of the returns (shared by every law).

A law's ``return_map(trial, tangent=...)`` gives a :class:`Return` for n points: the
stress, the plastic multipliers, the plastic strain increment, which return each point
took (:data:`NAMES`) and, on request, the consistent (algorithmic) tangent dσ/dε.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = [
    "APEX",
    "EDGE_COMPRESSION",
    "EDGE_EXTENSION",
    "ELASTIC",
    "NAMES",
    "SMOOTH",
    "TENSION",
    "TENSION_APEX",
    "TENSION_CORNER",
    "TENSION_EDGE",
    "TENSION_SHEAR",
    "Return",
]

#: The trial is admissible: σ = σ*.
ELASTIC = 0
#: The smooth part of the surface: the Drucker-Prager cone, the Mohr-Coulomb main plane.
SMOOTH = 1
#: Mohr-Coulomb edge σ₁ = σ₂ (the compression meridian; tension positive, σ₁ ≥ σ₂ ≥ σ₃).
EDGE_COMPRESSION = 2
#: Mohr-Coulomb edge σ₂ = σ₃ (the extension meridian).
EDGE_EXTENSION = 3
#: The apex of the cone or pyramid (hydrostatic, c cot φ; Drucker-Prager k/(3β)).
APEX = 4
#: The tension cut-off plane σ₁ = T.
TENSION = 5
#: The tension edge σ₁ = σ₂ = T.
TENSION_EDGE = 6
#: The line where the Mohr-Coulomb main plane meets σ₁ = T.
TENSION_SHEAR = 7
#: A corner of the cut-off on the Mohr-Coulomb surface (σ₁ = T with σ₂ = σ₃, or σ₁ = σ₂ = T).
TENSION_CORNER = 8
#: The vertex of the cut-off, σ₁ = σ₂ = σ₃ = T.
TENSION_APEX = 9

#: Readable name of each code.
NAMES = {
    ELASTIC: "elastic",
    SMOOTH: "smooth",
    EDGE_COMPRESSION: "edge_compression",
    EDGE_EXTENSION: "edge_extension",
    APEX: "apex",
    TENSION: "tension",
    TENSION_EDGE: "tension_edge",
    TENSION_SHEAR: "tension_shear",
    TENSION_CORNER: "tension_corner",
    TENSION_APEX: "tension_apex",
}


@dataclass(frozen=True)
class Return:
    """The return mapping of n elastic trial stresses.

    Attributes:
        stress: the returned stresses, shape=(n, 3, 3).
        multipliers: the plastic multipliers Δλ ≥ 0, shape=(n, m), one column per
            surface of the law (its ``SURFACES``); zero where a surface is inactive.
        plastic_strain: the plastic strain increment Δεᵖ = C⁻¹:(σ* − σ), shape=(n, 3, 3).
        kind: the return each point took (:data:`NAMES`), shape=(n,), int.
        tangent: the consistent tangent dσ/dΔε (Δε the strain increment of the trial),
            shape=(n, 3, 3, 3, 3), or None when not asked for.
    """

    stress: np.ndarray
    multipliers: np.ndarray
    plastic_strain: np.ndarray
    kind: np.ndarray
    tangent: np.ndarray | None = None
