"""Results do not depend on the number of ranks; errors stop every rank together.

Run on 2 ranks: ``mpiexec -n 2 python -m mpi4py -m pytest --only-mpi``. Each test
compares a COMM_WORLD run with a COMM_SELF run on rank 0 (the 1-rank reference).
"""

import json

import dolfinx_solver  # noqa: F401

import numpy as np
import pytest
from mpi4py import MPI

from geofrac.errors import RunError
from geofrac.pipeline import run_scene
from geofrac.runner import solve_scene
from geofrac.scene import SceneError, load_scene_collective
from tests.conftest import BROKEN, JOBS

WORLD = MPI.COMM_WORLD
pytestmark = pytest.mark.mpi(min_size=2)


def _serial_reference(overrides, key, job="quickstart"):
    """Solve ``jobs/<job>.toml`` on COMM_SELF on rank 0; broadcast ``key(results)``."""
    value = None
    if WORLD.rank == 0:
        scene = load_scene_collective(MPI.COMM_SELF, JOBS / f"{job}.toml", overrides)
        sol = solve_scene(scene, MPI.COMM_SELF, verbose=False)
        value = key(sol.results)
        sol.problem.destroy()
    return WORLD.bcast(value, root=0)


@pytest.mark.parametrize("element", ["cst", "p2", "rgnt", "gnt"])
def test_quickstart_same_on_one_and_n_ranks(element):
    overrides = [f"discretization.element={element}"]
    serial = _serial_reference(overrides, _key_numbers)
    scene = load_scene_collective(WORLD, JOBS / "quickstart.toml", overrides)
    sol = solve_scene(scene, WORLD, verbose=False)
    assert (
        sol.tagged.mesh.topology.index_map(2).size_local < sol.mesh_counts()["cells"]
    )  # really split
    parallel = _key_numbers(sol.results)
    sol.problem.destroy()
    tip, energy, error_u, u_norm = parallel
    assert tip == pytest.approx(serial[0], rel=1e-10)
    assert energy == pytest.approx(serial[1], rel=1e-10)
    # |e_1 - e_N| <= ||u_1 - u_N||: round-off in u, measured against the solution's size
    assert abs(error_u - serial[2]) < 1e-10 * u_norm
    # every rank holds the same numbers
    gathered = WORLD.allgather(parallel)
    assert all(g == gathered[0] for g in gathered)


def test_rgnq_box_same_on_one_and_n_ranks():
    overrides = ["geometry.parameters.n=3"]
    serial = _serial_reference(overrides, _box_numbers, job="mms3d")
    scene = load_scene_collective(WORLD, JOBS / "mms3d.toml", overrides)
    sol = solve_scene(scene, WORLD, verbose=False)
    assert sol.tagged.mesh.topology.index_map(3).size_local < sol.mesh_counts()["cells"]
    parallel = _box_numbers(sol.results)
    sol.problem.destroy()
    assert parallel[0] == pytest.approx(serial[0], rel=1e-10, abs=1e-10 * abs(serial[0][2]))
    assert parallel[1] == pytest.approx(serial[1], rel=1e-10)
    assert abs(parallel[2] - serial[2]) < 1e-10 * parallel[3]


def _box_numbers(results):
    e = results["errors"]
    return (results["probes"]["centre"], results["strain_energy"], e["u"], e["u_norm"])


def _key_numbers(results):
    e = results["errors"]
    return (results["probes"]["tip"][1], results["strain_energy"], e["u"], e["u_norm"])


def test_iterative_solver_same_on_one_and_n_ranks():
    overrides = ["solver.preset=iterative"]
    serial = _serial_reference(overrides, lambda r: r["probes"]["tip"][1])
    scene = load_scene_collective(WORLD, JOBS / "quickstart.toml", overrides)
    sol = solve_scene(scene, WORLD, verbose=False)
    tip = sol.results["probes"]["tip"][1]
    sol.problem.destroy()
    assert tip == pytest.approx(serial, rel=1e-8)


def test_scene_error_is_raised_on_every_rank_with_the_same_message():
    try:
        load_scene_collective(WORLD, BROKEN / "unknown_group.toml")
        message = None
    except SceneError as exc:
        message = str(exc)
    messages = WORLD.allgather(message)
    assert messages[0] is not None and "bc[0].group" in messages[0]
    assert all(m == messages[0] for m in messages)


def test_run_errors_stop_every_rank(mpi_tmp_path):
    scene = load_scene_collective(
        WORLD,
        JOBS / "cantilever.toml",
        ["bc.0.value=[0.0]", 'bc.0.components=["x"]'],
        out=mpi_tmp_path / "singular",
    )
    with pytest.raises(RunError, match="singular"):
        run_scene(scene, WORLD, verbose=False)
    WORLD.barrier()
    summary = json.loads((mpi_tmp_path / "singular" / "incomplete" / "summary.json").read_text())
    assert summary["status"].startswith("error:") and summary["ranks"] == WORLD.size


def test_output_on_n_ranks_is_the_whole_mesh(mpi_tmp_path):
    import meshio

    scene = load_scene_collective(WORLD, JOBS / "quickstart.toml", out=mpi_tmp_path / "q")
    summary = run_scene(scene, WORLD, verbose=False)
    if WORLD.rank == 0:
        with meshio.xdmf.TimeSeriesReader(mpi_tmp_path / "q" / "results.xdmf") as reader:
            points, cells = reader.read_points_cells()
            _, point_data, cell_data = reader.read_data(0)
        assert len(points) == summary["mesh"]["vertices"] == 205
        assert sum(len(c.data) for c in cells) == summary["mesh"]["cells"] == 320
        tip = np.argmin(np.linalg.norm(points - [10.0, 0.0], axis=1))
        assert point_data["displacement"][tip, 1] == pytest.approx(
            summary["results"]["probes"]["tip"][1], rel=1e-10
        )
        assert set(cell_data) == {"stress", "von_mises"}


def test_bench_records_match_serial(mpi_tmp_path):
    from geofrac.bench import load_bench
    from geofrac.cli import _parser

    argv = ["bench", "cantilever", "--elements", "cst,p2", "--meshes", "4,6", "--repeat", "1"]
    args = _parser().parse_args([*argv, "--out", str(mpi_tmp_path / "par")])
    parallel = load_bench("cantilever").run(args, WORLD)
    serial = None
    if WORLD.rank == 0:
        args = _parser().parse_args([*argv, "--out", str(mpi_tmp_path / "ser")])
        serial = load_bench("cantilever").run(args, MPI.COMM_SELF)
    serial = WORLD.bcast(serial, root=0)
    assert parallel["ranks"] == WORLD.size and serial["ranks"] == 1
    for p, s in zip(parallel["records"], serial["records"], strict=True):
        assert (p["element"], p["mesh"], p["nodes"], p["dofs"]) == (
            s["element"],
            s["mesh"],
            s["nodes"],
            s["dofs"],
        )
        # differences of error norms are bounded by round-off in u (|u| ~ 60 here, see above)
        assert abs(p["error_u"] - s["error_u"]) < 1e-8
        assert abs(p["error_energy"] - s["error_energy"]) < 1e-8
        assert p["error_u"] == pytest.approx(s["error_u"], rel=1e-4)


def test_group_outside_the_domain_is_an_error_not_an_abort(mpi_tmp_path):
    scene = load_scene_collective(
        WORLD, JOBS.parent / "tests" / "scenes" / "stray_curve.toml", out=mpi_tmp_path / "s"
    )
    with pytest.raises(RunError, match="physical group 'stray'"):
        run_scene(scene, WORLD, verbose=False)


def _fracture_cover(comm):
    from geofrac.meshing.distribute import build_mesh, check_fracture_cover

    overrides = ["dfn.mesh_size=3.0", "dfn.tolerance=0.21"]
    scene = load_scene_collective(comm, JOBS / "dfn_model2.toml", overrides)
    tagged = build_mesh(scene.geometry, comm)
    cover = check_fracture_cover(tagged)
    dim, facets = tagged.entities("fractures")
    xy = tagged.vertex_coordinates(dim, tagged.owned(dim, facets))[:, :, :2]
    from geofrac.dfn.check import covered_length

    lengths = comm.allreduce(covered_length(xy, tagged.fractures), op=MPI.SUM)
    owned_cells = tagged.mesh.topology.index_map(2).size_local
    return cover["fracture_facets"], lengths, owned_cells, tagged.num_global(2)


def test_dfn_fracture_facets_same_on_one_and_n_ranks():
    serial = None
    if WORLD.rank == 0:
        serial = _fracture_cover(MPI.COMM_SELF)[:2]
    serial = WORLD.bcast(serial, root=0)
    count, lengths, owned_cells, cells = _fracture_cover(WORLD)
    assert owned_cells < cells  # the mesh really is split
    assert count == serial[0] > 500
    np.testing.assert_allclose(lengths, serial[1], rtol=1e-12)
    assert WORLD.allgather(count) == [count] * WORLD.size
