"""Stress invariants and principal stresses of arrays of 3×3 stresses (pure numpy).

Tension is positive. Every function takes stresses of shape=(n, 3, 3) (plane strain keeps
σ_zz) and works on all n points at once.
"""

from __future__ import annotations

import numpy as np

__all__ = ["deviator", "first_invariant", "principal", "sqrt_j2"]


def first_invariant(stress: np.ndarray) -> np.ndarray:
    """I₁ = tr σ (Edo (2016), eq. 4.40), shape=(n, 3, 3) → shape=(n,)."""
    return np.trace(stress, axis1=1, axis2=2)


def deviator(stress: np.ndarray) -> np.ndarray:
    """The deviator s = σ − (I₁/3) I, shape=(n, 3, 3) → shape=(n, 3, 3)."""
    return stress - first_invariant(stress)[:, None, None] / 3 * np.eye(3)


def sqrt_j2(stress: np.ndarray) -> np.ndarray:
    """√J₂ with J₂ = ½ s:s (Edo (2016), eq. 4.41), shape=(n, 3, 3) → shape=(n,)."""
    s = deviator(stress)
    return np.sqrt(0.5 * np.sum(s * s, axis=(1, 2)))


def principal(stress: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Principal stresses, largest first, and their directions.

    Args:
        stress: symmetric stresses, shape=(n, 3, 3).

    Returns:
        values σ₁ ≥ σ₂ ≥ σ₃, shape=(n, 3), and the unit directions as columns,
        shape=(n, 3, 3) (``vectors[:, :, i]`` belongs to ``values[:, i]``), so that
        σ = V diag(values) Vᵀ.
    """
    values, vectors = np.linalg.eigh(stress)
    return values[:, ::-1].copy(), vectors[:, :, ::-1].copy()
