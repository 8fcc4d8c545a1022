"""The FEM method's result block (geofrac/runner.py FemMethod.result, geofrac/pipeline.report).

jobs/quickstart.toml, the Timoshenko cantilever: L = 10, D = 1, P = 1, E = 100, ν = 0.2,
plane stress; its tip deflects by P L³/(3EI) + (4 + 5ν) P D² L/(24 E I) = 40.25.
"""

import math

from mpi4py import MPI

from geofrac import pipeline
from geofrac.pipeline import run_scene
from geofrac.runner import FEM
from geofrac.scene import load_scene
from tests.conftest import JOBS


def _run(tmp_path, *overrides):
    scene = load_scene(JOBS / "quickstart.toml", list(overrides), out=tmp_path / "out")
    return scene, run_scene(scene, MPI.COMM_SELF, verbose=False)


def test_the_block_gives_the_probes_against_the_closed_form_in_the_scenes_unit(tmp_path):
    scene, summary = _run(tmp_path, "units.length=m")
    L, D, P, E, nu = 10.0, 1.0, 1.0, 100.0, 0.2
    inertia = D**3 / 12
    tip = P * L**3 / (3 * E * inertia) + (4 + 5 * nu) * P * D**2 * L / (24 * E * inertia)
    u = summary["results"]["probes"]["tip"]
    gap = math.hypot(u[0], u[1] - tip)
    lines = pipeline.report(FEM, summary, scene)
    k = lines.index("result:")  # the block, indented, right before the timings
    assert all(s.startswith("  ") for s in lines[k + 1 : -1]) and lines[-1].startswith("time: ")
    line = next(s for s in lines if s.startswith("  probe tip: "))
    assert "u = [" in line and "] m  (exact [0, 40.25]; " in line
    assert f"|difference| {gap:.3g} m, {100 * gap / tip:.3g} %" in line
    assert any(s.startswith("  accuracy: ||u - u_exact||_L2 = ") for s in lines)


def test_a_scene_without_units_prints_none(tmp_path):
    scene, summary = _run(tmp_path)
    assert scene.units.length == ""
    block = FEM.result(scene, summary)
    tip = next(s for s in block if s.startswith("probe tip: "))
    assert "] (exact" not in tip and "]  (exact [0, 40.25]; |difference| " in tip
    assert not any(" m," in s or "] m" in s for s in block)
