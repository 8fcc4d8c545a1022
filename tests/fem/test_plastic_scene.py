"""The ``plasticity`` effect in a FEM scene (jobs/opening_mohr_coulomb.toml)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from geofrac.analytic_plastic import MohrCoulombOpening
from geofrac.model.errors import SceneError
from geofrac.scene.load import load_scene
from tests.fem.helpers import JOBS, solve_job

JOB = JOBS / "opening_mohr_coulomb.toml"


def test_scene_opening_against_salencon() -> None:
    """The scene gives the closed-form wall displacement.

    Initial stress -p0 I, loaded sides, wall suction p0 - pi ramped; within 2 %
    (measured -0.28 % at h = 0.2).
    """
    exact = MohrCoulombOpening(
        a=1.0, b=10.0, p0=10.0, pi=1.0, E=1e4, nu=0.3, cohesion=1.0, friction_angle=30.0
    )
    solution = solve_job("opening_mohr_coulomb")
    try:
        results = solution.results
    finally:
        solution.problem.destroy()
    plastic = results["plasticity"]
    assert plastic["converged"] and plastic["end_reason"] == "converged"
    assert plastic["factor"] == 1.0 and plastic["plastic_points"] > 0
    assert all(s["reason"].startswith("CONVERGED") for s in plastic["steps"] if s["accepted"])
    u_wall = results["probes"]["wall"][0]
    assert u_wall == pytest.approx(exact.wall_displacement, rel=0.02)


def test_scene_without_load_reaches_the_initial_state_only() -> None:
    """No ramped load: nothing moves and nothing yields (the initial state balances)."""
    solution = solve_job("opening_mohr_coulomb", "load.0.value=[0.0]", "plasticity.load_steps=1")
    try:
        results = solution.results
    finally:
        solution.problem.destroy()
    assert results["plasticity"]["plastic_points"] == 0
    assert max(abs(c) for c in results["probes"]["wall"]) < 1e-12


def test_scene_with_davis_is_the_associated_equivalent() -> None:
    """``davis = true`` solves Davis's associated equivalent material.

    c* = β c, tan φ* = β tan φ, ψ* = φ*; β = cos 30° for ψ = 0: c* = √3/2, φ* = atan(1/2).
    The wall displacement of that material's closed form within 2 % on h = 0.1 (h = 0.05:
    -0.05 %), not the given material's (2.4 times smaller).
    """
    phi = float(np.degrees(np.arctan(0.5)))
    exact = MohrCoulombOpening(
        a=1.0,
        b=10.0,
        p0=10.0,
        pi=1.0,
        E=1e4,
        nu=0.3,
        cohesion=np.sqrt(3) / 2,
        friction_angle=phi,
        dilatancy_angle=phi,
    )
    solution = solve_job(
        "opening_mohr_coulomb", "plasticity.davis=true", "geometry.parameters.h=0.1"
    )
    try:
        results = solution.results
    finally:
        solution.problem.destroy()
    assert results["plasticity"]["converged"]
    assert results["probes"]["wall"][0] == pytest.approx(exact.wall_displacement, rel=0.02)


@pytest.mark.parametrize(
    ("override", "key"),
    [
        ("plasticity.law=tresca", "plasticity.law"),
        ("plasticity.dilatancy_angle=40.0", "plasticity.dilatancy_angle"),
        ("plasticity.tension_cutoff=5.0", "plasticity.tension_cutoff"),
        ("plasticity.match=outer", "plasticity.match"),
        ("plasticity.load_steps=0", "plasticity.load_steps"),
        ("plasticity.max_cuts=1.5", "plasticity.max_cuts"),
        ("discretization.element=cst", "discretization.element"),
        ("material.plane=stress", "material.plane"),
        ("plasticity.bogus=1", "plasticity"),
        ("plasticity.davis=1", "plasticity.davis"),
    ],
)
def test_bad_keys_named_before_meshing(override: str, key: str) -> None:
    """Each bad entry is refused by the loader (no mesh, no solve), naming its key."""
    with pytest.raises(SceneError) as info:
        load_scene(JOB, [override])
    assert info.value.key.startswith(key), info.value


def test_stages_with_the_ground_reaction_refused(tmp_path: Path) -> None:
    """Construction stages run with plasticity, but not beside the ground reaction curve."""
    geo = (JOB.parent / "../meshes/quarter_ring.geo").resolve()
    text = JOB.read_text().replace('"../meshes/quarter_ring.geo"', f'"{geo}"')
    path = tmp_path / "staged.toml"
    path.write_text(text + '\n[[stages]]\nname = "x"\nremove = ["rock"]\n')
    with pytest.raises(SceneError, match="does not go with \\[\\[stages\\]\\]") as info:
        load_scene(path)
    assert info.value.key == "plasticity.ground_reaction"


def test_huge_cohesion_scene_equals_the_elastic_scene(tmp_path: Path) -> None:
    """With c = 1e8 the plastic scene equals the same scene without the effect.

    The elastic initial-stress solve of docs/insitu.md, with the same quadrature degree 2,
    to 1e-10 of max |u| (measured 7e-15).
    """
    from mpi4py import MPI

    from geofrac.runner import solve_scene

    geo = (JOB.parent / "../meshes/quarter_ring.geo").resolve()
    text = JOB.read_text().replace('"../meshes/quarter_ring.geo"', f'"{geo}"')
    elastic = text[: text.index("[plasticity]")] + text[text.index("[[load]]") :]
    path = tmp_path / "elastic.toml"
    path.write_text(elastic.replace('effects = ["plasticity"]', "effects = []"))
    degree = ["discretization.quadrature_degree=2"]
    strong = [*degree, "plasticity.cohesion=1e8", "plasticity.load_steps=1"]
    comm = MPI.COMM_WORLD
    el = solve_scene(load_scene(path, degree), comm, verbose=False)
    pl = solve_scene(load_scene(JOB, strong), comm, verbose=False)
    try:
        assert pl.results["plasticity"]["plastic_points"] == 0
        u_el, u_pl = el.problem.uh.x.array, pl.problem.uh.x.array
        scale = comm.allreduce(float(np.abs(u_el).max()), op=MPI.MAX)
        gap = comm.allreduce(float(np.abs(u_el - u_pl).max()), op=MPI.MAX)
    finally:
        el.problem.destroy()
        pl.problem.destroy()
    assert gap <= 1e-10 * scale
