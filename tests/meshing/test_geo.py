import pytest

from geofrac.meshing.geo import define_constants, gmsh_session, inspect_geometry
from tests.conftest import REPO


def test_define_constants_reads_plain_and_named_entries():
    text = 'DefineConstant[ L = {10, Name "Parameters/L", Min 1, Max 5}, nx = 40 ];\nx = 3;'
    assert define_constants(text) == ["L", "nx"]
    assert define_constants("Point(1) = {0, 0, 0};") == []


def test_cantilever_geo_declares_its_parameters():
    text = (REPO / "meshes" / "cantilever.geo").read_text()
    assert define_constants(text) == ["L", "D", "nx", "ny"]


def test_parameters_reach_the_geometry():
    path = REPO / "meshes" / "cantilever.geo"
    with gmsh_session(path, {"nx": 10, "ny": 2, "L": 4.0}) as gmsh:
        gmsh.model.mesh.generate(2)
        nodes = gmsh.model.mesh.getNodes()[1].reshape(-1, 3)
    assert len(nodes) == 11 * 3
    assert nodes[:, 0].max() == pytest.approx(4.0)


def test_parameters_do_not_leak_into_the_next_session():
    path = REPO / "meshes" / "cantilever.geo"
    with gmsh_session(path, {"L": 4.0}) as gmsh:
        assert gmsh.parser.getNumber("L") == [4.0]
    with gmsh_session(path, {}) as gmsh:
        assert gmsh.parser.getNumber("L") == [10.0]  # the file's default again


def test_inspect_reports_dimension_and_groups():
    info = inspect_geometry(REPO / "meshes" / "square.geo", {})
    assert info.dim == 2
    assert info.groups["domain"] == 2 and info.groups["boundary"] == 1


def test_unreadable_geo_raises(tmp_path):
    bad = tmp_path / "bad.geo"
    bad.write_text("Point(1) = {0, 0, 0;\n")
    with pytest.raises(RuntimeError, match="syntax error"):
        inspect_geometry(bad, {})


def test_msh_file_is_used_as_is(tmp_path):
    """A mesh exported from gmsh runs unchanged: same cells and same answer as the .geo."""
    from mpi4py import MPI

    from geofrac.runner import solve_scene
    from geofrac.scene import load_scene
    from tests.conftest import JOBS

    with gmsh_session(REPO / "meshes" / "cantilever.geo", {"nx": 20, "ny": 2}) as gmsh:
        gmsh.model.mesh.generate(2)
        # binary: gmsh's ASCII .msh prints 16 significant digits, which moves 27 of these
        # node coordinates by one ulp (and the tip deflection by 1.1e-12 relative)
        gmsh.option.setNumber("Mesh.Binary", 1)
        gmsh.write(str(tmp_path / "beam.msh"))
    results = []
    for geometry in (
        ["geometry.parameters.nx=20", "geometry.parameters.ny=2"],
        [
            f"geometry.file='{tmp_path / 'beam.msh'}'",
            "geometry.parameters={}",
            "exact.L=10.0",
            "exact.D=1.0",
        ],
    ):
        scene = load_scene(JOBS / "cantilever.toml", geometry)
        sol = solve_scene(scene, MPI.COMM_SELF, verbose=False)
        results.append((sol.mesh_counts()["cells"], sol.results["probes"]["tip"][1]))
        sol.problem.destroy()
    assert results[0][0] == results[1][0] == 80
    assert results[1][1] == pytest.approx(results[0][1], rel=1e-12)


def test_group_outside_the_domain_is_an_error_not_an_abort(tmp_path):
    from mpi4py import MPI

    from geofrac.errors import RunError
    from geofrac.pipeline import run_scene
    from geofrac.scene import load_scene

    scene = load_scene(REPO / "tests" / "scenes" / "stray_curve.toml", out=tmp_path / "out")
    with pytest.raises(RunError, match=r"physical group 'stray' has \d+ node\(s\) outside"):
        run_scene(scene, MPI.COMM_SELF, verbose=False)
    assert not (tmp_path / "out" / "results.xdmf").exists()


def test_the_mesh_dependence_specimens_declare_their_parameters():
    """Every DefineConstant is found (a comment inside the block would hide the next one)."""
    for name, expected in (
        ("brazilian_disc.geo", ["D", "strip_deg", "h"]),
        ("sym_notched_beam.geo", ["a", "w", "pad", "h", "h_fine", "band", "transition"]),
    ):
        assert define_constants((REPO / "meshes" / name).read_text()) == expected
