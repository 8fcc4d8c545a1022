"""The 3D network: planar disc fractures by centre, unit normal and radius (pure numpy).

A :class:`DiscNetwork` is what the samplers (:mod:`geofrac.dfn3d.sampling`) and readers
(:mod:`geofrac.dfn3d.io`) make and what the cleaning (:mod:`geofrac.dfn3d.clean`) and the
mesher (:mod:`geofrac.meshing.dfn3d`) take. Each fracture is the disc of its radius about
its centre in the plane through the centre normal to its normal (its pole); the normal is
an axis (n and −n are the same fracture) and is stored with n_z >= 0 (n_y > 0, then
n_x > 0, on a vertical fracture).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["DiscNetwork", "canonical_normals", "pole_to_normal"]

#: |n_z| (and then |n_y|) below which a unit normal counts as horizontal for the sign rule.
HORIZONTAL = 1e-12


def pole_to_normal(trend_deg: np.ndarray | float, plunge_deg: np.ndarray | float) -> np.ndarray:
    """Unit vectors of poles given by trend (clockwise from north, +y) and plunge (down).

    Returns:
        (sin t cos p, cos t cos p, −sin p), shape=(n, 3) (n = 1 for scalars).
    """
    t = np.radians(np.atleast_1d(np.asarray(trend_deg, dtype=float)))
    p = np.radians(np.atleast_1d(np.asarray(plunge_deg, dtype=float)))
    return np.stack([np.sin(t) * np.cos(p), np.cos(t) * np.cos(p), -np.sin(p)], axis=1)


def canonical_normals(normals: np.ndarray) -> np.ndarray:
    """Unit normals with the sign rule: n_z > 0, else n_y > 0, else n_x > 0.

    Args:
        normals: nonzero vectors, shape=(n, 3).

    Returns:
        the unit normals, shape=(n, 3).

    Raises:
        ValueError: a normal is zero or not finite.
    """
    n = np.asarray(normals, dtype=float).reshape(-1, 3)
    length = np.linalg.norm(n, axis=1)
    if not np.all(np.isfinite(length)) or np.any(length <= 0):
        raise ValueError("every fracture normal must be a finite nonzero vector")
    n = n / length[:, None]
    flip = (n[:, 2] < -HORIZONTAL) | (
        (np.abs(n[:, 2]) <= HORIZONTAL)
        & ((n[:, 1] < -HORIZONTAL) | ((np.abs(n[:, 1]) <= HORIZONTAL) & (n[:, 0] < 0)))
    )
    n[flip] *= -1.0
    return n


@dataclass(frozen=True)
class DiscNetwork:
    """Planar disc fractures.

    Attributes:
        centre: the discs' centres, shape=(n, 3).
        normal: unit normals (poles) with the sign rule of :func:`canonical_normals`,
            shape=(n, 3).
        radius: the radii, > 0, shape=(n,).
        set_index: index into ``set_names`` of each fracture, shape=(n,).
        set_names: the fracture sets' names.
    """

    centre: np.ndarray
    normal: np.ndarray
    radius: np.ndarray
    set_index: np.ndarray
    set_names: tuple[str, ...]

    def __post_init__(self) -> None:  # noqa: D105
        n = len(self.radius)
        if (
            self.centre.shape != (n, 3)
            or self.normal.shape != (n, 3)
            or self.set_index.shape != (n,)
        ):
            raise ValueError(
                f"a network of {n} fractures needs centre and normal of shape ({n}, 3) and "
                f"set_index of shape ({n},), got {self.centre.shape}, {self.normal.shape}, "
                f"{self.set_index.shape}"
            )
        if n and (self.set_index.min() < 0 or self.set_index.max() >= len(self.set_names)):
            raise ValueError("a fracture's set index names no set")
        if not (np.all(np.isfinite(self.centre)) and np.all(np.isfinite(self.radius))):
            raise ValueError("fracture centres and radii must be finite")
        if np.any(self.radius <= 0):
            raise ValueError("fracture radii must be > 0")

    @property
    def size(self) -> int:
        """The number of fractures."""
        return len(self.radius)

    def subset(self, keep: np.ndarray) -> DiscNetwork:
        """The fractures where ``keep`` (a boolean mask or indices), same sets."""
        return DiscNetwork(
            self.centre[keep],
            self.normal[keep],
            self.radius[keep],
            self.set_index[keep],
            self.set_names,
        )

    def area(self) -> np.ndarray:
        """The discs' full areas π r², shape=(n,)."""
        return np.pi * self.radius**2
