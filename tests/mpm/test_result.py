"""An MPM run's result block (geofrac/mpm/result.py, MpmMethod.result).

jobs/mpm_bar_w1000.toml: a bar of L₀ = 50 (100 particles, spacing 0.5, base x = 0 fixed),
E = 1e6, ρ₀ = 1, gravity 20 towards the base. At rest the point at height X has moved
u(X) = −ρ₀ b (L₀ X − X²/2) / E (the weight above X stretches dX by σ/E); the top
particle sits at X = 49.75.
"""

import re

import pytest
from mpi4py import MPI

from geofrac.mpm.driver import MPM
from geofrac.mpm.result import self_weight_bar
from geofrac.pipeline import run_scene
from geofrac.scene import load_scene
from tests.conftest import JOBS

BAR = JOBS / "mpm_bar_w1000.toml"


@pytest.fixture(scope="module")
def bar(tmp_path_factory):
    scene = load_scene(BAR, ["units.length=m"], out=tmp_path_factory.mktemp("bar"))
    return scene, run_scene(scene, MPI.COMM_SELF, verbose=False)


def test_the_bar_moves_as_the_closed_form_at_rest_says(bar):
    scene, summary = bar
    rho0, b, L0, E, X = 1.0, 20.0, 50.0, 1e6, 49.75
    exact = -rho0 * b * (L0 * X - X * X / 2) / E
    u = summary["results"]["runout_m"]
    lines = MPM.result(scene, summary)
    assert (
        lines[0]
        == f"bar under its own weight: top particle (x = 49.75 m) moved {u:.4g} m at t = 0.05"
    )
    assert lines[1] == (
        f"closed form at rest (Edo (2016), eq. 4.73-4.74): {exact:.4g} m; difference "
        f"{u - exact:+.3g} m, {100 * (u - exact) / abs(exact):+.3g} %"
    )
    assert abs(u - exact) < 1e-3 * abs(exact)


def test_without_units_no_unit_is_printed(bar):
    _, summary = bar
    bare = load_scene(BAR)
    assert bare.units.length == ""
    lines = MPM.result(bare, summary)
    assert lines[0].endswith("(x = 49.75) moved -0.02499 at t = 0.05")
    assert not any(re.search(r"\d m\b", line) for line in lines)


def test_only_a_bar_on_its_base_has_the_closed_form():
    assert self_weight_bar(load_scene(BAR)) is not None
    assert self_weight_bar(load_scene(BAR, ["mpm.walls={}"])) is None
    assert self_weight_bar(load_scene(BAR, ["mpm.particles.lower=[2.0]"])) is None
    assert self_weight_bar(load_scene(JOBS / "mpm_impact_bar.toml")) is None


def test_any_other_scene_gives_its_runout_in_its_length_unit(tmp_path):
    scene = load_scene(BAR, ["units.length=m", "mpm.walls={}", "mpm.t_end=0.005"], out=tmp_path)
    summary = run_scene(scene, MPI.COMM_SELF, verbose=False)
    runout = summary["results"]["runout_m"]
    assert MPM.result(scene, summary)[0].startswith(f"runout (front x moved): {runout:.4g} m at t")
