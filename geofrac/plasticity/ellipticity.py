"""Loss of ellipticity of a tangent: the acoustic tensor's determinant (pure numpy).

A tangent D (dσ = D : dε) is strongly elliptic in the direction n when the acoustic
tensor Q(n)ᵢₖ = nⱼ Dᵢⱼₖₗ nₗ is non-singular; where det Q(n) <= 0 for some n the rate
problem admits a discontinuous velocity gradient across a plane of normal n (a shear
band; Hill (1962), Rudnicki and Rice (1975)), its solution need not be unique, and a
mesh-independent answer is not to be expected. Elastic, det Q = μ (λ + 2μ) for every n.
Perfect plasticity with associated flow stays on the border (min det Q = 0 up to
round-off at the slip directions); non-associated flow (ψ < φ) crosses it: det Q < 0 in
a fan of directions at every plastic point (Rudnicki and Rice's critical hardening
modulus is positive there). docs/plasticity.md, "Zero dilatancy on fine meshes",
measures what it does to Newton's method.
"""

from __future__ import annotations

import numpy as np

__all__ = ["acoustic_determinant", "directions", "lost_ellipticity"]


def directions(dim: int, count: int = 180) -> np.ndarray:
    """Unit normals sampling the half circle (dim 2) or the half sphere (dim 3).

    Returns:
        shape=(count, dim); dim 2: angles kπ/count; dim 3: a Fibonacci lattice of the
        upper hemisphere.
    """
    if dim == 2:
        theta = np.pi * np.arange(count) / count
        return np.stack([np.cos(theta), np.sin(theta)], axis=1)
    if dim != 3:
        raise ValueError(f"dim must be 2 or 3, got {dim}")
    k = np.arange(count) + 0.5
    z = k / count
    phi = np.pi * (1 + 5**0.5) * k
    r = np.sqrt(1 - z * z)
    return np.stack([r * np.cos(phi), r * np.sin(phi), z], axis=1)


def acoustic_determinant(tangent: np.ndarray, normals: np.ndarray) -> np.ndarray:
    """The acoustic determinant det Q(n) of every tangent and normal.

    Args:
        tangent: fourth-order tangents, shape=(m, 3, 3, 3, 3).
        normals: unit normals, shape=(k, dim) (dim 2: the plane (x, y) of a plane
            strain problem, Q restricted to the in-plane components).

    Returns:
        shape=(m, k).
    """
    dim = normals.shape[1]
    D = tangent[:, :dim, :dim, :dim, :dim]
    Q = np.einsum("aj,pijkl,al->paik", normals, D, normals, optimize=True)
    return np.linalg.det(Q)


def lost_ellipticity(
    tangent: np.ndarray, *, shear_modulus: float, dim: int = 2, tolerance: float = 1e-6
) -> np.ndarray:
    """Which tangents have det Q(n) < −tolerance · G^dim for a sampled n, shape=(m,) bool.

    The scale G^dim is that of the elastic det Q (G (λ + 2G) in 2D, G² (λ + 2G) in 3D);
    ``tolerance`` keeps an associated material on the border (round-off of order 1e-12
    G^dim) from counting. In plane strain (dim 2) only in-plane normals count: a band
    whose normal leaves the plane cannot form when nothing varies along z.

    Args:
        tangent: shape=(m, 3, 3, 3, 3).
        shear_modulus: G, the scale.
        dim: 2 (in-plane normals, plane strain) or 3.
        tolerance: relative to G^dim.
    """
    if len(tangent) == 0:
        return np.zeros(0, dtype=bool)
    det = acoustic_determinant(tangent, directions(dim))
    return det.min(axis=1) < -tolerance * shear_modulus**dim
