"""Small-strain linear elasticity in 2D (plane stress/strain) and 3D.

σ = 2μ ε + λ tr(ε) I, with λ the effective plane-stress value in 2D plane stress
(see :func:`geofrac.materials.lame`); the weak form is the stiffness of Edo (2016), eq. (2.4),
k = t ∫ Bᵀ D B dΩ, written as t ∫ σ(u) : ε(v) dΩ.
"""

from __future__ import annotations

from typing import Any

import ufl

__all__ = [
    "body_force_form",
    "energy_error_form",
    "epsilon",
    "l2_error_form",
    "sigma",
    "stiffness_form",
    "strain_energy_form",
    "stress_3d",
    "traction_form",
    "von_mises",
]


def epsilon(u: Any) -> Any:
    """Small strain tensor sym(∇u)."""
    return ufl.sym(ufl.grad(u))


def sigma(u: Any, lam: Any, mu: Any) -> Any:
    """Cauchy stress of displacement ``u``."""
    eps = epsilon(u)
    return 2.0 * mu * eps + lam * ufl.tr(eps) * ufl.Identity(len(u))


def stiffness_form(u: Any, v: Any, lam: Any, mu: Any, thickness: Any, dx: Any) -> Any:
    """Bilinear form t ∫ σ(u) : ε(v) dx (Edo (2016), eq. 2.4)."""
    return thickness * ufl.inner(sigma(u, lam, mu), epsilon(v)) * dx


def traction_form(v: Any, traction: Any, thickness: Any, ds: Any) -> Any:
    """Linear form t ∫ t̄ · v ds on a boundary measure."""
    return thickness * ufl.dot(traction, v) * ds


def body_force_form(v: Any, force: Any, thickness: Any, dx: Any) -> Any:
    """Linear form t ∫ b · v dx (force per unit volume)."""
    return thickness * ufl.dot(force, v) * dx


def strain_energy_form(u: Any, lam: Any, mu: Any, thickness: Any, dx: Any) -> Any:
    """Functional ½ t ∫ σ(u) : ε(u) dx."""
    return 0.5 * thickness * ufl.inner(sigma(u, lam, mu), epsilon(u)) * dx


def l2_error_form(u: Any, u_exact: Any, dx: Any) -> Any:
    """Functional ∫ (u - u_exact)·(u - u_exact) dx; its square root is Edo (2016), eq. (2.22)."""
    e = u - u_exact
    return ufl.inner(e, e) * dx


def energy_error_form(u: Any, u_exact: Any, lam: Any, mu: Any, dx: Any) -> Any:
    """Functional ∫ ½ (ε - ε_exact) : (σ - σ_exact) dx; its square root is Edo (2016), eq. (3.30b).

    ε_exact is the symmetric gradient of the exact displacement, equal to D⁻¹ σ_exact
    (Edo (2016), eq. 3.32) for an exact elasticity solution.
    """
    e = u - u_exact
    return 0.5 * ufl.inner(sigma(e, lam, mu), epsilon(e)) * dx


def stress_3d(stress: Any, stress_zz: Any = 0.0) -> Any:
    """Embed a 2×2 in-plane stress in 3×3 with out-of-plane ``stress_zz``; 3×3 passes through.

    ``stress_zz`` is 0 in plane stress and λ tr(ε) in plane strain.
    """
    if stress.ufl_shape == (3, 3):
        return stress
    return ufl.as_matrix(
        [
            [stress[0, 0], stress[0, 1], 0.0],
            [stress[1, 0], stress[1, 1], 0.0],
            [0.0, 0.0, stress_zz],
        ]
    )


def von_mises(stress: Any, stress_zz: Any = 0.0) -> Any:
    """Von Mises stress of a 2×2 (with out-of-plane ``stress_zz``) or 3×3 stress tensor."""
    s = ufl.dev(stress_3d(stress, stress_zz))
    return ufl.sqrt(1.5 * ufl.inner(s, s))
