"""The Jaumann rotation of the stress over one step (Edo (2016), eqs. D.30-D.31).

Pure numpy: the numpy reference of every MPM constitutive model's stress update; the
compiled elastic update (:func:`geofrac.mpm.kernels.elastic_update`) does the same.
"""

from __future__ import annotations

import numpy as np

__all__ = ["rotate_stress", "spin_increment"]


def spin_increment(L: np.ndarray, dt: float) -> np.ndarray:
    """The spin increment Δω = Δt/2 (∂v_j/∂x_i − ∂v_i/∂x_j) (Edo (2016), eq. D.31).

    With L_ij = ∂v_i/∂x_j this is −Δt W, W = ½ (L − Lᵀ) the usual spin: a rigid
    rotation at rate ω about z has W = ω [[0, −1], [1, 0]].

    Args:
        L: velocity gradients ∇v, shape=(n, dim, dim).
        dt: the step of this update.

    Returns:
        shape=(n, dim, dim).
    """
    return -0.5 * dt * (L - np.swapaxes(L, 1, 2))


def rotate_stress(stress: np.ndarray, spin: np.ndarray) -> np.ndarray:
    """The Jaumann-rotated stress σ + σ Δω − Δω σ (Edo (2016), eq. D.30), before D : Δε is added.

    Applied to every 2D and 3D stress update, elastic and Drucker-Prager: a rigidly
    rotating body keeps its stress turning with it, σ = R σ₀ Rᵀ, to first order in Δt
    (explicit: over a rotation θ in steps of Δθ the deviator grows by about 2 θ Δθ
    relative, docs/mpm_physics.md).

    Args:
        stress: shape=(n, d, d).
        spin: Δω of :func:`spin_increment`, shape=(n, d, d).
    """
    return stress + np.matmul(stress, spin) - np.matmul(spin, stress)
