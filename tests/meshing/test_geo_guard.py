"""Geometry files are data from possibly untrusted users.

The .geo scanner, time limits, parameter bounds, overlapping groups and never-empty
meshing errors.
"""

import re
import time
from pathlib import Path

import pytest

from geofrac.meshing.geo import (
    GmshTimeout,
    MeshingFailed,
    gmsh_session,
    inspect_geometry,
    meshed_model,
)
from geofrac.meshing.geo_guard import (
    GeoRefused,
    check_parameters,
    count_parameters,
    parameter_specs,
    scan_geo,
    tokenize,
)
from tests.conftest import REPO

SQUARE = "Point(1) = {0, 0, 0};\nPoint(2) = {1, 0, 0};\nLine(1) = {1, 2};\n"


def _geo(tmp_path: Path, text: str, name: str = "x.geo") -> Path:
    path = tmp_path / name
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(text)
    return path


@pytest.mark.parametrize(
    ("statement", "why"),
    [
        ('System "touch PWNED";', "'System' runs a program"),
        ('SystemCall "touch PWNED";', "'SystemCall' runs a program"),
        ('NonBlockingSystemCall "touch PWNED";', "runs a program"),
        ('OnelabRun("x", "touch PWNED");', "runs a program"),
        ("Exit;", "'Exit' ends the gmsh interpreter"),
        ("Abort;", "'Abort' ends the gmsh interpreter"),
        ('Printf("x") > "PWNED";', "'Printf(...) >' writes a file"),
        ('Printf("%g", 1) >> "PWNED";', "'Printf(...) >>' writes a file"),
        ('Save "PWNED.msh";', "'Save' writes a file"),
        ('Save View[0] "PWNED.pos";', "'Save' writes a file"),
        ('Print "PWNED.png";', "'Print' writes a file"),
        ('CreateDir "PWNED";', "creates a directory"),
        ('DeleteFile "x";', "deletes a file"),
        ("Delete File;", "deletes a file"),
        ('RenameFile "a" "b";', "renames a file"),
        ('Merge "other.msh";', "reads another file"),
        ('MergeWithBoundingBox "other.msh";', "reads another file"),
        ('v() = ShapeFromFile("x.step");', "reads another file"),
        ("Sleep 1e9;", "pauses gmsh"),
        ("Plugin(Skin).Run;", "plugin"),
        ('S2N["SystemCall"] "touch PWNED";', "cannot be checked"),
        ('General.OptionsFileName = "PWNED";', "'General.*' options"),
        ("General.SaveOptions = 1;", "'General.*' options"),
        ('Solver.Executable0 = "/bin/sh";', "'Solver.*' options"),
        ('Include StrCat("a", ".geo");', "computed file name"),
    ],
)
def test_statements_that_act_outside_the_geometry_are_refused(tmp_path, statement, why):
    path = _geo(tmp_path, SQUARE + "\n" + statement + "\n")
    with pytest.raises(GeoRefused) as err:
        scan_geo(path)
    message = str(err.value)
    assert why in message
    assert message.startswith(f"{path}:5: ") or message.startswith("x.geo:5: ")
    assert message.endswith("geometry files are data (set geometry.trusted = true to allow it)")
    assert "\n" not in message


@pytest.mark.parametrize(
    "text",
    [
        '// SystemCall "touch PWNED";\n',
        '/* Exit;\n Save "x"; */\n',
        "Printf(\"SystemCall 'touch PWNED' and Exit;\");\n",
        'Printf("x = %g", 1);\n',
        "Print.Width = 800;\n",
        "t = General.Terminal;\n",
        "Mesh.MeshSizeMax = 0.1;\nGeometry.Tolerance = 1e-8;\n",
        "If (1 > 0)\n  x = 1;\nEndIf\nDelete Physicals;\n",
    ],
)
def test_harmless_text_passes(tmp_path, text):
    scan_geo(_geo(tmp_path, SQUARE + text))


def test_project_geometry_files_pass_on_their_own_merits():
    for path in sorted((REPO / "meshes").glob("*.geo")):
        assert scan_geo(path) == [path.resolve()]


def test_lexer_follows_gmsh_strings_and_comments():
    tokens = tokenize('a = "x // y"; // z\nb = \'q"\'; /* c\n d */ e')
    assert [t.text for t in tokens] == ["a", "=", "x // y", ";", "b", "=", 'q"', ";", "e"]
    assert [t.line for t in tokens][-1] == 3


@pytest.mark.parametrize(
    ("text", "why"),
    [
        ('// x\0\nSystemCall "touch PWNED";\n', "NUL byte"),
        ('s = "' + "a" * 1100 + '";\n', "longer than"),
        ("/* never closed\n", "unterminated /* comment"),
        ('s = "never closed;\n', "unterminated string"),
    ],
)
def test_text_gmsh_would_read_differently_is_refused(tmp_path, text, why):
    with pytest.raises(GeoRefused, match=re.escape(why)):
        scan_geo(_geo(tmp_path, text))


def test_includes_are_scanned_and_stay_in_the_tree(tmp_path):
    root = tmp_path / "scene"
    main = _geo(root, 'Include "parts/a.geo";\n', "main.geo")
    _geo(root, "x = 1;\n", "parts/a.geo")
    assert [p.name for p in scan_geo(main)] == ["main.geo", "a.geo"]

    _geo(root, '\n\nSystemCall "touch PWNED";\n', "parts/a.geo")
    with pytest.raises(GeoRefused, match=r"a\.geo:3: 'SystemCall' runs a program"):
        scan_geo(main)

    _geo(tmp_path, "x = 1;\n", "outside.geo")
    _geo(root, 'Include "../outside.geo";\n', "main.geo")
    with pytest.raises(GeoRefused, match="reads a file outside"):
        scan_geo(main)

    _geo(root, 'Include "missing.geo";\n', "main.geo")
    with pytest.raises(GeoRefused, match="no such file"):
        scan_geo(main)

    _geo(root, 'Include "parts/a.geo";\n', "main.geo")
    _geo(root, 'Include "b.geo";\n', "parts/a.geo")
    _geo(root, 'Include "a.geo";\n', "parts/b.geo")
    with pytest.raises(GeoRefused, match="includes itself"):
        scan_geo(main)


def test_an_include_through_a_symlink_out_of_the_tree_is_refused(tmp_path):
    _geo(tmp_path, 'SystemCall "touch PWNED";\n', "evil.geo")
    root = tmp_path / "scene"
    root.mkdir()
    (root / "link.geo").symlink_to(tmp_path / "evil.geo")
    main = _geo(root, 'Include "link.geo";\n', "main.geo")
    with pytest.raises(GeoRefused, match="outside"):
        scan_geo(main)


def test_inspect_refuses_before_gmsh_runs(tmp_path):
    pwned = tmp_path / "PWNED"
    path = _geo(tmp_path, SQUARE + f'SystemCall "touch {pwned}";\n')
    with pytest.raises(GeoRefused):
        inspect_geometry(path, {})
    assert not pwned.exists()


def test_an_endless_loop_stops_at_the_time_limit(tmp_path):
    path = _geo(tmp_path, SQUARE + "For i In {1 : 1e18}\n  x = i;\nEndFor\n")
    start = time.perf_counter()
    with pytest.raises(GmshTimeout) as err:
        inspect_geometry(path, {}, time_limit=1.0)
    assert time.perf_counter() - start < 20
    assert str(err.value) == (
        "gmsh did not finish reading 'x.geo' within 1 s (geometry.time_limit)"
    )
    with (
        pytest.raises(GmshTimeout, match=r"did not finish meshing 'x\.geo' within 1 s"),
        meshed_model(path, {}, None, dim=2, time_limit=1.0),
    ):
        pass


def test_exit_in_a_trusted_file_ends_only_the_child(tmp_path):
    path = _geo(tmp_path, SQUARE + "Exit;\n")
    with pytest.raises(RuntimeError, match=r"stopped reading 'x\.geo' without finishing"):
        inspect_geometry(path, {}, trusted=True)


def test_gmsh_errors_come_back_from_the_child(tmp_path):
    path = _geo(tmp_path, "Point(1) = {0, 0, 0;\n")
    with pytest.raises(RuntimeError, match="syntax error"):
        inspect_geometry(path, {})


def test_nx_1e20_silently_meshes_8_cells_so_it_is_refused():
    """Why the bound: gmsh turns nx + 1 into an overflowing int and ignores the line."""
    with gmsh_session(REPO / "meshes" / "cantilever.geo", {"nx": 1e20, "ny": 4}) as gmsh:
        gmsh.model.mesh.generate(2)
        assert sum(len(e) for e in gmsh.model.mesh.getElements(2)[1]) == 8
    text = (REPO / "meshes" / "cantilever.geo").read_text()
    errors = check_parameters({"nx": 1e20}, parameter_specs(text), count_parameters(text))
    assert errors and errors[0][0] == "nx" and "+-1e+09" in errors[0][1]


def test_parameter_rules():
    text = (
        'DefineConstant[ L = {10, Min 1, Max 5e2, Name "P/L"}, n = {4, Step 1},\n'
        "  r = {0.5, Range {0.1, 2, 0.1}}, h = 0.2, k = {3, Min 2 * a} ];\n"
        "Transfinite Curve{1, 2} = m + 1 Using Progression 1.1;\nLayers{q};\n"
        "Transfinite Curve{3} = L / h;\n"
    )
    specs, counts = parameter_specs(text), count_parameters(text)
    assert specs["L"].minimum == 1 and specs["L"].maximum == 500
    assert specs["n"].integer and not specs["r"].integer
    assert specs["r"].minimum == 0.1 and specs["r"].maximum == 2
    assert specs["k"].minimum is None  # an expression is not evaluated
    assert set(counts) == {"m", "q"}

    def errors(**values):
        return dict(check_parameters(values, specs, counts))

    assert errors(L=5, n=3, r=1, h=0.3, k=-1, m=10, q=2) == {}
    assert "must be >= 1" in errors(L=0.5)["L"]
    assert "must be <= 500" in errors(L=600)["L"]
    assert "Step 1" in errors(n=2.5)["n"]
    assert "Transfinite Curve{...} = m + 1" in errors(m=2.5)["m"]
    assert "Layers{q}" in errors(q=1.5)["q"]
    assert "finite" in errors(h=float("nan"))["h"]
    assert "+-1e+09" in errors(h=-2e9)["h"]


def test_overlapping_groups_are_reported(tmp_path):
    info = inspect_geometry(REPO / "meshes" / "square.geo", {})
    assert (1, "boundary", "left", 4) in info.overlaps
    assert all(d == 1 for d, *_ in info.overlaps)


def test_overlapping_boundary_groups_each_keep_their_facets():
    import dolfinx
    import ufl
    from mpi4py import MPI

    from geofrac.meshing.distribute import build_mesh
    from geofrac.model.scene import Geometry

    info = inspect_geometry(REPO / "meshes" / "square.geo", {})
    geometry = Geometry(REPO / "meshes" / "square.geo", {"a": 5.0, "h": 1.0}, None, 2, info.groups)
    tagged = build_mesh(geometry, MPI.COMM_SELF)
    ds = ufl.Measure("ds", domain=tagged.mesh, subdomain_data=tagged.tags[1])
    one = dolfinx.fem.Constant(tagged.mesh, 1.0)
    length = {
        name: dolfinx.fem.assemble_scalar(dolfinx.fem.form(one * ds(tag)))
        for name, (dim, tag) in tagged.groups.items()
        if dim == 1
    }
    expected = {"boundary": 20.0, "left": 5.0, "right": 5.0, "top": 5.0, "bottom": 5.0}
    assert length == pytest.approx(expected)
    _, left = tagged.entities("left")
    _, boundary = tagged.entities("boundary")
    assert len(left) == 5 and len(boundary) == 20 and set(left) <= set(boundary)


def test_overlapping_cell_groups_are_a_scene_error(tmp_path):
    from geofrac.scene import SceneError, load_scene

    _geo(
        tmp_path,
        SQUARE.replace("Line(1) = {1, 2};\n", "")
        + "Point(3) = {1, 1, 0};\nLine(1) = {1, 2};\nLine(2) = {2, 3};\nLine(3) = {3, 1};\n"
        + "Curve Loop(1) = {1, 2, 3};\nPlane Surface(1) = {1};\n"
        + 'Physical Surface("domain") = {1};\nPhysical Surface("core") = {1};\n'
        + 'Physical Curve("fixed") = {3};\n',
    )
    scene = tmp_path / "s.toml"
    scene.write_text(
        '[geometry]\nfile = "x.geo"\n[material]\nE = 1.0\nnu = 0.2\n'
        '[discretization]\nelement = "cst"\n[[bc]]\ngroup = "fixed"\nvalue = [0.0, 0.0]\n'
    )
    with pytest.raises(SceneError, match=r"groups 'domain' and 'core' of 'x\.geo' share surface 1"):
        load_scene(scene)


def test_a_silent_gmsh_failure_says_what_was_done(monkeypatch):
    from geofrac.meshing import geo

    def silent(*args, **kwargs):
        raise RuntimeError("")

    monkeypatch.setattr(geo, "_run_worker", silent)
    path = REPO / "meshes" / "square.geo"
    with pytest.raises(MeshingFailed) as err, meshed_model(path, {"h": 0.5}, None, dim=2):
        pass
    assert str(err.value) == (
        "meshing square.geo with parameters {'h': 0.5} failed (gmsh gave no message; "
        f"run gmsh {path} -2 to see its log)"
    )


def test_failure_message_falls_back_to_the_gmsh_log():
    from geofrac.meshing.geo import failure_message

    class Log:
        @staticmethod
        def get():
            return ["Info    : Meshing", "Error   : Unable to recover the edge 3"]

    class Gmsh:
        logger = Log()

    assert failure_message(Exception("  "), Gmsh()) == "Unable to recover the edge 3"
    assert failure_message(Exception("boom"), Gmsh()) == "boom"
    assert failure_message(Exception(""), None) == ""


def test_a_meshed_geo_matches_the_in_process_mesh_exactly():
    import numpy as np

    path = REPO / "meshes" / "plate_hole.geo"
    with gmsh_session(path, {"h": 5.0}) as gmsh:
        gmsh.model.mesh.generate(2)
        tags0, x0, _ = gmsh.model.mesh.getNodes()
    with meshed_model(path, {"h": 5.0}, None, dim=2) as gmsh:
        tags1, x1, _ = gmsh.model.mesh.getNodes()
    assert np.array_equal(tags0, tags1) and np.array_equal(x0, x1)
