"""The 1D bar benchmarks of Edo (2016), §4.5.1-4.5.3: quasi-static, impact, translating.

After Bardenhagen and Kober (GIMP, 2004), as Edo (2016) sets it up: E = 1e6, ρ₀ = 1,
L₀ = 50, A = 1, 100 particles (two per cell), cell 1.0, Courant number 0.1 (Δt = 1e-4),
the base x = 0 fixed, gravity b with W = ρ₀|b|L₀. Gravity acts from t = 0; at
t = L₀/c the compression wave from the base has crossed the bar once and, for a linear
bar, leaves exactly the static stress behind it with the bar at rest, which is why the
thesis compares at that time. The reference is eq. 4.73,

    σ(x) = E (√(1 − 2ρ₀|b|(Δ − x)/E) − 1),   Δ = L₀ − ρ₀|b|L₀²/(2E)   (4.74),

the equilibrium of σ = E (λ − 1) in the deformed bar (λ the stretch); at W = 1000 the
strains are 1e-3 and the hypoelastic update differs from that law by ~1e-6 relative.

The bar with an initial velocity (4.5.2, Fig. 4.16-4.18): the same bar without gravity,
moving towards its fixed base at v₀ = c/50. A compression wave runs up from the base;
behind it the bar is at rest with the stress of eq. 4.75, σ = E((ct − v₀t)/(ct) − 1) =
−E v₀/c (the stretch 1 − v₀/c). The thesis compares when the wave has run through 80 % of
the bar, t = 0.8 L₀/c.

The translating bar (4.5.3) is a scene, ``jobs/mpm_translating_bar.toml``, run by
:func:`geofrac.bench.mpm.translating_bar` (it loads the scene file, so it lives with the
benchmarks, above this engine).
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from geofrac.mpm import shapes
from geofrac.mpm.elastic import Elastic
from geofrac.mpm.grid import grid
from geofrac.mpm.particles import lattice
from geofrac.mpm.schemes import StepSettings, step, time_step

__all__ = [
    "BarResult",
    "ImpactResult",
    "impact_bar",
    "quasi_static_bar",
    "self_weight_displacement",
    "self_weight_stress",
]


def self_weight_stress(x: np.ndarray, *, E: float, rho0: float, b: float, L0: float) -> np.ndarray:
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


def self_weight_displacement(X: float, *, E: float, rho0: float, b: float, L0: float) -> float:
    """The displacement at rest of the material point at height ``X`` of the bar of eq. 4.73.

    u(X) = −ρ₀ b (L₀ X − X²/2) / E: the weight above X, ρ₀ b (L₀ − X), stretches dX by
    λ − 1 = σ/E; at the top, u(L₀) = Δ − L₀ of eq. 4.74.

    Args:
        X: the point's height before loading, 0 <= X <= L0 (the base at 0).
        E: Young's modulus.
        rho0: initial density.
        b: magnitude of the body force per mass (downwards).
        L0: initial length.
    """
    return -rho0 * b * (L0 * X - X * X / 2.0) / E


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
    *,
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
    p = lattice([0.0], [n], h, density=rho0)
    g = grid([-2.0 * cell], cell, [int(np.ceil(L0 / cell)) + 6])
    mat = Elastic(E)
    dt = time_step(courant, cell, mat, density=rho0, dim=1)
    fixed = (g.nodes() <= 0.0).reshape(-1, 1)
    s = StepSettings(scheme, shapes.get(shape), dt, np.array([-b]), fixed)
    steps = round(L0 / mat.wave_speed(rho0, 1) / dt)
    t0 = time.perf_counter()
    for _ in range(steps):
        step(g, p, mat, settings=s)
    seconds = time.perf_counter() - t0
    x, stress = p.x[:, 0].copy(), p.stress[:, 0, 0].copy()
    exact = self_weight_stress(x, E=E, rho0=rho0, b=b, L0=L0)
    error = float(np.sqrt(np.mean((stress - exact) ** 2)) / (rho0 * b * L0))
    return BarResult(x, stress, exact, error, steps, seconds)


@dataclass(frozen=True)
class ImpactResult:
    """A run of the bar with an initial velocity (4.5.2).

    Attributes:
        x0: initial particle positions, shape=(n,).
        stress: particle stresses σ_xx normalised by eq. 4.75, shape=(n,).
        error: RMS of (σ/σ₇₅ − 1) over the particles the wave has passed by a margin
            (initial position below 0.7 L₀; the front, at 0.8 L₀, is smeared over cells).
        overshoot: the largest |σ/σ₇₅| over the whole bar.
        steps: time steps taken.
        seconds: wall time of the steps.
    """

    x0: np.ndarray
    stress: np.ndarray
    error: float
    overshoot: float
    steps: int
    seconds: float


def impact_bar(
    shape: str, scheme: str = "musl", smoothing: float | None = None, *, n: int = 100
) -> ImpactResult:
    """Run the bar of Edo (2016), §4.5.2 to t = 0.8 L₀/c; compare with eq. 4.75."""
    E, rho0, L0, cell = 1e6, 1.0, 50.0, 1.0
    h = L0 / n
    p = lattice([0.0], [n], h, density=rho0)
    x0 = p.x[:, 0].copy()
    mat = Elastic(E)
    c = mat.wave_speed(rho0, 1)
    v0 = c / 50
    p.v[:] = -v0
    g = grid([-2.0 * cell], cell, [round(L0 / cell) + 6])
    dt = time_step(0.1, cell, mat, density=rho0, dim=1)
    fixed = (g.nodes() <= 0.0).reshape(-1, 1)
    s = StepSettings(scheme, shapes.get(shape), dt, np.zeros(1), fixed, smoothing)
    steps = round(0.8 * L0 / c / dt)
    t0 = time.perf_counter()
    for _ in range(steps):
        step(g, p, mat, settings=s)
    seconds = time.perf_counter() - t0
    exact = E * ((c * 1.0 - v0 * 1.0) / (c * 1.0) - 1)  # eq. 4.75 (independent of t)
    ratio = p.stress[:, 0, 0] / exact
    behind = x0 < 0.7 * L0
    error = float(np.sqrt(np.mean((ratio[behind] - 1.0) ** 2)))
    return ImpactResult(x0, ratio, error, float(np.max(np.abs(ratio))), steps, seconds)
