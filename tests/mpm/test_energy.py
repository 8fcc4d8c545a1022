"""The MPM energy budget (geofrac.mpm.energy), consistent smoothing, one answer per set-up.

Closure to round-off, closed forms, and the bench and the scene agreeing.
"""

import numpy as np
import pytest
from mpi4py import MPI

from geofrac.bench.mpm import TRANSLATING_SCENE, translating_bar, translating_overrides
from geofrac.mpm.driver import simulate
from geofrac.mpm.elastic import Elastic
from geofrac.mpm.energy import EnergyLog, StepBudget
from geofrac.mpm.grid import grid
from geofrac.mpm.particles import lattice
from geofrac.mpm.schemes import SCHEMES, StepSettings, step, strain_energy, time_step
from geofrac.scene import load_scene


def _block(scheme, shape="ugimp", smoothing=None, kind="standard", mu=0.3, backend="numba"):
    """A 2D elastic block thrown sideways onto a frictional floor beside a fixed wall."""
    cell = 0.5
    g = grid([-1.0, -1.0], cell, [16, 12])
    p = lattice([1.0, 0.0], [8, 6], cell / 2, density=1000.0)
    p.v[:] = [-4.0, -0.5]
    X = g.nodes()
    fixed = np.zeros((g.num_nodes, 2), dtype=bool)
    fixed[X[:, 0] <= 0.0] = True  # a fixed wall at x = 0, the block thrown at it
    friction = None
    floor = np.flatnonzero((X[:, 1] <= 0.0) & (X[:, 0] > 0.0))
    if mu is not None:
        from geofrac.mpm.friction import friction as make

        friction = make(floor, np.tile([0.0, -1.0], (len(floor), 1)), mu)
    else:
        fixed[floor, 1] = True
    mat = Elastic(1e6, 0.3)
    dt = time_step(0.2, cell, mat, density=1000.0, dim=2)
    s = StepSettings(
        scheme, shape, dt, np.array([0.0, -9.81]), fixed, smoothing, friction, backend,
        smoothing_kind=kind,
    )  # fmt: skip
    return g, p, mat, s


def _run(g, p, mat, s, steps):
    """Step with the budget; the energy log and the last row of ``energies.csv``."""
    log = EnergyLog(p.kinetic_energy(), strain_energy(p, mat))
    u0 = -float(p.mass @ (p.x @ s.gravity))
    row = log.first_row()
    for _ in range(steps):
        b = StepBudget()
        step(g, p, mat, settings=s, budget=b)
        pot = -float(p.mass @ (p.x @ s.gravity)) - u0
        row = log.record(p.kinetic_energy(), strain_energy(p, mat), pot, terms=b.terms())
    return log, row


@pytest.mark.parametrize("scheme", SCHEMES)
def test_the_budget_closes_with_gravity_a_wall_and_friction(scheme):
    """K + W + Π − E₀ = wall + friction + smoothing − plastic + numerical to round-off.

    Every term is computed from its own formula (the kinetic side from the grid update,
    the stored side from the stress updates), so the sum is a check of the identity in
    docs/mpm_energy.md, not a definition.
    """
    g, p, mat, s = _block(scheme, smoothing=2.0)
    log, _ = _run(g, p, mat, s, 150)
    b = log.budget
    assert log.closure < 1e-12 * log.scale
    assert b.friction_work < 0  # friction took energy out
    assert abs(b.wall_work) > 1e-6 * log.scale  # the block hit the wall
    assert abs(b.smoothing_work) > 1e-6 * log.scale


def test_the_budget_closes_on_the_numpy_reference_and_with_plasticity():
    from geofrac.mpm.plasticity import DruckerPrager

    g, p, _, s = _block("usavg", shape="mpm", backend="numpy", mu=None)
    mat = DruckerPrager(1e6, 0.3, 20.0, 0.0, 0.0)
    log, _ = _run(g, p, mat, s, 150)
    assert log.closure < 1e-12 * log.scale
    assert log.budget.plastic_dissipation > 0  # the cohesionless block yields on impact


def test_dropping_a_term_breaks_the_closure():
    """The closure can fail: without the smoothing term it is off by that term."""
    g, p, mat, s = _block("musl", smoothing=2.0)
    log, row = _run(g, p, mat, s, 100)
    b = log.budget
    total_work = row[-2]
    assert abs(total_work - log.e0 - b.explained()) < 1e-12 * log.scale
    assert abs(total_work - log.e0 - (b.explained() - b.smoothing_work)) > 1e3 * log.closure


def test_free_fall_loses_half_m_g2_dt_per_step_to_the_time_integration():
    """A block in free fall: K = ½ M (g t)² exactly, and Δt ½ M g² t is lost.

    No wall is reached. The symplectic Euler update x^{k+1} = x^k + Δt v^{k+1} loses
    ½ M g² Δt² per step, which the budget books as numerical work.
    """
    g, p, mat, s = _block("musl", mu=None)
    p.v[:] = 0.0
    p.x[:, 1] += 3.0  # well above the floor
    M, gmag, n = p.mass.sum(), 9.81, 200
    log, _ = _run(g, p, mat, s, n)
    t = n * s.dt
    assert p.kinetic_energy() == pytest.approx(0.5 * M * (gmag * t) ** 2, rel=1e-12)
    expected = -0.5 * M * gmag**2 * s.dt**2 * n
    assert log.budget.numerical_work == pytest.approx(expected, rel=1e-9)
    assert log.budget.wall_work == 0.0
    assert abs(log.budget.friction_work) < 1e-12 * log.scale


def test_the_stored_work_is_the_hypoelastic_bars_energy_at_the_impact():
    """The bar stopped against the wall holds K₀ as stress work W, 3 % more than ½Vσ²/E.

    At min K (t ≈ 11.3) the stress work W holds the initial kinetic energy (1D
    hypoelastic bar, σ = E ln λ: W = E V₀ (λ ln λ − λ + 1) = K₀), while ½ V σ²/E is at
    most λ ln²λ / (2 (λ ln λ − λ + 1)) = 0.9695 of it (uniform stress; less when the
    stress varies along the bar).
    """
    from scipy.optimize import brentq

    lam = brentq(lambda x: 500.0 * (x * np.log(x) - x + 1) - 2.0, 0.5, 0.9999)
    ratio = lam * np.log(lam) ** 2 / (2 * (lam * np.log(lam) - lam + 1))
    h = translating_bar("ugimp", "usavg", t_end=12.0, samples=10**6)
    k = int(np.argmin(np.where(h.t > 10.0, h.kinetic, np.inf)))
    assert h.kinetic[k] < 0.01
    assert h.kinetic[k] + h.stored_work[k] == pytest.approx(1.0, abs=0.005)
    assert h.kinetic[k] + h.strain[k] < ratio + 0.005


def test_consistent_smoothing_makes_the_grid_work_the_stress_work():
    """The adjoint forces' work is the smoothed increments' stress work; Edo (2016)'s is not.

    Forces from the V-weighted adjoint of the MLS operator Φ: −Δt Σ f_int·v =
    Σ V σ : (Φ Δε(v)) for any σ and v; the forces of Edo (2016) (from σ) do not satisfy it.
    """
    from geofrac.mpm.consistent import mls_operator
    from geofrac.mpm.shapes import UGIMP, weights

    rng = np.random.default_rng(7)
    g = grid([0.0, 0.0], 0.5, [12, 12])
    p = lattice([1.0, 1.0], [16, 16], 0.25, density=1.0)
    p.x += rng.uniform(-0.05, 0.05, p.x.shape)
    p.volume *= rng.uniform(0.8, 1.2, p.n)
    stress = rng.normal(size=(p.n, 2, 2))
    stress = stress + np.swapaxes(stress, 1, 2)
    v = rng.normal(size=(g.num_nodes, 2))
    dt = 1e-3
    w = weights(g, p.x, UGIMP, lp=p.lp)
    op = mls_operator(p.x, 2 * g.spacing)
    L = np.matmul(np.swapaxes(v[w.nodes], 1, 2), w.grad)
    deps = 0.5 * dt * (L + np.swapaxes(L, 1, 2))
    smoothed = op.apply(deps.reshape(p.n, 4)).reshape(p.n, 2, 2)
    power = np.einsum("p,pij,pij->", p.volume, stress, smoothed)

    def work(s):  # −Δt Σ_i f_int,i·v_i with f_int,i = −Σ_p V_p s_p ∇φ_ip
        return dt * np.einsum("p,pij,pkj,pki->", p.volume, s, w.grad, v[w.nodes])

    adjoint = op.adjoint(stress.reshape(p.n, 4), p.volume).reshape(p.n, 2, 2)
    assert work(adjoint) == pytest.approx(power, rel=1e-10)
    assert abs(work(stress) - power) > 1e-3 * abs(power)


def test_the_bench_and_the_scene_report_the_same_drift():
    """One set-up, one answer: the bench's translating bar is the scene's run."""
    overrides = translating_overrides("mpm", "musl", 2.0, t_end=6.0)
    scene = simulate(load_scene(TRANSLATING_SCENE, overrides), MPI.COMM_SELF, verbose=False)
    bench = translating_bar("mpm", "musl", 2.0, t_end=6.0)
    assert bench.drift_max == scene["energy_drift_max"]
    assert bench.drift_work_max == scene["energy_drift_work_max"]
    assert bench.steps == scene["steps"]


def test_energy_balance_error_is_defined_for_a_body_starting_at_rest(tmp_path):
    """A bar dropped under gravity: E₀ = 0, so no drift, but a balance error."""
    overrides = [
        "mpm.t_end=2.5",
        "mpm.velocity=[0.0]",
        'effects=["gravity"]',
        "gravity.acceleration=[-9.81]",
    ]
    results = simulate(load_scene(TRANSLATING_SCENE, overrides), MPI.COMM_SELF, verbose=False)
    assert results["energy_drift_max"] is None
    assert 0 < results["energy_balance_error"] < 0.05


@pytest.mark.mpi(min_size=2)
def test_the_budget_closes_on_two_ranks_and_matches_one():
    """The bar, vibrating after a wall hit, crosses the slabs' boundary at x = 25.

    Each node's terms are counted once (by the rank owning its node plane).
    """
    overrides = translating_overrides("ugimp", "usavg", None, t_end=16.0)
    overrides += ["mpm.particles.lower=[2.5]", "mpm.velocity=[-2.0]"]
    one = simulate(load_scene(TRANSLATING_SCENE, overrides), MPI.COMM_SELF, verbose=False)
    two = simulate(load_scene(TRANSLATING_SCENE, overrides), MPI.COMM_WORLD, verbose=False)
    assert two["energy_budget_closure"] < 1e-12
    assert two["energy_drift_work_max"] == pytest.approx(one["energy_drift_work_max"], rel=1e-6)


@pytest.mark.mpi(min_size=2)
def test_consistent_smoothing_on_two_ranks_gives_the_serial_energies():
    """The scene with the consistent kind: 1 and 2 ranks report the same drift of K + U.

    The bar starts on one rank (the other holds no particle until it crosses x = 25),
    then flies across.
    """
    overrides = translating_overrides("ugimp", "musl", 2.0, t_end=16.0, smoothing_kind="consistent")
    one = simulate(load_scene(TRANSLATING_SCENE, overrides), MPI.COMM_SELF, verbose=False)
    two = simulate(load_scene(TRANSLATING_SCENE, overrides), MPI.COMM_WORLD, verbose=False)
    assert two["energy_budget_closure"] < 1e-12
    assert two["energy_drift_max"] == one["energy_drift_max"]
