"""The elasto-plastic run's outputs (geofrac/fem/plastic_outputs.py, docs/plasticity.md).

The ground reaction curve of jobs/opening_mohr_coulomb.toml against Salençon's closed form
(the ring a = 1 <= r <= b = 10, p0 = 10 held outside, pi = 10 − 9λ; E = 1e4, ν = 0.3,
c = 1, φ = 30°, ψ = 0), the DG0 fields of results.xdmf on 1 and 2 ranks, and the
strength-reduction outputs of jobs/slope_griffiths_lane.toml on its coarse mesh (h = 2).
"""

from __future__ import annotations

import csv
import json
from pathlib import Path

import h5py
import numpy as np
import pytest
from mpi4py import MPI

from geofrac.analytic_plastic import MohrCoulombOpening
from geofrac.model.errors import SceneError
from geofrac.pipeline import run_scene
from geofrac.scene import load_scene_collective
from geofrac.scene.load import load_scene
from tests.fem.helpers import JOBS

OPENING = JOBS / "opening_mohr_coulomb.toml"
SLOPE = JOBS / "slope_griffiths_lane.toml"
FIELDS = ("displacement", "stress", "von_mises", "plastic_shear_strain")


def _run(path: Path, out: Path, *overrides: str, comm: MPI.Comm = MPI.COMM_WORLD) -> dict:
    sets = [*overrides, "output.xdmf=true"]
    scene = load_scene_collective(comm, path, sets, out=str(out))
    return run_scene(scene, comm, verbose=False)


def _shared(tmp_path: Path, comm: MPI.Comm = MPI.COMM_WORLD) -> Path:
    return Path(comm.bcast(str(tmp_path) if comm.rank == 0 else None, root=0))


def _rows(path: Path) -> list[dict[str, str]]:
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def _h5_fields(out: Path) -> dict[str, np.ndarray]:
    with h5py.File(out / "results.h5", "r") as f:
        return {name: np.asarray(f["Function"][name]["0"]) for name in f["Function"]}


def _exact(pi: float) -> MohrCoulombOpening:
    return MohrCoulombOpening(
        a=1.0, b=10.0, p0=10.0, pi=pi, E=1e4, nu=0.3, cohesion=1.0, friction_angle=30.0
    )


def test_ground_reaction_curve_against_salencon(tmp_path: Path) -> None:
    """ground_reaction.csv: p_i = 10 − 9λ per step, u_r within 2 % of the closed form.

    Measured (h = 0.2, 5 steps): −0.03 % on the elastic steps, −0.28 % at pi = 1 (ρ =
    1.473 there); the closed-form column is the closed form at the row's p_i.
    """
    out = _shared(tmp_path) / "open"
    summary = _run(OPENING, out)
    rows = _rows(out / "ground_reaction.csv")
    assert [float(r["load_factor"]) for r in rows] == pytest.approx([0, 0.2, 0.4, 0.6, 0.8, 1])
    for r in rows:
        lam, pi = float(r["load_factor"]), float(r["p_i"])
        assert pi == pytest.approx(10.0 - 9.0 * lam, rel=1e-12)
        exact = _exact(10.0 - 9.0 * lam)
        assert float(r["u_r_closed_form"]) == pytest.approx(exact.wall_displacement, rel=1e-9)
        assert float(r["plastic_radius_closed_form"]) == pytest.approx(exact.plastic_radius)
        if lam == 0.0:
            assert float(r["u_r"]) == 0.0
        else:
            assert float(r["u_r"]) == pytest.approx(exact.wall_displacement, rel=0.02)
    final = summary["results"]["plasticity"]["ground_reaction"]["final"]
    assert final["p_i"] == pytest.approx(1.0) and abs(final["relative_difference"]) <= 0.02
    # load_steps.csv holds the probe at every step: the wall probe's u_x is u_r there
    steps = _rows(out / "load_steps.csv")
    assert [float(s["wall_ux"]) for s in steps] == pytest.approx([float(r["u_r"]) for r in rows])
    for name in ("ground_reaction.png", "plastic_shear_strain.png"):
        assert (out / name).stat().st_size > 1000
    if MPI.COMM_WORLD.rank == 0:
        fields = _h5_fields(out)
        assert set(FIELDS) <= set(fields)
        assert all(np.isfinite(v).all() for v in fields.values())
        shear = fields["plastic_shear_strain"]
        assert shear.max() > 0.0 and shear.min() >= 0.0
        assert np.count_nonzero(shear) < len(shear)  # the plastic zone is around the wall only


def _ordered(values: np.ndarray) -> np.ndarray:
    """Cell values in an order independent of the partition: sorted by value."""
    return np.sort(values.ravel())


@pytest.mark.mpi(min_size=2)
def test_ground_reaction_and_fields_on_two_ranks_equal_one_rank(tmp_path: Path) -> None:
    """The 2-rank run's CSV and results.h5 cell fields equal 1 rank's (to 1e-9 of their scale)."""
    comm = MPI.COMM_WORLD
    root = _shared(tmp_path)
    _run(OPENING, root / "two")
    if comm.rank == 0:
        _run(OPENING, root / "one", comm=MPI.COMM_SELF)
    comm.barrier()
    one, two = _rows(root / "one/ground_reaction.csv"), _rows(root / "two/ground_reaction.csv")
    assert [float(r["u_r"]) for r in two] == pytest.approx(
        [float(r["u_r"]) for r in one], rel=1e-9, abs=1e-15
    )
    a, b = _h5_fields(root / "one"), _h5_fields(root / "two")
    for name in ("stress", "von_mises", "plastic_shear_strain"):
        assert a[name].shape == b[name].shape, name
        scale = float(np.abs(a[name]).max())
        assert np.abs(_ordered(a[name]) - _ordered(b[name])).max() <= 1e-9 * scale, name


def test_strength_reduction_outputs(tmp_path: Path) -> None:
    """strength_reduction.csv agrees with the bracket; the failure mechanism is written.

    Coarse mesh h = 2 (145 cells), the two trials 0.97 × 1.4 (stable) and 1.03 × 1.4
    (failed, tests/fem/test_strength_reduction.py), then the stable one re-solved.
    """
    out = _shared(tmp_path) / "slope"
    summary = _run(
        SLOPE,
        out,
        "geometry.parameters.h=2.0",
        "plasticity.max_cuts=1",
        "plasticity.max_iterations=15",
        "plasticity.reduction_bracket=[1.358, 1.442]",
        "plasticity.reduction_tolerance=1.0",
    )
    entry = summary["results"]["plasticity"]
    rows = _rows(out / "strength_reduction.csv")
    assert len(rows) == len(entry["trials"]) == 2
    stable = [float(r["factor"]) for r in rows if r["stable"] == "1"]
    failed = [float(r["factor"]) for r in rows if r["stable"] == "0"]
    assert max(stable) == pytest.approx(entry["stable"]) and min(failed) == pytest.approx(
        entry["failed"]
    )
    for r, t in zip(rows, entry["trials"], strict=True):
        assert float(r["factor"]) == pytest.approx(t["factor"])
        assert int(r["newton_iterations"]) == t["iterations"] > 0
        assert float(r["monitor"]) == pytest.approx(t["monitor"])
        assert (float(r["load_factor"]) == 1.0) == (r["stable"] == "1")
    for name in ("strength_reduction.png", "failure_mechanism.png"):
        assert (out / name).stat().st_size > 1000
    if MPI.COMM_WORLD.rank == 0:
        fields = _h5_fields(out)
        assert set(FIELDS) <= set(fields)
        shear = fields["plastic_shear_strain"]
        assert np.isfinite(shear).all() and shear.max() > 0.0
        # a cell mean never exceeds the largest quadrature-point value
        assert shear.max() <= entry["last_stable"]["max_plastic_shear_strain"] * (1 + 1e-12)
        assert json.loads((out / "summary.json").read_text())["results"]["plasticity"]


@pytest.mark.parametrize(
    ("override", "key"),
    [
        ('plasticity.ground_reaction.probe="nope"', "plasticity.ground_reaction.probe"),
        ('plasticity.ground_reaction.group="outer"', "plasticity.ground_reaction.group"),
        ('plasticity.ground_reaction.group="rock"', "plasticity.ground_reaction.group"),
        ("plasticity.ground_reaction.outer_radius=0.5", "plasticity.ground_reaction.outer_radius"),
        ("plasticity.ground_reaction.centre=[1.0, 0.0]", "plasticity.ground_reaction.centre"),
        ("plasticity.ground_reaction.bogus=1", "plasticity.ground_reaction.bogus"),
        ("initial_stress.stress=[-10.0, -5.0, 0.0]", "plasticity.ground_reaction"),
        ('initial_stress.loaded=["outer"]', "plasticity.ground_reaction"),
        ("plasticity.strength_reduction=true", "plasticity.ground_reaction"),
        ('output.fields=["stress_nodal"]', "output.fields"),
    ],
)
def test_bad_ground_reaction_named_before_meshing(override: str, key: str) -> None:
    """Each bad entry is refused by the loader, naming its key."""
    with pytest.raises(SceneError) as info:
        load_scene(OPENING, [override])
    assert info.value.key == key, info.value


def test_a_scene_without_probes_runs() -> None:
    """No ``output.probes``: the steps carry no probes and the run still ends.

    (The probe history of zero points once failed to build its rows.)
    """
    from tests.fem.helpers import solve_job

    solution = solve_job(
        "footing_prandtl",
        "output.probes={}",
        "geometry.parameters.h=1.0",
        "geometry.parameters.hf=0.2",
        "plasticity.load_steps=4",
    )
    try:
        plastic = solution.results["plasticity"]
    finally:
        solution.problem.destroy()
    assert plastic["converged"] and plastic["factor"] == 1.0 and plastic["steps"]
    assert all("probes" not in step for step in plastic["steps"])


@pytest.mark.parametrize(
    "comm",
    [
        pytest.param(MPI.COMM_SELF, id="self"),
        pytest.param(MPI.COMM_WORLD, id="world", marks=pytest.mark.mpi(min_size=2)),
    ],
)
def test_removed_cells_are_not_drawn(comm) -> None:
    """The pictures of a staged run leave the excavated cells blank (``alive`` = 0).

    The unit square, its cells left of x = 0.5 removed: the gathered triangles cover the
    right half (area 0.5), every cell once, on 1 rank and gathered from 2.
    """
    import dolfinx

    from geofrac.fem.plastic_outputs import cell_triangles

    mesh = dolfinx.mesh.create_unit_square(comm, 8, 8)
    Q = dolfinx.fem.functionspace(mesh, ("DG", 0))
    fn, alive = dolfinx.fem.Function(Q), dolfinx.fem.Function(Q)
    fn.interpolate(lambda x: x[0])
    alive.interpolate(lambda x: (x[0] > 0.5).astype(float))
    gathered = cell_triangles(fn, alive=alive)
    if comm.rank != 0:
        assert gathered is None
        return
    assert gathered is not None
    xy, values = gathered
    p = xy.reshape(-1, 3, 2)
    e1, e2 = p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]
    area = 0.5 * np.abs(e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0])
    assert len(values) == 64  # half of the 128 triangles
    assert area.sum() == pytest.approx(0.5, rel=1e-12)
    assert values.min() > 0.5  # only the right half's cell means
