"""The seed's 1D bar benchmarks (4.5.1): the quasi-static bar under its own weight.

After Bardenhagen and Kober (GIMP, 2004), as the seed sets it up: E = 1e6, ρ₀ = 1,
L₀ = 50, A = 1, 100 particles (two per cell), cell 1.0, Courant number 0.1 (Δt = 1e-4),
the base x = 0 fixed, gravity b with W = ρ₀|b|L₀. Gravity acts from t = 0; at
t = L₀/c the compression wave from the base has crossed the bar once and, for a linear
bar, leaves exactly the static stress behind it with the bar at rest, which is why the
seed compares at that time. The reference is eq. 4.73,

    σ(x) = E (√(1 − 2ρ₀|b|(Δ − x)/E) − 1),   Δ = L₀ − ρ₀|b|L₀²/(2E)   (4.74),

the equilibrium of σ = E (λ − 1) in the deformed bar (λ the stretch); at W = 1000 the
strains are 1e-3 and the hypoelastic update differs from that law by ~1e-6 relative.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from geofrac.mpm.grid import grid
from geofrac.mpm.particles import particles
from geofrac.mpm.schemes import Elastic, StepSettings, step, time_step

__all__ = ["BarResult", "quasi_static_bar", "self_weight_stress"]


def self_weight_stress(x: np.ndarray, E: float, rho0: float, b: float, L0: float) -> np.ndarray:
    """Eqs. 4.73-4.74: axial stress at current heights x of a bar on a fixed base.

    Args:
        x: heights, 0 <= x <= Δ, shape=(n,).
        E: Young's modulus.
        rho0: initial density.
        b: magnitude of the body force per mass (downwards).
        L0: initial length.
    """
    delta = L0 - rho0 * b * L0**2 / (2 * E)
    return E * (np.sqrt(1 - 2 * rho0 * b * (delta - x) / E) - 1)


@dataclass(frozen=True)
class BarResult:
    """A quasi-static bar run.

    Attributes:
        x: final particle heights, shape=(n,).
        stress: particle stresses σ_xx, shape=(n,).
        exact: eq. 4.73 at x, shape=(n,).
        error: RMS of (stress − exact) over the particles divided by ρ₀|b|L₀.
        steps: time steps taken.
        seconds: wall time of the steps.
    """

    x: np.ndarray
    stress: np.ndarray
    exact: np.ndarray
    error: float
    steps: int
    seconds: float


def quasi_static_bar(
    shape: str,
    scheme: str,
    W: float = 1000.0,
    E: float = 1e6,
    rho0: float = 1.0,
    L0: float = 50.0,
    n: int = 100,
    cell: float = 1.0,
    courant: float = 0.1,
) -> BarResult:
    """Run the bar to t = L₀/c with one shape and scheme; compare with eq. 4.73."""
    b = W / (rho0 * L0)
    h = L0 / n
    p = particles((np.arange(n) + 0.5)[:, None] * h, np.full(n, h), rho0, np.full((n, 1), h / 2))
    g = grid([-2.0 * cell], cell, [int(np.ceil(L0 / cell)) + 6])
    mat = Elastic(E)
    dt = time_step(courant, cell, mat, rho0, 1)
    fixed = (g.nodes() <= 0.0).reshape(-1, 1)
    s = StepSettings(scheme, shape, dt, np.array([-b]), fixed)
    steps = round(L0 / mat.wave_speed(rho0, 1) / dt)
    t0 = time.perf_counter()
    for _ in range(steps):
        step(g, p, mat, s)
    seconds = time.perf_counter() - t0
    x, stress = p.x[:, 0].copy(), p.stress[:, 0, 0].copy()
    exact = self_weight_stress(x, E, rho0, b, L0)
    error = float(np.sqrt(np.mean((stress - exact) ** 2)) / (rho0 * b * L0))
    return BarResult(x, stress, exact, error, steps, seconds)
