"""Curved (second-order) gmsh cells: only the elements that pass the patch test are accepted.

P2 and P3 represent them and run through output; every other element is refused at load
time with one line.

The scene (scenes/curved_patch.toml) is a quarter annulus 1 <= r <= 2 whose arcs are
circles, meshed with ``Mesh.ElementOrder = order``, with the displacement of a uniform
strain held on its whole boundary: an element that represents the cells reproduces the
uniform strain to round-off (the constant-strain patch test, Edo (2016) section 2.4.2).
"""

import dataclasses
import json
from pathlib import Path

import dolfinx_solver  # noqa: F401

import meshio
import numpy as np
import pytest
from mpi4py import MPI

from geofrac import elements
from geofrac.runner import solve_scene
from geofrac.scene import SceneError, load_scene_collective

SCENE = Path(__file__).resolve().parent / "scenes" / "curved_patch.toml"
#: the uniform strain of the scene's [exact] table (εxx, εyy, γxy)
STRAIN = (0.002, -0.0006, 0.001)
#: (element, geometry order) for every 2D element and the curved orders 2 and 3
CASES = [(n, k) for n in elements.available() if 2 in elements.get(n).dims for k in (2, 3)]


def _accepted(name: str, order: int) -> bool:
    """Whether the loader accepts element ``name`` on cells of ``order``."""
    try:
        load_scene_collective(
            MPI.COMM_SELF,
            SCENE,
            [f"discretization.element={name}", f"geometry.parameters.order={order}"],
        )
    except SceneError:
        return False
    return True


def _patch_error(name: str, order: int, comm: MPI.Comm) -> float:
    """Relative L2 displacement error of element ``name`` on cells of ``order``.

    The scene is loaded on straight cells (accepted for every element) and then given
    the curved geometry, so that an element the loader refuses can be measured too.
    """
    scene = load_scene_collective(
        comm, SCENE, [f"discretization.element={name}", "geometry.parameters.order=1"]
    )
    geometry = dataclasses.replace(
        scene.geometry, parameters={**scene.geometry.parameters, "order": order}, order=order
    )
    solution = solve_scene(dataclasses.replace(scene, geometry=geometry), comm, verbose=False)
    try:
        return float(solution.results["errors"]["u_relative"])
    finally:
        solution.problem.destroy()


@pytest.mark.parametrize(("name", "order"), CASES)
def test_an_element_is_accepted_on_curved_cells_exactly_when_it_passes_the_patch_test(name, order):
    """The refusal rule is the patch test.

    Accepted elements reproduce a uniform strain to round-off on curved cells, refused
    ones do not (CST, RGNT, GNT: ~2e-3; P2 on cubic cells: ~1e-4).
    """
    if _accepted(name, order):
        assert _patch_error(name, order, MPI.COMM_SELF) < 1e-12
    elif elements.get(name).hold != "nodes":  # EFMM's patches refuse to build on them
        assert _patch_error(name, order, MPI.COMM_SELF) > 1e-6


def test_p2_and_p3_represent_second_order_cells():
    assert _accepted("p2", 2) and _accepted("p3", 2) and _accepted("p3", 3)


@pytest.mark.mpi(min_size=2)
def test_p2_patch_test_on_curved_cells_on_n_ranks():
    assert _patch_error("p2", 2, MPI.COMM_WORLD) < 1e-12


def test_curved_run_ends_with_summary_and_readable_xdmf(cli, tmp_path):
    code, _, err = cli("run", SCENE, "--out", tmp_path, "-q")
    assert code == 0, err
    summary = json.loads((tmp_path / "summary.json").read_text())
    assert summary["results"]["errors"]["u_relative"] < 1e-12
    assert not list(tmp_path.glob("incomplete"))
    with meshio.xdmf.TimeSeriesReader(tmp_path / "results.xdmf") as reader:
        points, cells = reader.read_points_cells()
        _, point_data, cell_data = reader.read_data(0)
    assert [c.type for c in cells] == ["triangle6"]  # drawn curved by ParaView
    # the nodes on the arcs lie on the circles r = 1, 2 (mid-edge nodes included)
    r = np.linalg.norm(points, axis=1)
    on_arc = (np.abs(r - 1.0) < 1e-9) | (np.abs(r - 2.0) < 1e-9)
    assert on_arc.sum() > 2 * len(points) ** 0.5
    exx, eyy, gxy = STRAIN
    x, y = points[:, 0], points[:, 1]
    exact = np.stack([exx * x + 0.5 * gxy * y, 0.5 * gxy * x + eyy * y], axis=1)
    np.testing.assert_allclose(point_data["displacement"][:, :2], exact, atol=1e-14)
    # the nodal stress (interpolated to the geometry's nodes) is the uniform one
    nodal = point_data["stress_nodal"]
    np.testing.assert_allclose(nodal, np.broadcast_to(nodal[0], nodal.shape), atol=1e-11)
    assert cell_data["von_mises"][0].shape[0] == len(cells[0].data)


@pytest.mark.parametrize(
    "name",
    [n for n in elements.available() if 2 in elements.get(n).dims and not elements.get(n).curved],
)
def test_a_refused_element_gets_one_line_naming_it_and_the_fix(cli, name):
    code, _, err = cli("check", SCENE, "--set", f"discretization.element={name}")
    assert code == 2
    lines = err.strip().splitlines()
    assert len(lines) == 1
    assert f"element '{name}' cannot represent the curved cells" in lines[0]
    assert "use element 'p2' or 'p3', or Mesh.ElementOrder = 1" in lines[0]


def test_cracking_is_refused_on_curved_cells(cli):
    code, _, err = cli(
        "check",
        SCENE,
        "--set",
        'effects=["cracking"]',
        "--set",
        "material.tensile_strength=3.0",
    )
    assert code == 2 and len(err.strip().splitlines()) == 1
    assert "effect 'cracking' assumes straight cells" in err


def test_an_order_no_element_represents_is_refused(cli):
    code, _, err = cli("check", SCENE, "--set", "geometry.parameters.order=4")
    assert code == 2 and len(err.strip().splitlines()) == 1
    assert "geometry.file: no element represents the curved cells" in err


@pytest.mark.mpi(min_size=2)
def test_curved_run_on_n_ranks_writes_the_whole_mesh(cli, mpi_tmp_path):
    code, _, err = cli("run", SCENE, "--out", mpi_tmp_path, "-q")
    assert code == 0, err
    if MPI.COMM_WORLD.rank == 0:  # rank 0 writes summary.json
        summary = json.loads((mpi_tmp_path / "summary.json").read_text())
        assert summary["results"]["errors"]["u_relative"] < 1e-12
        with meshio.xdmf.TimeSeriesReader(mpi_tmp_path / "results.xdmf") as reader:
            points, cells = reader.read_points_cells()
        assert sum(len(c.data) for c in cells) == summary["mesh"]["cells"]
        assert len(points) == len(np.unique(points.round(12), axis=0))
