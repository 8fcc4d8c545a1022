"""Elastic constants: Lamé parameters, bulk/shear and P-wave moduli, D matrices.

The one place that turns (E, ν) into other elastic constants (FEM, cracking, MPM
materials and the scene size estimate call it). Pure numpy. The D matrices use Voigt
order (xx, yy, xy) in 2D and (xx, yy, zz, yz, xz, xy) in 3D with engineering shear
strains, as in Edo (2016), eq. 2.4.
"""

from __future__ import annotations

import numpy as np

__all__ = ["bulk_shear", "d_matrix", "lame", "p_wave_modulus"]


def lame(E: float, nu: float, dim: int, *, plane: str = "stress") -> tuple[float, float]:
    """Return (λ, μ) such that σ = 2μ ε + λ tr(ε) I holds in the analysis plane.

    For 2D plane stress λ is the effective λ* = 2λμ/(λ + 2μ) = Eν/(1-ν²).
    """
    mu = E / (2.0 * (1.0 + nu))
    lam = E * nu / ((1.0 + nu) * (1.0 - 2.0 * nu))
    if dim == 2 and plane == "stress":
        lam = 2.0 * lam * mu / (lam + 2.0 * mu)
    return lam, mu


def bulk_shear(E: float, nu: float) -> tuple[float, float]:
    """Return (K, G): the bulk modulus E/(3(1-2ν)) and the shear modulus E/(2(1+ν)) (3D)."""
    return E / (3 * (1 - 2 * nu)), E / (2 * (1 + nu))


def p_wave_modulus(E: float, nu: float, dim: int) -> float:
    """The P-wave modulus M = λ + 2μ of 3D (and plane strain), E in 1D (a bar).

    An elastic wave runs at c = √(M/ρ) (the time step of eq. 4.72).
    """
    if dim == 1:
        return E
    lam, mu = lame(E, nu, 3)
    return lam + 2 * mu


def d_matrix(E: float, nu: float, dim: int, *, plane: str = "stress") -> np.ndarray:
    """Stress-strain matrix D in Voigt notation.

    Returns:
        D, shape=(3, 3) in 2D or (6, 6) in 3D.
    """
    lam, mu = lame(E, nu, dim, plane=plane)
    n = 3 if dim == 2 else 6
    D = np.zeros((n, n))
    D[:dim, :dim] = lam
    D[np.arange(dim), np.arange(dim)] += 2.0 * mu
    D[np.arange(dim, n), np.arange(dim, n)] = mu
    return D
