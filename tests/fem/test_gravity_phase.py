"""The gravity phase of the elasto-plastic solve (docs/plasticity.md, "Gravity phase").

``[plasticity] gravity_phase = true``: gravity ramped from a stress-free start with the
loads off and the ``[[bc]]`` values held at 0, the displacements reset (u = 0, εₙ = 0,
σₙ and the plastic strain kept), then the analysis (gravity held, loads and ``[[bc]]``
values ramped). References from closed forms:

- a level layer (tests/fem/gravity_layer.toml: rollers on the sides, the base fixed,
  γ = 20, D = 5, E = 1e5, ν = 0.2), strong rock: σ_yy = γ y, σ_xx = σ_zz = K0 σ_yy with
  K0 = ν/(1 − ν) (a linear field: exact for P2; its DG0 cell means are the values at the
  centroids), the surface settles γ D²/(2M), M = E(1 − ν)/((1 + ν)(1 − 2ν)) (the gravity
  phase's largest |u|), and after the reset an analysis without loads moves nothing;
- the same layer with c = 1, φ = 30°, ψ = 0: K0 = 0.25 < K_a = (1 − sin φ)/(1 + sin φ) =
  1/3, so below z = 2c√K_a/(γ(K_a − K0)) = 0.69 m the layer yields to Rankine's active
  state σ_xx = K_a σ_yy + 2c√K_a (σ_zz = σ_xx: the triaxial corner of Mohr-Coulomb, the
  two lateral stresses alike as the lateral strains);
- a surface pressure after the gravity phase of a strong layer moves it as the same
  pressure moves the weightless layer (superposition; the loads are off in the gravity
  phase and ramped in the analysis);
- Prandtl's footing on heavy clay (jobs/footing_heavy_clay.toml, φ = 0): the collapse
  pressure (2 + π) c does not depend on the soil's weight, within 3 %;
- joints keep their forces through the reset (the planar slide's block); in strength
  reduction a gravity phase without loads gives gravity ramped's trials.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import dolfinx
import numpy as np
import pytest
from mpi4py import MPI

from geofrac.fem.strength_reduction import largest_monitor
from geofrac.model.errors import SceneError
from geofrac.runner import solve_scene
from geofrac.scene import load_scene_collective
from geofrac.scene.load import load_scene
from tests.conftest import JOBS
from tests.fem.helpers import solve_job

LAYER = Path(__file__).parent / "gravity_layer.toml"
GAMMA, DEPTH, E, NU = 20.0, 5.0, 1.0e5, 0.2
K0 = NU / (1.0 - NU)
#: the constrained modulus of plane strain with rollers on the sides
M = E * (1.0 - NU) / ((1.0 + NU) * (1.0 - 2.0 * NU))
PHI = np.radians(30.0)
KA = (1.0 - np.sin(PHI)) / (1.0 + np.sin(PHI))
#: the scale of the stresses: γ D
SCALE = GAMMA * DEPTH


def _layer(tmp_path: Path | None, *sets: str, extra: str = "", comm: MPI.Comm = MPI.COMM_WORLD):
    """Solve the layer (with ``extra`` scene text appended, e.g. a [[load]]); destroy later."""
    path = LAYER
    if extra:
        assert tmp_path is not None
        geo = (JOBS / "../meshes/footing_prandtl.geo").resolve()
        text = LAYER.read_text().replace('"../../meshes/footing_prandtl.geo"', f'"{geo}"')
        path = tmp_path / "layer.toml"
        if comm.rank == 0:
            path.write_text(text + extra)
        comm.barrier()
    scene = load_scene_collective(comm, path, sets)
    return solve_scene(scene, comm, verbose=False)


def _cells(solution: Any) -> tuple[np.ndarray, np.ndarray]:
    """(owned cells' centroid y, shape=(n,); their DG0 stress, shape=(n, 3, 3))."""
    mesh = solution.problem.mesh
    n = mesh.topology.index_map(mesh.topology.dim).size_local
    y = dolfinx.mesh.compute_midpoints(mesh, mesh.topology.dim, np.arange(n, dtype=np.int32))
    stress = solution.fields["stress"].x.array.reshape(-1, 3, 3)[:n]
    return y[:, 1], stress


def _max(comm: MPI.Comm, values: np.ndarray) -> float:
    return float(comm.allreduce(float(np.abs(values).max(initial=0.0)), op=MPI.MAX))


def _geostatic(solution: Any, comm: MPI.Comm) -> dict[str, float]:
    """The largest deviations of the layer's state from the closed form (all ranks)."""
    y, s = _cells(solution)
    plastic = solution.results["plasticity"]
    settle = GAMMA * DEPTH**2 / (2.0 * M)
    return {
        "syy": _max(comm, s[:, 1, 1] - GAMMA * y) / SCALE,
        "sxx": _max(comm, s[:, 0, 0] - K0 * GAMMA * y) / SCALE,
        "szz": _max(comm, s[:, 2, 2] - K0 * GAMMA * y) / SCALE,
        "sxy": _max(comm, s[:, 0, 1]) / SCALE,
        "settlement": abs(plastic["gravity_phase"]["max_displacement"] - settle) / settle,
        "u": _max(comm, solution.problem.uh.x.array) / settle,
    }


def test_level_layer_gravity_phase_is_geostatic_and_the_reset_leaves_it() -> None:
    """Strong rock: the closed-form geostatic state to 1e-9, nothing moves afterwards.

    Break check: resetting u but not εₙ makes the analysis undo the gravity strain
    (the stress drops to 0, then the body sags back: u ≈ the gravity phase's).
    """
    comm = MPI.COMM_WORLD
    solution = _layer(None)
    try:
        dev = _geostatic(solution, comm)
        plastic = solution.results["plasticity"]
    finally:
        solution.problem.destroy()
    assert plastic["converged"] and plastic["end_reason"] == "converged"
    gravity = plastic["gravity_phase"]
    assert gravity["converged"] and gravity["plastic_points"] == 0
    assert [s["factor"] for s in gravity["steps"]] == [0.5, 1.0]  # gravity_steps = load_steps
    assert [s["factor"] for s in plastic["steps"]] == [0.5, 1.0]
    assert plastic["plastic_points"] == 0
    assert all(v <= 1e-9 for v in dev.values()), dev


def test_rankine_active_state_after_the_gravity_phase() -> None:
    """Cohesion 1, φ = 30°, ψ = 0, ν = 0.2: σ_xx = σ_zz = K_a σ_yy + 2c√K_a below 1.5 m.

    Measured: 1e-6 of γD in every cell below 1.1 m (σ_yy = γ y there to 2e-4 of γD; the
    cells at the elastic-plastic front, z = 0.69 m, carry the error of P2 at the kink).
    """
    comm = MPI.COMM_WORLD
    solution = _layer(None, "plasticity.cohesion=1.0", "plasticity.gravity_steps=4")
    try:
        y, s = _cells(solution)
        plastic = solution.results["plasticity"]
        u = _max(comm, solution.problem.uh.x.array)
    finally:
        solution.problem.destroy()
    assert plastic["converged"] and plastic["gravity_phase"]["plastic_points"] > 0
    deep = y < -1.5
    rankine = KA * s[deep, 1, 1] + 2.0 * 1.0 * np.sqrt(KA)
    assert _max(comm, s[deep, 0, 0] - rankine) <= 1e-5 * SCALE
    assert _max(comm, s[deep, 2, 2] - rankine) <= 1e-5 * SCALE
    assert _max(comm, s[deep, 1, 1] - GAMMA * y[deep]) <= 1e-3 * SCALE
    # not K0's: the elastic state is 2c√K_a + (K_a − K0) γ z away at every depth
    assert comm.allreduce(int(np.count_nonzero(deep)), op=MPI.SUM) > 10
    # the analysis without a load leaves it (the gravity phase's residual below 1e-8)
    assert u <= 1e-6 * GAMMA * DEPTH**2 / (2.0 * M)


PRESSURE = """
[[load]]
type = "pressure"
group = "footing"
value = 50.0
"""


def test_a_load_after_the_gravity_phase_moves_the_body_as_on_a_weightless_one(tmp_path):
    """Strong rock: u of the analysis = u of the same load without weight, to 1e-10.

    The loads are off in the gravity phase and ramped in the analysis; gravity held.
    """
    comm = MPI.COMM_WORLD
    tmp = Path(comm.bcast(str(tmp_path), root=0))
    heavy = _layer(tmp, extra=PRESSURE)
    light = _layer(
        tmp,
        "plasticity.gravity_phase=false",
        "gravity.acceleration=[0.0, 0.0]",
        extra=PRESSURE,
    )
    try:
        u_heavy, u_light = heavy.problem.uh.x.array, light.problem.uh.x.array
        scale = _max(comm, u_light)
        gap = _max(comm, u_heavy - u_light)
        assert "gravity_phase" not in light.results["plasticity"]
        y, s = _cells(heavy)
        _, s_light = _cells(light)
        # total stress: the weight's plus the load's
        total = _max(comm, s[:, 1, 1] - (GAMMA * y + s_light[:, 1, 1]))
    finally:
        heavy.problem.destroy()
        light.problem.destroy()
    assert scale > 0.0
    assert gap <= 1e-10 * scale
    assert total <= 1e-9 * SCALE


def test_footing_on_heavy_clay_reaches_prandtl() -> None:
    """φ = 0: q = −R_y/(B/2) → (2 + π) c, the soil's weight notwithstanding, within 3 %.

    Coarse mesh h = 0.5, hf = 0.05: +1.45 % (the weightless footing: +1.46 %). The
    settlement of the footing's centre is the prescribed −0.05 from the gravity state.
    """
    solution = solve_job(
        "footing_heavy_clay", "geometry.parameters.h=0.5", "geometry.parameters.hf=0.05"
    )
    try:
        results = solution.results
    finally:
        solution.problem.destroy()
    plastic = results["plasticity"]
    assert plastic["converged"] and plastic["gravity_phase"]["converged"]
    assert plastic["gravity_phase"]["max_displacement"] > 1e-3  # it did settle, 1.8 mm
    accepted = [s for s in plastic["steps"] if s["accepted"]]
    q = -accepted[-1]["reactions"]["footing"][1] / 1.0  # B/2 = 1
    assert q == pytest.approx((2.0 + np.pi) * 100.0, rel=0.03)
    assert results["probes"]["centre"][1] == pytest.approx(-0.05, rel=1e-12)


def test_a_gravity_phase_that_fails_ends_the_run_without_the_analysis() -> None:
    """One Newton iteration, no cut: the first plastic gravity step fails; no phase 2."""
    solution = _layer(
        None,
        "plasticity.cohesion=1.0",
        "plasticity.max_iterations=1",
        "plasticity.max_cuts=0",
    )
    try:
        plastic = solution.results["plasticity"]
    finally:
        solution.problem.destroy()
    assert not plastic["converged"]
    assert plastic["end_reason"] == "gravity_step_too_small"
    assert plastic["steps"] == [] and plastic["factor"] == 0.0
    gravity = plastic["gravity_phase"]
    assert not gravity["converged"] and gravity["factor"] < 1.0
    assert not gravity["steps"][-1]["accepted"]


@pytest.mark.parametrize(
    ("override", "key"),
    [
        ("plasticity.gravity_steps=0", "plasticity.gravity_steps"),
        ("plasticity.gravity_steps=2.5", "plasticity.gravity_steps"),
        ("plasticity.gravity_phase=1", "plasticity.gravity_phase"),
    ],
)
def test_bad_gravity_phase_keys_are_named(override: str, key: str) -> None:
    with pytest.raises(SceneError) as info:
        load_scene(LAYER, [override])
    assert info.value.key.startswith(key), info.value


def test_gravity_steps_need_the_gravity_phase() -> None:
    with pytest.raises(SceneError, match="needs gravity_phase") as info:
        load_scene(LAYER, ["plasticity.gravity_phase=false", "plasticity.gravity_steps=3"])
    assert info.value.key == "plasticity.gravity_steps"


def test_initial_stress_and_gravity_phase_are_alternatives(tmp_path: Path) -> None:
    """A K0 start and a gravity phase together: refused by the loader, naming both."""
    geo = (JOBS / "../meshes/footing_prandtl.geo").resolve()
    text = LAYER.read_text().replace('"../../meshes/footing_prandtl.geo"', f'"{geo}"')
    path = tmp_path / "k0.toml"
    path.write_text(text + '\n[initial_stress]\nkind = "geostatic"\nsurface = 0.0\n')
    load_scene(path, ["plasticity.gravity_phase=false"])  # the K0 start alone is fine
    with pytest.raises(SceneError, match=r"initial_stress") as info:
        load_scene(path)
    assert info.value.key == "plasticity.gravity_phase"


def test_ground_reaction_and_gravity_phase_are_refused() -> None:
    with pytest.raises(SceneError, match="gravity_phase") as info:
        load_scene(JOBS / "opening_mohr_coulomb.toml", ["plasticity.gravity_phase=true"])
    assert info.value.key == "plasticity.ground_reaction"


@pytest.mark.mpi(min_size=2)
def test_gravity_phase_on_two_ranks_equals_one() -> None:
    """The Rankine layer on 2 ranks: the closed form as on 1.

    The gravity phase's numbers equal each rank's serial run (largest |u| to 1e-10,
    plastic points exactly).
    """
    world = MPI.COMM_WORLD
    sets = ("plasticity.cohesion=1.0", "plasticity.gravity_steps=4")
    both = _layer(None, *sets, comm=world)
    alone = _layer(None, *sets, comm=MPI.COMM_SELF)
    try:
        y, s = _cells(both)
        deep = y < -1.5
        rankine = KA * s[deep, 1, 1] + 2.0 * np.sqrt(KA)
        assert _max(world, s[deep, 0, 0] - rankine) <= 1e-5 * SCALE
        a = both.results["plasticity"]["gravity_phase"]
        b = alone.results["plasticity"]["gravity_phase"]
        assert a["max_displacement"] == pytest.approx(b["max_displacement"], rel=1e-10)
        assert a["plastic_points"] == b["plastic_points"] > 0
        pa, pb = both.results["plasticity"], alone.results["plasticity"]
        assert pa["plastic_points"] == pb["plastic_points"]
        assert pa["yielded_area"] == pytest.approx(pb["yielded_area"], rel=1e-12)
    finally:
        both.problem.destroy()
        alone.problem.destroy()


SLOPE_SETS = (
    "geometry.parameters.h=2.0",
    "plasticity.max_cuts=1",
    "plasticity.max_iterations=15",
    "plasticity.reduction_tolerance=0.2",
)


def test_strength_reduction_with_a_gravity_phase_and_no_load_is_the_ramped_one() -> None:
    """Griffiths-Lane's slope (h = 2): the same trials and factor as gravity ramped.

    With no ``[[load]]`` the gravity phase of each trial is the ramped-gravity solve of
    the plain strength reduction (the same steps with the same law), and the analysis
    has nothing to carry: every trial's verdict and the bracket are the same; the
    failed trials fail in the gravity phase; the monitor of a stable trial (measured in
    the analysis, from the gravity state) stays 0 to round-off.
    """
    runs = []
    for extra in ((), ("plasticity.gravity_phase=true",)):
        solution = solve_job("slope_griffiths_lane", *SLOPE_SETS, *extra)
        try:
            runs.append(solution.results["plasticity"])
        finally:
            solution.problem.destroy()
    ramped, phased = runs
    assert ramped["gravity"] == "ramped" and phased["gravity"] == "gravity phase, then held"
    assert [t["factor"] for t in phased["trials"]] == [t["factor"] for t in ramped["trials"]]
    assert [t["stable"] for t in phased["trials"]] == [True, False, False]
    assert [t["stable"] for t in ramped["trials"]] == [True, False, False]
    assert phased["factor_of_safety"] == ramped["factor_of_safety"]
    for t in phased["trials"]:
        if t["stable"]:
            assert t["end_reason"] == "converged" and t["monitor"] <= 1e-12
        else:
            assert t["end_reason"] == "gravity_step_too_small" and t["load_factor"] == 0.0
    last = phased["last_stable"]
    assert last["converged"] and last["gravity_phase"]["converged"]
    assert last["gravity_phase"]["max_displacement"] > 1e-3  # it settled (the crest: 8.7 mm)


def _planar_joint(directory: Path) -> Path:
    """jobs/slope_planar_joint.toml load-stepped (its strength-reduction keys dropped)."""
    geo = (JOBS / "../meshes/slope_planar_joint.geo").resolve()
    text = (JOBS / "slope_planar_joint.toml").read_text()
    text = text.replace('"../meshes/slope_planar_joint.geo"', f'"{geo}"')
    lines = text.splitlines()
    path = directory / "planar_joint.toml"
    if MPI.COMM_WORLD.rank == 0:
        keep = [ln for ln in lines if not ln.startswith(("strength_reduction", "reduction_"))]
        path.write_text("\n".join(keep) + "\n")
    MPI.COMM_WORLD.barrier()
    return path


def test_joints_keep_their_forces_through_the_reset(tmp_path: Path) -> None:
    """The planar slide's block on its joint: its springs keep their forces at the reset.

    c = 10, μ = tan 35°: after the gravity phase and the reset an analysis without load
    moves nothing, and the joint's state is that of gravity ramped without a phase (the
    same steps), to 1e-9.

    Break check: without the jump kept at the reset the springs lose their force and
    the analysis does not converge (the block rests on nothing).
    """
    comm = MPI.COMM_WORLD
    path = _planar_joint(Path(comm.bcast(str(tmp_path), root=0)))
    runs = []
    for sets in ((), ("plasticity.gravity_phase=true", "plasticity.load_steps=1")):
        scene = load_scene_collective(comm, path, ("plasticity.max_cuts=0", *sets))
        solution = solve_scene(scene, comm, verbose=False)
        try:
            runs.append((solution.results["plasticity"], largest_monitor(solution.problem.uh)[0]))
        finally:
            solution.problem.destroy()
    (ramped, u_ramped), (phased, u_phased) = runs
    assert ramped["converged"] and phased["converged"]
    assert phased["gravity_phase"]["max_displacement"] == pytest.approx(u_ramped, rel=1e-9)
    assert u_phased <= 1e-9 * u_ramped
    a, b = phased["joints"], ramped["joints"]
    counts = ("pairs", "slipping", "open")
    assert [a[k] for k in counts] == [b[k] for k in counts]
    assert a["max_slip"] == pytest.approx(b["max_slip"], rel=1e-9)
    assert abs(a["max_opening"] - b["max_opening"]) <= 1e-9 * b["max_slip"]
    assert a["slipping"] > 0  # the joint's state is not trivial


def test_gravity_phase_without_gravity_is_refused(tmp_path: Path) -> None:
    """Without the gravity effect the phase would load nothing: refused by the loader."""
    geo = (JOBS / "../meshes/footing_prandtl.geo").resolve()
    text = LAYER.read_text().replace('"../../meshes/footing_prandtl.geo"', f'"{geo}"')
    head, tail = text.split("[gravity]")
    path = tmp_path / "weightless.toml"
    path.write_text(head.replace('"gravity", ', "") + tail[tail.index("\n[") :])
    with pytest.raises(SceneError, match="'gravity' effect") as info:
        load_scene(path)
    assert info.value.key == "plasticity.gravity_phase"
    load_scene(path, ["plasticity.gravity_phase=false"])  # the weightless layer alone is fine
