"""The constitutive-model contract (geofrac.mpm.constitutive) on every registered model.

Closed forms of isotropic elasticity (λ = Eν/((1+ν)(1−2ν)), μ = E/(2(1+ν)), written out
here, not taken from geofrac.materials), of the Jaumann rotation to first order, and of
the Drucker-Prager return (Edo (2016), eqs. 4.39-4.43, ψ = 0) for pure shear and at the
apex; then a throwaway model registered by monkeypatch runs a scene's steps.
"""

import sys
from dataclasses import fields
from types import ModuleType
from typing import ClassVar

import numpy as np
import pytest
from mpi4py import MPI

from geofrac.effects.plasticity import PlasticityConfig
from geofrac.mpm import constitutive
from geofrac.mpm.energy import StepBudget
from geofrac.mpm.particles import Particles, particles
from tests.conftest import JOBS

E, NU, RHO = 2.0e7, 0.3, 2000.0
LAM = E * NU / ((1 + NU) * (1 - 2 * NU))
MU = E / (2 * (1 + NU))
#: The scene config of each model: stiff enough in cohesion to stay elastic here.
ELASTIC_RANGE = {"elastic": None, "plasticity": PlasticityConfig(30.0, 1e9, 0.0)}
BACKENDS = ("numpy", "numba")


def _model(name, config="elastic range"):
    cfg = ELASTIC_RANGE[name] if config == "elastic range" else config
    return constitutive.load(name).from_scene(E, NU, cfg)


def _particles(dim, stress=None, n=2):
    p = particles(np.zeros((n, dim)), np.full(n, 0.5), RHO, lp0=np.full((n, dim), 0.25))
    if stress is not None:
        p.stress[:] = stress
    return p


@pytest.mark.parametrize("name", constitutive.available())
def test_every_model_declares_the_contract(name):
    model = _model(name)
    assert model.name == name
    assert set(model.dims) <= {1, 2, 3} and model.dims
    assert set(model.state) <= {f.name for f in fields(Particles)}
    assert "stress" in model.state
    assert isinstance(model.compiled, bool)
    assert model.E == E and model.nu == NU


@pytest.mark.parametrize("name", constitutive.available())
def test_wave_speed_is_the_p_wave(name):
    model = _model(name)
    for dim in model.dims:
        c = np.sqrt(E / RHO) if dim == 1 else np.sqrt((LAM + 2 * MU) / RHO)
        assert model.wave_speed(RHO, dim) == pytest.approx(c, rel=1e-14)


@pytest.mark.parametrize("backend", BACKENDS)
@pytest.mark.parametrize("name", constitutive.available())
def test_uniaxial_strain_gives_the_elastic_stress_and_energy(name, backend):
    """Δε = e e_x ⊗ e_x: σ_xx = (λ + 2μ) e, the other normals λ e (plane strain σ_zz too).

    The stored energy is then ½ V σ : ε = ½ V (λ + 2μ) e²; nothing is dissipated.
    """
    model, e, dt = _model(name), 1e-5, 1e-3
    for dim in model.dims:
        p = _particles(dim)
        deps = np.zeros((p.n, dim, dim))
        deps[:, 0, 0] = e
        budget = StepBudget()
        model.stress_update(p, deps, deps / dt, dt=dt, backend=backend, budget=budget)
        expect = np.diag([LAM + 2 * MU] + [LAM] * (dim - 1))[:dim, :dim] * e
        if dim == 1:
            expect = np.array([[E * e]])
        np.testing.assert_allclose(p.stress, np.broadcast_to(expect, p.stress.shape), rtol=1e-13)
        if dim == 2:
            np.testing.assert_allclose(p.stress_zz, LAM * e, rtol=1e-13)
        modulus = E if dim == 1 else LAM + 2 * MU
        np.testing.assert_allclose(model.stored_energy(p), 0.5 * 0.5 * modulus * e**2, rtol=1e-12)
        assert abs(budget.plastic) <= 1e-12 * 0.5 * modulus * e**2


@pytest.mark.parametrize("backend", BACKENDS)
@pytest.mark.parametrize("name", constitutive.available())
def test_a_rigid_spin_turns_the_stress(name, backend):
    """Jaumann (D.30-D.31): spinning σ = s e_x ⊗ e_x by θ = ω Δt gives σ_xy = θ s.

    R σ Rᵀ to first order in θ; with no strain the normal stresses stay.
    """
    model, s, omega, dt = _model(name), -1e4, 0.2, 1e-3
    for dim in (d for d in model.dims if d > 1):
        stress = np.zeros((dim, dim))
        stress[0, 0] = s
        p = _particles(dim, stress)
        L = np.zeros((p.n, dim, dim))
        L[:, 0, 1], L[:, 1, 0] = -omega, omega  # v = ω e_z × x
        model.stress_update(p, np.zeros_like(L), L, dt=dt, backend=backend, budget=None)
        np.testing.assert_allclose(p.stress[:, 0, 1], omega * dt * s, rtol=1e-12)
        np.testing.assert_allclose(p.stress[:, 1, 0], omega * dt * s, rtol=1e-12)
        np.testing.assert_allclose(p.stress[:, 0, 0], s, rtol=1e-12)


PHI, COHESION = 30.0, 1e4
TAN = np.tan(np.radians(PHI))
BETA = TAN / np.sqrt(9 + 12 * TAN**2)  # eq. 4.42
K_DP = 3 * COHESION / np.sqrt(9 + 12 * TAN**2)  # eq. 4.43


@pytest.mark.parametrize("backend", BACKENDS)
def test_drucker_prager_shear_returns_to_the_closed_form_point(backend):
    """Pure shear from σ = p₀ I beyond the cone, ψ = 0 (plane strain and 3D).

    Trial τ* = 2μγ; the return keeps p₀ and lands on f = 3β p₀ + |τ| − k = 0, so
    τ = k − 3β p₀, Δλ = (τ* − τ)/μ; it dissipates V (τ*² − τ²)/(2μ) (the stored
    energy of a shear τ is τ²/(2μ) per volume).
    """
    model = _model("plasticity", PlasticityConfig(PHI, COHESION, 0.0))
    p0, gamma, dt = -2e4, 2e-3, 1e-3
    tau_trial, tau = 2 * MU * gamma, K_DP - 3 * BETA * p0
    assert tau_trial > tau > 0
    for dim in (2, 3):
        p = _particles(dim, p0 * np.eye(dim))
        p.stress_zz[:] = p0
        deps = np.zeros((p.n, dim, dim))
        deps[:, 0, 1] = deps[:, 1, 0] = gamma
        budget = StepBudget()
        model.stress_update(p, deps, deps / dt, dt=dt, backend=backend, budget=budget)
        expect = p0 * np.eye(dim)
        expect[0, 1] = expect[1, 0] = tau
        np.testing.assert_allclose(p.stress, np.broadcast_to(expect, p.stress.shape), rtol=1e-10)
        if dim == 2:
            np.testing.assert_allclose(p.stress_zz, p0, rtol=1e-10)
        np.testing.assert_allclose(p.plastic, (tau_trial - tau) / MU, rtol=1e-10)
        dissipated = p.n * 0.5 * (tau_trial**2 - tau**2) / (2 * MU)
        assert budget.plastic == pytest.approx(dissipated, rel=1e-9)


@pytest.mark.parametrize("backend", BACKENDS)
def test_drucker_prager_tension_returns_to_the_apex(backend):
    """Stretching far beyond the apex: σ = k/(3β) I (eqs. 4.39-4.43), σ_zz included."""
    model = _model("plasticity", PlasticityConfig(PHI, COHESION, 0.0))
    dt = 1e-3
    for dim in (2, 3):
        p = _particles(dim)
        deps = np.broadcast_to(1e-2 * np.eye(dim), (p.n, dim, dim)).copy()
        model.stress_update(p, deps, deps / dt, dt=dt, backend=backend, budget=None)
        apex = K_DP / (3 * BETA)
        np.testing.assert_allclose(p.stress, np.broadcast_to(apex * np.eye(dim), p.stress.shape))
        if dim == 2:
            np.testing.assert_allclose(p.stress_zz, apex)


def test_a_model_is_one_module_and_one_registry_line(monkeypatch, tmp_path):
    """A throwaway model, registered by monkeypatch only, runs a scene's steps.

    The model keeps the stress at zero (dust) and has its own wave speed: the driver's
    time step must come from it (Δt = α h / c, eq. 4.72), the step must call its update,
    and its results must reach the summary; no other code knows it.
    """
    from geofrac.mpm.driver import simulate
    from geofrac.scene import load_scene

    calls = []

    class Dust:
        name: ClassVar[str] = "dust"
        dims: ClassVar[tuple[int, ...]] = (2,)
        state: ClassVar[tuple[str, ...]] = ("stress",)
        compiled: ClassVar[bool] = False
        E, nu = 1.0, 0.0

        def wave_speed(self, density, dim):
            return 50.0

        def stored_energy(self, p):
            return np.zeros(p.n)

        def results(self):
            return {"dust_calls": float(len(calls))}

        def stress_update(self, p, deps, L, *, dt, backend, budget):
            calls.append(dt)

    module = ModuleType("throwaway_dust_model")
    module.from_scene = lambda E, nu, config: Dust()
    monkeypatch.setitem(sys.modules, module.__name__, module)
    monkeypatch.setitem(constitutive.MODELS, "dust", module.__name__)
    monkeypatch.setattr(constitutive, "DEFAULT", "dust")

    scene = load_scene(JOBS / "mpm_two_blocks.toml", ["mpm.t_end=0.01"], out=tmp_path)
    results = simulate(scene, MPI.COMM_SELF, verbose=False)
    # courant 0.1 (default) × spacing 0.1 / c = 50 → Δt = 2e-4: 50 steps to t_end
    assert results["steps"] == 50 and results["dt"] == pytest.approx(2e-4)
    assert len(calls) == 50 and results["dust_calls"] == 50.0
    # no stress, no force: the striker flies on at 1 m/s
    assert results["probes"]["striker"][-1]["v"] == pytest.approx([1.0, 0.0])
