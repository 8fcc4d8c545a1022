"""The dfn3d effect: scene keys, the size estimate, and a small jointed cube on 1 and 2 ranks.

A coarse version of jobs/dfn3d_triaxial.toml (the same network, sizes 5 and 2, two load
steps) runs in seconds: its network statistics are the sets' within their sampling
bands, its estimate is within 2x of the mesh, and 2 ranks give the same network, mesh
and reactions as 1.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from mpi4py import MPI

from geofrac.effects import result_lines
from geofrac.meshing.distribute import build_mesh
from geofrac.model.errors import SceneError
from geofrac.runner import solve_scene
from geofrac.scene import load_scene_collective
from tests.conftest import JOBS

SCENE = JOBS / "dfn3d_triaxial.toml"
COARSE = (
    "dfn3d.mesh_size=5.0",
    "dfn3d.fracture_mesh_size=2.0",
    "dfn3d.transition=2.0",
    "plasticity.load_steps=2",
)


def _solve(comm: MPI.Comm, *overrides: str) -> dict:
    scene = load_scene_collective(comm, SCENE, (*COARSE, *overrides))
    solution = solve_scene(scene, comm, verbose=False)
    solution.problem.destroy()
    return solution.results


@pytest.mark.parametrize(
    ("override", "key"),
    [
        ("dfn3d.box=[0, 0, 0, 1, 1]", "dfn3d.box"),
        ("dfn3d.box=[0, 0, 0, 1, -1, 1]", "dfn3d.box"),
        ("dfn3d.algorithm3d='frontal'", "dfn3d.algorithm3d"),
        ("dfn3d.tolerance=5.0", "dfn3d.tolerance"),
        ("dfn3d.fracture_mesh_size=3.0", "dfn3d.fracture_mesh_size"),
        ("dfn3d.sizes=1", "dfn3d.sizes"),
        ("dfn3d.sets=[{name='xmin', trend=0, plunge=80, radius_min=1, count=3}]", "dfn3d.sets"),
        ("dfn3d.sets=[{name='a', trend=0, plunge=80, radius_min=1, count=3, p32=1}]", "sets[0]"),
        ("dfn3d.sets=[{name='a', trend=0, plunge=95, radius_min=1, count=3}]", "sets[0]"),
        ("dfn3d.file='no_such_file.csv'", "dfn3d.file"),
    ],
)
def test_bad_tables_are_refused_naming_the_key(override: str, key: str) -> None:
    """Each bad ``[dfn3d]`` value is a SceneError naming its key, before any meshing."""
    with pytest.raises(SceneError, match=key.replace("[", r"\[").replace("]", r"\]")):
        load_scene_collective(MPI.COMM_SELF, SCENE, ("dfn3d.mesh_size=2.0", override))


def test_coarse_cube_statistics_and_estimate() -> None:
    """The sets' P32 within their exact bounds, κ̂ and mean poles in their 99 % bands."""
    results = _solve(MPI.COMM_SELF)
    report = results["geometry"]
    for name, got in report["sets"].items():
        low, high = got["p32_bounds"]
        assert low <= got["p32"] <= high + 1e-12, name
        assert got["kappa_in_band"] and got["mean_in_band"], name
        assert got["radius_ks_p"] > 0.01, name
    scene = load_scene_collective(MPI.COMM_SELF, SCENE, COARSE)
    estimate = scene.geometry.builder.estimate_cells()
    assert 0.5 <= estimate / report["tetrahedra"] <= 2.0
    full = load_scene_collective(MPI.COMM_SELF, SCENE, ())  # the scene's own sizes
    cells = build_mesh(full.geometry, MPI.COMM_SELF).report["tetrahedra"]
    assert 0.5 <= full.geometry.builder.estimate_cells() / cells <= 2.0
    joints = results["plasticity"]["joints"]
    assert joints["pairs"] > 0 and joints["open"] == 0  # all closed under confinement
    lines = result_lines(scene, results)  # the result block: the sets, then the joints
    assert any(line.startswith("set J1: Fisher") and "inside" in line for line in lines)
    assert any(f"{joints['pairs']} node pairs, {joints['slipping']} slipping" in x for x in lines)
    assert math.isfinite(report["min_dihedral_deg"]) and report["min_dihedral_deg"] > 0


@pytest.mark.mpi(min_size=2)
def test_two_ranks_give_the_same_network_mesh_and_reactions() -> None:
    """The geometry report (network, cleaning, mesh) is identical; reactions to 1e-10.

    Newton is taken to |F| <= 1e-13 (relative), so the two differ by round-off only.
    """
    comm = MPI.COMM_WORLD
    tight = "solver.options={snes_rtol=1e-13, snes_atol=1e-13}"
    many = _solve(comm, tight)
    one = _solve(MPI.COMM_SELF, tight) if comm.rank == 0 else None
    one = comm.bcast(one, root=0)
    drop = ("time_",)
    same = {k: v for k, v in one["geometry"].items() if not k.startswith(drop)}
    got = {k: v for k, v in many["geometry"].items() if not k.startswith(drop)}
    assert got.keys() == same.keys()
    for key, value in same.items():
        assert got[key] == value, key
    a = np.array([s["reactions"]["zmax"][2] for s in one["plasticity"]["steps"]])
    b = np.array([s["reactions"]["zmax"][2] for s in many["plasticity"]["steps"]])
    assert np.max(np.abs(a - b)) <= 1e-10 * np.max(np.abs(a))
    for key in ("pairs", "slipping", "open"):
        assert many["plasticity"]["joints"][key] == one["plasticity"]["joints"][key]
