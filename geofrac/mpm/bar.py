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

The translating bar (4.5.3, Fig. 4.19-4.21): length 5, E = 500, ρ = 1, centred at
x = 25 in a box 0 … 50 with walls (fixed nodes) at both ends, initial velocity 2.0, cell
0.5, Courant number 0.1; it flies, hits a wall, bounces, and so on. The energies
(kinetic, strain, total) are normalised by the initial (kinetic) energy; without
dissipation the total should stay 1. The thesis does not give the particle count; we use
two per cell (20), as in the quasi-static bar.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from geofrac.mpm.elastic import Elastic
from geofrac.mpm.grid import grid
from geofrac.mpm.particles import lattice
from geofrac.mpm.schemes import StepSettings, step, time_step

__all__ = [
    "TRANSLATING_SCENE",
    "BarResult",
    "EnergyHistory",
    "ImpactResult",
    "impact_bar",
    "quasi_static_bar",
    "self_weight_stress",
    "translating_bar",
    "translating_overrides",
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
    s = StepSettings(scheme, shape, dt, np.array([-b]), fixed)
    steps = round(L0 / mat.wave_speed(rho0, 1) / dt)
    t0 = time.perf_counter()
    for _ in range(steps):
        step(g, p, mat, settings=s)
    seconds = time.perf_counter() - t0
    x, stress = p.x[:, 0].copy(), p.stress[:, 0, 0].copy()
    exact = self_weight_stress(x, E=E, rho0=rho0, b=b, L0=L0)
    error = float(np.sqrt(np.mean((stress - exact) ** 2)) / (rho0 * b * L0))
    return BarResult(x, stress, exact, error, steps, seconds)


#: The translating bar's scene: the bench runs it (with overrides), as ``geofrac run`` does.
TRANSLATING_SCENE = Path(__file__).resolve().parents[2] / "jobs" / "mpm_translating_bar.toml"


@dataclass(frozen=True)
class EnergyHistory:
    """Energies of a translating-bar run, normalised by the initial energy.

    Attributes:
        t: times, shape=(k,).
        kinetic: shape=(k,).
        strain: ½ V σ : D⁻¹ : σ, shape=(k,).
        total: kinetic + strain, shape=(k,).
        drift_max: max |E(t) − E₀| / E₀ over the run (every step), E = kinetic + strain.
        finite: the run ended without a non-finite state.
        steps: time steps taken.
        seconds: wall time of the steps.
        particles: number of particles.
        stored_work: the stored energy as stress work W (:mod:`~geofrac.mpm.energy`),
            shape=(k,).
        drift_work_max: max |K + W − E₀| / E₀ over the run (every step).
        budget: the cumulative budget terms of :data:`~geofrac.mpm.energy.COLUMNS`
            normalised by E₀, name -> shape=(k,).
        closure_max: the budget's largest closure error over E₀ (round-off).
    """

    t: np.ndarray
    kinetic: np.ndarray
    strain: np.ndarray
    total: np.ndarray
    drift_max: float
    finite: bool
    steps: int
    seconds: float
    particles: int
    stored_work: np.ndarray
    drift_work_max: float
    budget: dict[str, np.ndarray]
    closure_max: float


def translating_overrides(
    shape: str,
    scheme: str,
    smoothing: float | None,
    *,
    t_end: float,
    smoothing_kind: str = "standard",
) -> list[str]:
    """The ``--set`` overrides of :data:`TRANSLATING_SCENE` for one variant."""
    sets = [f"mpm.shape={shape}", f"mpm.scheme={scheme}", f"mpm.t_end={t_end!r}"]
    if smoothing is not None:
        sets += [
            'effects=["mls_smoothing"]',
            f"mls_smoothing.radius={smoothing!r}",
            f"mls_smoothing.kind={smoothing_kind}",
        ]
    return sets


def translating_bar(
    shape: str,
    scheme: str = "musl",
    smoothing: float | None = None,
    *,
    t_end: float = 100.0,
    steps: int | None = None,
    samples: int = 2000,
    smoothing_kind: str = "standard",
) -> EnergyHistory:
    """Run the translating bar of Edo (2016), §4.5.3 to ``t_end`` (or for ``steps`` steps).

    The scene ``jobs/mpm_translating_bar.toml`` with :func:`translating_overrides`, on one
    process, stepped by :func:`geofrac.mpm.driver.advance`: the same grid, walls, time
    step and energies as ``geofrac run jobs/mpm_translating_bar.toml --set ...``.

    Args:
        shape: shape functions.
        scheme: update scheme.
        smoothing: MLS radius factor (None: no smoothing).
        t_end: end time (Edo (2016), Fig. 4.21, runs to about 100).
        steps: run exactly this many steps of the Courant time step instead.
        samples: about this many energy samples are kept (the drifts use every step).
        smoothing_kind: ``standard`` (Edo (2016)'s) or ``consistent``
            (:data:`~geofrac.mpm.schemes.SMOOTHINGS`).
    """
    from mpi4py import MPI

    from geofrac.errors import RunError
    from geofrac.mpm.driver import advance, prepare, start_log
    from geofrac.scene import load_scene

    if steps is not None:  # the scene's rule dt = t_end / ceil(t_end / dt_courant)
        E, rho, cell = 500.0, 1.0, 0.5
        t_end = steps * time_step(0.1, cell, Elastic(E), density=rho, dim=1)
    scene = load_scene(
        TRANSLATING_SCENE,
        translating_overrides(shape, scheme, smoothing, t_end=t_end, smoothing_kind=smoothing_kind),
    )
    comm = MPI.COMM_SELF
    run = prepare(scene, comm)
    log = start_log(run, comm)
    e0 = log.e0
    every = max(1, run.steps // samples)
    rows = [[0.0, *log.first_row()]]
    finite = True
    k = 0
    t0 = time.perf_counter()
    try:
        for k in range(1, run.steps + 1):
            row = advance(run, comm, log, k=k)
            if k % every == 0 or k == run.steps:
                rows.append([k * run.settings.dt, *row])
    except RunError:
        finite = False
    seconds = time.perf_counter() - t0
    arr = np.array(rows)
    from geofrac.mpm.energy import COLUMNS, CSV_COLUMNS

    col = {name: i - 1 for i, name in enumerate(CSV_COLUMNS) if i >= 1}
    budget = {c: arr[:, col[c]] / e0 for c in COLUMNS}
    return EnergyHistory(
        t=arr[:, 0],
        kinetic=arr[:, col["kinetic"]] / e0,
        strain=arr[:, col["strain"]] / e0,
        total=arr[:, col["total"]] / e0,
        drift_max=float(log.drift_max) if finite else float("inf"),
        finite=finite,
        steps=k,
        seconds=seconds,
        particles=run.total,
        stored_work=budget["stored_work"],
        drift_work_max=float(log.drift_work_max) if finite else float("inf"),
        budget=budget,
        closure_max=log.closure / e0,
    )


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
    s = StepSettings(scheme, shape, dt, np.zeros(1), fixed, smoothing)
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
