"""Size estimates: the caps, the trial meshes against real meshes, the formulas' anchors.

Every scene of jobs/ is well below every cap and, where it meshes a geometry file or a
DFN, estimated within a factor of 2 of its real mesh.

``python -m tests.scene.test_size`` prints the table of estimate against real count
of every ``jobs/`` scene with a geometry (docs/scenes.md, "Size estimate and caps").
"""

import functools
import math
import sys
import time
import tomllib
from pathlib import Path

import pytest

from geofrac.scene import SceneError, load_scene
from geofrac.scene.size import CAPS, TRIAL_CELLS, format_count
from tests.conftest import JOBS

#: Scenes of jobs/ left to ``-m slow`` in the test against real meshes. None takes long
#: (each is meshed in under a second); this is the largest, 35,000 cells.
SLOW_JOBS = frozenset({"dcn_plate.toml"})
#: A quarter plate with a hole, its sizes graded 50 times from the hole by a
#: Distance/Threshold field: the bounding box asks for 5.9e6 cells, gmsh makes 13,828.
GRADED_GEO = """\
DefineConstant[ W = {16.0, Name "Parameters/W"}, h_hole = {0.01, Name "Parameters/h_hole"},
  h_far = {0.5, Name "Parameters/h_far"} ];
Point(1) = {0, 0, 0, h_hole}; Point(2) = {1, 0, 0, h_hole}; Point(3) = {W, 0, 0, h_far};
Point(4) = {W, W, 0, h_far}; Point(5) = {0, W, 0, h_far}; Point(6) = {0, 1, 0, h_hole};
Line(1) = {2, 3}; Line(2) = {3, 4}; Line(3) = {4, 5}; Line(4) = {5, 6};
Circle(5) = {6, 1, 2};
Curve Loop(1) = {1, 2, 3, 4, 5}; Plane Surface(1) = {1};
Field[1] = Distance; Field[1].CurvesList = {5}; Field[1].Sampling = 200;
Field[2] = Threshold; Field[2].InField = 1; Field[2].SizeMin = h_hole;
Field[2].SizeMax = h_far; Field[2].DistMin = 0; Field[2].DistMax = 10;
Background Field = 2;
Mesh.MeshSizeExtendFromBoundary = 0; Mesh.MeshSizeFromPoints = 0;
Mesh.MeshSizeFromCurvature = 0;
Physical Surface("domain") = {1}; Physical Curve("left") = {4};
"""
GRADED_SCENE = """\
[geometry]
file = "graded.geo"
parameters = {parameters}
[material]
E = 1000.0
nu = 0.25
[discretization]
element = "cst"
[[bc]]
group = "left"
value = [0.0, 0.0]
"""


def _job_files() -> list[Path]:
    """The scenes of jobs/ and of its subdirectories that are not links to them."""
    files = sorted(JOBS.glob("*.toml"))
    known = {p.resolve() for p in files}
    for path in sorted(JOBS.glob("*/*.toml")):
        if path.resolve() not in known:
            known.add(path.resolve())
            files.append(path)
    return files


def _meshes_a_file(path: Path) -> bool:
    data = tomllib.loads(path.read_text())
    return isinstance(data.get("geometry"), dict) and "file" in data["geometry"]


@functools.cache
def _scene(path: Path):
    return load_scene(path)


def real_cells(geometry) -> int:
    """Cells of the mesh a run makes of ``geometry`` (its ``dim``-D physical groups).

    gmsh in this process (the files are ours) with what the run's child process sets:
    the parameters, ``mesh_size``, ``algorithm`` (:mod:`geofrac.meshing.geo_worker`).
    """
    parameters = tuple(sorted(geometry.parameters.items()))
    return _real_cells(geometry.file, parameters, geometry.mesh_size, geometry.algorithm)


@functools.cache
def _real_cells(file: Path, parameters: tuple, mesh_size: float | None, algorithm: str | None):
    from geofrac.meshing.geo import ALGORITHMS, gmsh_session

    with gmsh_session(file, dict(parameters), mesh_size) as gmsh:
        if algorithm is not None:
            gmsh.option.setNumber("Mesh.Algorithm", ALGORITHMS[algorithm])
        model, dim = gmsh.model, int(gmsh.model.getDimension())
        model.mesh.generate(dim)
        return _group_cells(model, dim)


def _group_cells(model, dim: int) -> int:
    """Elements of dimension ``dim`` in the physical groups of that dimension."""
    entities = {
        int(e)
        for _, tag in model.getPhysicalGroups(dim)
        for e in model.getEntitiesForPhysicalGroup(dim, tag)
    }
    return sum(len(t) for e in entities for t in model.mesh.getElements(dim, e)[1])


@functools.cache
def dfn_real_cells(path: Path) -> int:
    """Triangles of the mesh a run makes of a DFN scene: its builder at the full sizes."""
    from geofrac.meshing.geo import gmsh_session

    geometry = _scene(path).geometry
    with gmsh_session(None, geometry.parameters, geometry.mesh_size) as gmsh:
        geometry.builder.build(gmsh)
        return _group_cells(gmsh.model, geometry.dim)


def _cells(scene) -> float:
    q = scene.size.quantities
    return q["cells"] if "cells" in q else q["particles"]


def test_every_job_is_ten_times_below_every_cap():
    for path in _job_files():
        scene = _scene(path)
        assert scene.size is not None and scene.size.summary()
        for name, value in scene.size.quantities.items():
            if name in CAPS:
                assert value * 10 <= CAPS[name][0], (path.name, name, value)


def test_estimates_match_the_structured_meshes_and_the_terrain():
    quick = load_scene(JOBS / "quickstart.toml").size.quantities
    assert quick["cells"] == 320  # 40 x 4 squares, two triangles each
    assert quick["dofs"] == pytest.approx(2 * 4 * 160)  # P2: 2 x 4 nodes per vertex
    for element, per_vertex in (("cst", 2), ("rgnt", 3), ("gnt", 6)):  # (u, v), (u, v, θ), ...
        dofs = load_scene(JOBS / "quickstart.toml", [f"discretization.element={element}"])
        assert dofs.size.quantities["dofs"] == pytest.approx(per_vertex * 160), element
    bar = load_scene(JOBS / "mpm_bar_w1000.toml").size.quantities
    assert bar["particles"] == 100 and bar["grid_nodes"] == 59
    assert bar["steps"] == 500  # t_end 0.05, dt = 0.1 * 1 / sqrt(1e6 / 1)
    terrain = load_scene(JOBS / "terrain_100k.toml").size.quantities
    assert terrain["blocks"] == pytest.approx(100_643, rel=0.05)


FILE_JOBS = [p for p in _job_files() if _meshes_a_file(p)]


@pytest.mark.parametrize(
    "path",
    [pytest.param(p, marks=pytest.mark.slow) if p.name in SLOW_JOBS else p for p in FILE_JOBS],
    ids=lambda p: p.stem,
)
def test_every_job_with_a_geometry_file_is_estimated_within_two(path, monkeypatch):
    """As loaded, and from trial meshes aimed at 10 times fewer cells.

    Most of these scenes are small enough for the trial to mesh them in full; the
    coarser trials (k up to about 7 here) test the extrapolation on 14 of them.
    """
    import geofrac.scene.load as loader
    import geofrac.scene.size as sizes

    scene = _scene(path)
    real = real_cells(scene.geometry)
    assert "from a trial mesh" in scene.size.method, scene.size.method
    assert 0.5 <= _cells(scene) / real <= 2.0, (path.name, _cells(scene) / real)
    monkeypatch.setattr(sizes, "TRIAL_CELLS", TRIAL_CELLS / 10)
    monkeypatch.setattr(loader, "TRIAL_CELLS", TRIAL_CELLS / 10)
    coarse = load_scene(path)
    ratio = _cells(coarse) / real
    assert 0.5 <= ratio <= 2.0, (path.name, coarse.size.method, ratio)


DFN_JOBS = [p for p in _job_files() if "dfn" in tomllib.loads(p.read_text())]


@pytest.mark.parametrize("path", DFN_JOBS, ids=lambda p: p.stem)
def test_every_dfn_job_is_estimated_within_two(path, monkeypatch):
    """From the builder's trial meshes, as loaded and aimed at 2 times fewer cells.

    The real count is the run's mesh (the builder at the full sizes). As loaded, the
    seven larger scenes are extrapolated (k from 1.1 to 2.9) and three small ones meshed
    in full; aimed at 10,000 cells, k grows to 4.8 and the tunnel is extrapolated too.
    Not fewer: below about 5,000 cells the triangles that the fracture
    lines pin still grow as 1/k, not 1/k², and the Model 1 estimate reaches 3.4 times
    the real count. No gmsh session is left open.
    """
    import gmsh

    import geofrac.scene.load as loader
    import geofrac.scene.size as sizes

    scene = _scene(path)
    real = dfn_real_cells(path)
    assert "from a trial mesh" in scene.size.method, scene.size.method
    assert 0.5 <= _cells(scene) / real <= 2.0, (path.name, _cells(scene) / real)
    monkeypatch.setattr(sizes, "TRIAL_CELLS", TRIAL_CELLS / 2)
    monkeypatch.setattr(loader, "TRIAL_CELLS", TRIAL_CELLS / 2)
    coarse = load_scene(path)
    ratio = _cells(coarse) / real
    assert "from a trial mesh at" in coarse.size.method
    assert 0.5 <= ratio <= 2.0, (path.name, coarse.size.method, ratio)
    assert not gmsh.isInitialized()


def test_a_huge_dfn_request_is_refused_from_a_coarse_trial(monkeypatch):
    """Fine sizes are refused from small trials in seconds; too many fractures, untried."""
    from geofrac.meshing import geo_worker

    made = []
    meshes = geo_worker.trial_meshes

    def spy(*args, **kwargs):
        result = meshes(*args, **kwargs)
        made.extend(result)
        return result

    monkeypatch.setattr(geo_worker, "trial_meshes", spy)
    scene = JOBS / "crack_model1.toml"
    fine = ["dfn.fracture_mesh_size=0.005", "dfn.transition=20"]  # about 9e7 cells
    start = time.perf_counter()
    with pytest.raises(SceneError, match=r"dfn\.fracture_mesh_size: about .* cells is far beyond"):
        load_scene(scene, fine)
    assert made and all(n <= 4 * TRIAL_CELLS for _, n in made), made
    assert min(k for k, _ in made) > 50  # never meshed in full
    made.clear()
    with pytest.raises(SceneError, match=r"dfn\.mesh_size: about .* cells is far beyond"):
        load_scene(scene, ["dfn.mesh_size=0.05"])  # about 2.5e7 cells
    assert made and all(n <= 4 * TRIAL_CELLS for _, n in made), made
    assert min(k for k, _ in made) > 10
    assert time.perf_counter() - start < 20
    made.clear()
    start = time.perf_counter()
    with pytest.raises(SceneError, match="fractures is far beyond the cap"):
        load_scene(scene, ["dfn.sets.0.p21=1e4"])  # 1.4e7 fractures: neither drawn nor meshed
    assert not made
    assert time.perf_counter() - start < 1


@pytest.mark.parametrize(
    ("module", "name", "error"),
    [
        ("geofrac.meshing.geo_worker", "trial_meshes", Exception("Invalid boundary mesh")),
        ("geofrac.dfn.clean", "clean_network", "DfnError"),
    ],
)
def test_a_failed_dfn_trial_falls_back_on_the_area(monkeypatch, module, name, error):
    """When gmsh fails (a bare Exception) or the network cannot be cleaned: the area, and why."""
    import importlib

    import gmsh

    from geofrac.dfn.errors import DfnError

    if error == "DfnError":
        error = DfnError("the fracture network did not settle")

    def fails(*args, **kwargs):
        raise error

    monkeypatch.setattr(importlib.import_module(module), name, fails)
    scene = load_scene(JOBS / "joint_slip_opening.toml")
    assert scene.size.method == (
        f"estimate from the DFN domain's area (the trial mesh failed: {error})"
    )
    assert _cells(scene) == pytest.approx(2.31 * 12**2 / 1.5**2, rel=0.01)
    assert not gmsh.isInitialized()


def _graded(tmp_path: Path, parameters: str = "{}", *, hidden: bool = False) -> Path:
    """The graded plate's scene file, written with its ``.geo`` into ``tmp_path``.

    ``hidden``: only the size field has the fine size, under a name that the bounding
    box does not read (the points all take ``h_far``).
    """
    text = GRADED_GEO
    if hidden:
        text = text.replace(", h_hole}", ", h_far}").replace("h_hole", "fine")
    (tmp_path / "graded.geo").write_text(text)
    scene = tmp_path / "graded.toml"
    scene.write_text(GRADED_SCENE.format(parameters=parameters))
    return scene


def test_a_graded_plate_is_estimated_from_a_coarse_trial_within_two(tmp_path, monkeypatch):
    from geofrac.meshing import geo

    path = _graded(tmp_path)
    scene = load_scene(path)  # no allow_large: the bounding box said 5.9e6 cells
    assert "from a trial mesh at" in scene.size.method
    ratio = scene.size.quantities["cells"] / real_cells(scene.geometry)
    assert 0.5 <= ratio <= 2.0, ratio
    finer = load_scene(path, ["geometry.parameters.h_hole=0.005", "geometry.parameters.h_far=0.25"])
    assert "from a trial mesh at" in finer.size.method
    assert "full sizes" not in finer.size.method  # 83,000 cells: extrapolated from k > 1
    ratio = finer.size.quantities["cells"] / real_cells(finer.geometry)
    assert 0.5 <= ratio <= 2.0, ratio

    def late(*args, **kwargs):
        raise geo.GmshTimeout("too slow")

    monkeypatch.setattr(geo, "trial_counts", late)  # no trial: the bounding box, refused
    with pytest.raises(SceneError, match=r"about 5\.9e6 cells is far beyond the cap"):
        load_scene(path)
    scene = load_scene(path, allow_large=True)
    assert scene.size.method == (
        "estimate from the bounding box (the trial mesh did not finish within 20 s)"
    )


def test_sizes_only_a_field_asks_for_are_seen(tmp_path):
    """The bounding box sees only h_far (2,400 cells, 6 times too few); the trial sees all."""
    scene = load_scene(_graded(tmp_path, hidden=True))
    assert "from a trial mesh at" in scene.size.method
    ratio = scene.size.quantities["cells"] / real_cells(scene.geometry)
    assert 0.5 <= ratio <= 2.0, ratio


def test_sizes_that_do_not_shrink_the_mesh_are_seen():
    """A transfinite mesh keeps its count whatever the sizes: the fit's fixed part."""
    tiny = "geometry.mesh_size=1e-3"  # the bounding box: 2.3e7 cells
    assert _cells(load_scene(JOBS / "quickstart.toml", [tiny])) == 320
    big = [tiny, "geometry.parameters.nx=200", "geometry.parameters.ny=20"]
    scene = load_scene(JOBS / "quickstart.toml", big)
    assert "× the sizes" in scene.size.method and "full" not in scene.size.method
    assert _cells(scene) == pytest.approx(8000, rel=0.01)


def test_a_huge_request_is_refused_from_a_coarse_trial(tmp_path, monkeypatch):
    from geofrac.meshing import geo

    made = []
    counts = geo.trial_counts

    def spy(*args, **kwargs):
        result = counts(*args, **kwargs)
        made.extend(result)
        return result

    monkeypatch.setattr(geo, "trial_counts", spy)
    hostile = JOBS.parent / "tests" / "scenes" / "hostile" / "fem_cells_mesh_size.toml"
    with pytest.raises(SceneError, match="cells is far beyond the cap"):
        load_scene(hostile)
    assert made and all(n <= 4 * TRIAL_CELLS for _, n in made)
    assert min(k for k, _ in made) > 100  # never meshed in full
    made.clear()
    graded = _graded(tmp_path, "{ h_hole = 1e-5, h_far = 5e-4 }")  # about 1e10 cells
    scene = load_scene(graded, allow_large=True)
    assert scene.size.quantities["cells"] > 1e9
    assert made and all(n <= 4 * TRIAL_CELLS for _, n in made)
    assert min(k for k, _ in made) > 100


def _fake_gmsh(monkeypatch, fixed: float, scaling: float, *, dim: int, coarsest: float):
    """A gmsh whose mesh at size factor k has fixed + scaling / k^dim cells.

    Beyond k = ``coarsest`` it fails (a mesh too coarse for a detail of the geometry).
    """
    from types import SimpleNamespace

    from geofrac.meshing import geo_worker

    options = {"Mesh.MeshSizeFactor": 1.0}

    def generate(d):
        assert d == dim
        if options["Mesh.MeshSizeFactor"] > coarsest:
            raise Exception("Invalid boundary mesh")  # gmsh raises bare Exceptions

    def cells(model, d):
        return round(fixed + scaling / options["Mesh.MeshSizeFactor"] ** d)

    monkeypatch.setattr(geo_worker, "_cells", cells)
    mesh = SimpleNamespace(clear=lambda: None, generate=generate)
    option = SimpleNamespace(getNumber=options.__getitem__, setNumber=options.__setitem__)
    return SimpleNamespace(option=option, model=SimpleNamespace(mesh=mesh))


@pytest.mark.parametrize(
    ("fixed", "scaling", "dim", "factor", "coarsest"),
    [
        (0, 1e9, 2, 220.0, math.inf),  # the first k about right: one more mesh at 2k
        (0, 1e6, 2, 2000.0, math.inf),  # the bounding box far above (graded): stepped down
        (0, 1e9, 3, 100.0, math.inf),
        (5000, 1e6, 2, 7.0, math.inf),  # a structured part that does not shrink
        (0, 1e7, 2, 300.0, 40.0),  # gmsh fails beyond k = 40: halved until it does not
        (0, 3e3, 2, 30.0, math.inf),  # small: meshed in full
    ],
)
def test_trial_meshes_stay_small_and_extrapolate(
    monkeypatch, fixed, scaling, dim, factor, coarsest
):
    from geofrac.meshing.geo_worker import MAX_TRIALS, trial_meshes
    from geofrac.scene.size import _trial_cells

    gmsh = _fake_gmsh(monkeypatch, fixed, scaling, dim=dim, coarsest=coarsest)
    made = trial_meshes(gmsh, dim, factor, cells=TRIAL_CELLS)
    assert len(made) <= MAX_TRIALS + 1
    assert all(n <= fixed + 4 * TRIAL_CELLS for _, n in made), made
    cells, k = _trial_cells(tuple(made), dim)
    assert cells == pytest.approx(fixed + scaling, rel=0.01)
    assert (k == 1.0) == (fixed + scaling <= TRIAL_CELLS)


def test_trial_meshes_raise_when_no_mesh_can_be_made(monkeypatch):
    from geofrac.meshing.geo_worker import trial_meshes

    gmsh = _fake_gmsh(monkeypatch, 0, 1e6, dim=2, coarsest=0.5)
    with pytest.raises(Exception, match="Invalid boundary mesh"):
        trial_meshes(gmsh, 2, 50.0, cells=TRIAL_CELLS)


def test_format_count():
    assert format_count(80) == "80"
    assert format_count(1.0e9) == "1.0e9"


def _table() -> None:
    """Print estimate against real count for every jobs/ scene with a geometry."""
    from geofrac.meshing.geo import gmsh_session

    print("| scene | estimate | real | estimate/real | source | real mesh |")
    print("|---|---|---|---|---|---|")
    for path in _job_files():
        scene = load_scene(path)
        geometry = scene.geometry
        if geometry is None:
            continue
        start = time.perf_counter()
        if geometry.builder is not None and path in DFN_JOBS:
            real = dfn_real_cells(path)
        elif geometry.builder is not None:
            with gmsh_session(None, geometry.parameters, geometry.mesh_size) as gmsh:
                geometry.builder.build(gmsh)
                types = gmsh.model.mesh.getElements(geometry.dim)[1]
                real = sum(len(t) for t in types)
        else:
            real = real_cells(geometry)
        seconds = time.perf_counter() - start
        cells = _cells(scene)
        print(
            f"| {path.name} | {cells:.0f} | {real} | {cells / real:.2f} | "
            f"{scene.size.method} | {seconds:.1f} s |"
        )


if __name__ == "__main__":
    _table()
    sys.exit(0)
