"""Particle state of the MPM (Edo (2016), eqs. 4.7-4.11)."""

from __future__ import annotations

from dataclasses import dataclass, field, fields

import numpy as np

__all__ = ["Particles", "concat", "lattice", "particles", "take"]


@dataclass
class Particles:
    """Material points; arrays are updated in place by the schemes.

    Attributes:
        x: positions, shape=(n, dim).
        v: velocities, shape=(n, dim).
        mass: m_p, shape=(n,).
        volume: V_p (current), shape=(n,).
        stress: Cauchy stress σ_p, shape=(n, dim, dim).
        F: deformation gradient G_p (eq. 4.70), shape=(n, dim, dim).
        lp0: initial GIMP half-widths l_p⁰, shape=(n, dim).
        lp: current half-widths (= lp0 except for ``cpgimp``), shape=(n, dim).
        stress_zz: out-of-plane stress σ_zz of plane strain (2D; zero otherwise),
            shape=(n,).
        plastic: accumulated plastic multiplier Σ Δλ (``plasticity``), shape=(n,).
        ids: global particle ids (kept when particles move between MPI ranks), int64,
            shape=(n,); ``arange(n)`` when not given.
    """

    x: np.ndarray
    v: np.ndarray
    mass: np.ndarray
    volume: np.ndarray
    stress: np.ndarray
    F: np.ndarray
    lp0: np.ndarray
    lp: np.ndarray
    stress_zz: np.ndarray
    plastic: np.ndarray
    ids: np.ndarray = field(default=None)  # type: ignore[arg-type]  # None: numbered in __post_init__

    def __post_init__(self) -> None:
        """Number the particles 0 … n−1 unless ids were given."""
        if self.ids is None:
            self.ids = np.arange(len(self.x), dtype=np.int64)

    @property
    def n(self) -> int:
        """Number of particles."""
        return len(self.x)

    @property
    def dim(self) -> int:
        """Spatial dimension."""
        return self.x.shape[1]

    @property
    def density(self) -> np.ndarray:
        """ρ_p = m_p / V_p (eq. 4.9), shape=(n,)."""
        return self.mass / self.volume

    def kinetic_energy(self) -> float:
        """Σ ½ m_p |v_p|²."""
        return 0.5 * float(np.sum(self.mass * np.sum(self.v**2, axis=1)))

    def momentum(self) -> np.ndarray:
        """Σ m_p v_p, shape=(dim,)."""
        return self.mass @ self.v

    def state(self) -> dict[str, np.ndarray]:
        """Every array of the particles by field name (a checkpoint's content; not copies).

        This is the whole state a step carries to the next: the schemes, plasticity,
        smoothing and friction keep nothing else between steps.
        """
        return {f.name: getattr(self, f.name) for f in fields(Particles)}

    @classmethod
    def from_state(cls, arrays: dict[str, np.ndarray]) -> Particles:
        """The particles of :meth:`state`'s arrays (copied, in their order).

        Raises:
            ValueError: an array is missing or the arrays disagree in length.
        """
        names = [f.name for f in fields(Particles)]
        missing = [n for n in names if n not in arrays]
        if missing:
            raise ValueError(f"particle arrays {missing} are missing")
        lengths = {n: len(arrays[n]) for n in names}
        if len(set(lengths.values())) > 1:
            raise ValueError(f"particle arrays of different lengths: {lengths}")
        return cls(**{n: np.array(arrays[n], order="C") for n in names})


def particles(
    x: np.ndarray, volume: np.ndarray, density: np.ndarray | float, *, lp0: np.ndarray
) -> Particles:
    """Particles at rest and stress-free.

    Args:
        x: positions, shape=(n, dim).
        volume: initial volumes, shape=(n,).
        density: initial density ρ_p, shape=(n,) or one number.
        lp0: initial GIMP half-widths, shape=(n, dim) (half the particle spacing).
    """
    x = np.array(x, dtype=float)
    n, dim = x.shape
    vol = np.array(volume, dtype=float).reshape(n)
    if np.any(vol <= 0):
        raise ValueError("particles: every volume must be > 0")
    rho = np.broadcast_to(np.asarray(density, dtype=float), (n,))
    if np.any(rho <= 0):
        raise ValueError("particles: every density must be > 0")
    lp0 = np.array(lp0, dtype=float).reshape(n, dim)
    return Particles(
        x=x,
        v=np.zeros((n, dim)),
        mass=rho * vol,
        volume=vol.copy(),
        stress=np.zeros((n, dim, dim)),
        F=np.broadcast_to(np.eye(dim), (n, dim, dim)).copy(),
        lp0=lp0,
        lp=lp0.copy(),
        stress_zz=np.zeros(n),
        plastic=np.zeros(n),
        ids=np.arange(n, dtype=np.int64),
    )


def take(p: Particles, index: np.ndarray) -> Particles:
    """The particles selected by ``index`` (a boolean mask or ids into p), as copies.

    Args:
        p: particles.
        index: shape=(n,) bool or shape=(k,) int.
    """
    return Particles(**{f.name: getattr(p, f.name)[index] for f in fields(Particles)})


def concat(parts: list[Particles], dim: int) -> Particles:
    """The particles of ``parts`` one after the other (none: an empty set of ``dim``)."""
    if not parts:
        empty = particles(np.zeros((0, dim)), np.zeros(0), 1.0, lp0=np.zeros((0, dim)))
        return empty
    return Particles(
        **{f.name: np.concatenate([getattr(q, f.name) for q in parts]) for f in fields(Particles)}
    )


def lattice(
    lower: np.ndarray | list[float], counts: list[int], spacing: float, *, density: float
) -> Particles:
    """Particles filling a box on a regular lattice, one per lattice cell, at its centre.

    Each particle has the volume spacing**dim and the GIMP half-width spacing/2 (the
    particles tile the box).

    Args:
        lower: the box's lowest corner, shape=(dim,).
        counts: particles per direction, shape=(dim,).
        spacing: the lattice spacing (e.g. half the grid cell for two per cell).
        density: initial density.
    """
    lo = np.asarray(lower, dtype=float).reshape(-1)
    axes = [lo[a] + (np.arange(n) + 0.5) * spacing for a, n in enumerate(counts)]
    x = np.stack([m.ravel() for m in np.meshgrid(*axes, indexing="ij")], axis=1)
    n = len(x)
    return particles(x, np.full(n, spacing ** len(lo)), density, lp0=np.full(x.shape, spacing / 2))
