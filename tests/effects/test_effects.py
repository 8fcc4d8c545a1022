"""Ask 3: a scene gets exactly the effects it declares, and nothing else is loaded."""

import json

import pytest

from geofrac import effects
from tests.conftest import JOBS
from tests.conftest import run_and_list_modules as _run_and_list_modules


def test_undeclared_effects_are_never_imported(tmp_path):
    modules = _run_and_list_modules(tmp_path, JOBS / "quickstart.toml")
    assert "geofrac.fem.elastic" in modules  # the run really happened in this process
    for name, module in effects.REGISTRY.items():
        assert module not in modules, f"effect '{name}' was imported without being declared"
    assert not [m for m in modules if m.startswith("geofrac.effects.")]


def test_declared_effect_is_imported_and_applied(tmp_path):
    modules = _run_and_list_modules(
        tmp_path, JOBS / "quickstart.toml", "effects=['gravity']", "material.density=2.0"
    )
    assert effects.REGISTRY["gravity"] in modules
    summary = json.loads((tmp_path / "out" / "summary.json").read_text())
    assert summary["scene"]["effects"] == ["gravity"]


def test_gravity_equals_the_same_body_force():
    from tests.fem.helpers import solve_job

    base = ["load=[]", "bc.0.value=[0.0, 0.0]"]
    gravity = solve_job(
        "cantilever",
        *base,
        "effects=['gravity']",
        "material.density=2.0",
        "gravity.acceleration=[0.0, -0.5]",
    )
    body = solve_job("cantilever", *base, "load=[{type='body_force', value=[0.0, -1.0]}]")
    tip_g = gravity.results["probes"]["tip"][1]
    tip_b = body.results["probes"]["tip"][1]
    gravity.problem.destroy()
    body.problem.destroy()
    assert tip_g == pytest.approx(tip_b, rel=1e-12)
    assert tip_g < 0


def test_gravity_deflection_matches_beam_theory():
    """Self-weight q = ρ g D per length: v_tip = qL⁴/(8EI) + qL²/(2κGA), κ = 5/6."""
    from tests.fem.helpers import solve_job

    sol = solve_job(
        "cantilever",
        "discretization.element=p2",
        "load=[]",
        "bc.0.value=[0.0, 0.0]",
        "effects=['gravity']",
        "material.density=1.0",
        "gravity.acceleration=[0.0, -0.01]",
    )
    tip = sol.results["probes"]["tip"][1]
    sol.problem.destroy()
    E, nu, L, D, q = 100.0, 0.2, 10.0, 1.0, 0.01
    inertia, shear = D**3 / 12, E / (2 * (1 + nu))
    beam = q * L**4 / (8 * E * inertia) + q * L**2 / (2 * 5 / 6 * shear * D)
    assert -tip == pytest.approx(beam, rel=0.02)


def test_effect_registry_lists_only_importable_modules():
    for name in effects.available():
        module = effects.load(name)
        assert callable(module.configure)
