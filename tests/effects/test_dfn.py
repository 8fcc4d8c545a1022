"""Effect ``dfn``: scene validation, the models of Edo (2016), a mesh that follows the network."""

import dataclasses
import json
import math

import dolfinx_solver  # noqa: F401

import meshio
import numpy as np
import pytest
from mpi4py import MPI

from geofrac.dfn.io import load_network, save_network
from geofrac.errors import RunError
from geofrac.meshing.distribute import build_mesh, check_fracture_cover
from geofrac.pipeline import run_scene
from geofrac.scene import SceneError, load_scene
from tests.conftest import JOBS
from tests.conftest import run_and_list_modules as _run_and_list_modules

MODEL1, MODEL2 = JOBS / "dfn_model1.toml", JOBS / "dfn_model2.toml"
#: A coarse mesh of the models of Edo (2016) for tests (their full size is geofrac bench
#: dfn), with the cleaning tolerance of the full-size mesh (0.84 / 4) so the network is the
#: same.
COARSE = ["dfn.mesh_size=3.0", "dfn.tolerance=0.21"]


def _config(scene):
    return next(e.config for e in scene.effects if e.name == "dfn")


def test_thesis_models_declare_table_2_1():
    one, two = _config(load_scene(MODEL1)), _config(load_scene(MODEL2))
    table = [(s.mean_deg, s.spread**2) for s in two.sets]
    np.testing.assert_allclose(table, [(47.473, 60.74), (102.753, 57.16), (162.830, 57.48)])
    assert [(s.lmin, s.lmax, s.exponent) for s in one.sets] == [(10.0, 50.0, 3.1)]
    np.testing.assert_array_equal(one.domain, [[0, 0], [200, 0], [200, 100], [0, 100]])
    scene = load_scene(MODEL1)
    assert scene.geometry.file is None and scene.geometry.dim == 2
    assert {"domain", "fractures", "bottom", "top", "lower_left"} <= set(scene.geometry.groups)


@pytest.mark.parametrize(
    ("override", "key", "message"),
    [
        ("dfn.sets.0.lmin=60", "dfn.sets[0]", "lmin"),
        ("dfn.sets.0.p21=-0.1", "dfn.sets[0]", "negative"),
        ("dfn.sets.0.count=10", "dfn.sets[0]", "exactly one density"),
        ("dfn.sets.0.exponent=0", "dfn.sets[0]", "exponent"),
        ("dfn.sets.0.kappa=3.0", "dfn.sets[0]", "exactly one of variance, std"),
        ("dfn.sets.0.variance=-1", "dfn.sets[0].variance", ">= 0"),
        ("dfn.sets.0.mean='north'", "dfn.sets[0].mean", "finite number"),
        ("dfn.sets.0.distribution=cauchy", "dfn.sets[0].distribution", "unknown value"),
        ("dfn.sets.0.color=1", "dfn.sets[0].color", "unknown key"),
        ("dfn.sets=[]", "dfn.sets", "at least one"),
        ("dfn.seed=-1", "dfn.seed", r"integer in \[0, 2\^63\)"),
        ("dfn.mesh_size=-1", "dfn.mesh_size", "> 0"),
        ("dfn.mesh_size=1e-5", "dfn.mesh_size", "too fine"),
        ("dfn.fracture_mesh_size=2.0", "dfn.fracture_mesh_size", "must not exceed"),
        ("dfn.tolerance=1.0", "dfn.tolerance", "smaller than"),
        ("dfn.algorithm=voronoi", "dfn.algorithm", "unknown"),
        ("dfn.domain=[0, 0, -1, 1]", "dfn.domain", "rectangle"),
        ("dfn.polygon=[[0, 0], [1, 0], [1, 1]]", "dfn.domain", "exactly one of"),
        ("dfn.region=[[0, 0], [4, 3], [4, 0], [0, 1]]", "dfn.region", "not simple"),
        ("dfn.region=[300.0, 0.0, 400.0, 100.0]", "dfn.region", "farther than half"),
        ("dfn.file='network.csv'", "dfn.file", "not both"),
        ("dfn.colour=1", "dfn.colour", "unknown key"),
        ("geometry.file='../meshes/square.geo'", "geometry", "builds the geometry"),
    ],
)
def test_impossible_requests_are_scene_errors(override, key, message):
    with pytest.raises(SceneError, match=message) as info:
        load_scene(MODEL1, [override])
    assert info.value.key == key


def _scene_with_file(tmp_path, text, name="net.csv"):
    """Model 1 with its [[dfn.sets]] replaced by ``file = name`` holding ``text``."""
    (tmp_path / name).write_text(text)
    scene = MODEL1.read_text()
    scene = scene[: scene.index("[[dfn.sets]]")] + scene[scene.index("[material]") :]
    path = tmp_path / "scene.toml"
    path.write_text(scene.replace("[dfn]\n", f'[dfn]\nfile = "{name}"\n', 1))
    return path


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("set,x0,y0,x1,y1\nset1,1,2,3\n", "line 2"),
        ("set,x0,y0,x1,y1\nset1,1,2,3,abc\n", "line 2"),
        ("set,x0,y0,x1,y1\nset1,1,2,1,2\n", "zero"),
        ("x0,y0,x1,y1\n1,2,3,4\n", "header"),
        ("", "empty"),
    ],
)
def test_malformed_network_file_is_a_scene_error(tmp_path, text, message):
    path = _scene_with_file(tmp_path, text)
    with pytest.raises(SceneError, match=message) as info:
        load_scene(path)
    assert info.value.key == "dfn.file" and "net.csv" in str(info.value)


def test_saved_network_meshes_like_the_generated_one(tmp_path):
    generated = _config(load_scene(MODEL1, COARSE)).make_network()
    save_network(generated, tmp_path / "net.csv")
    scene = load_scene(_scene_with_file(tmp_path, (tmp_path / "net.csv").read_text()), COARSE)
    network = _config(scene).make_network()
    np.testing.assert_array_equal(network.segments, generated.segments)
    tagged = build_mesh(scene.geometry, MPI.COMM_WORLD)
    assert tagged.report["fractures"] == len(generated)


@pytest.mark.parametrize("job", [MODEL1, MODEL2])
def test_every_fracture_is_covered_by_tagged_facets(job):
    """Acceptance: tagged length per fracture equals its clipped length (1e-9).

    That holds for every fracture no rule moved; every fracture's tagged length equals
    its length in the cleaned network.
    """
    scene = load_scene(job, COARSE)
    tagged = build_mesh(scene.geometry, MPI.COMM_WORLD)
    clean = tagged.fractures
    dim, facets = tagged.entities("fractures")
    xy = tagged.vertex_coordinates(dim, facets)[:, :, :2]
    from geofrac.dfn.check import covered_length

    covered = covered_length(xy, clean)
    keep = ~clean.modified
    assert keep.sum() > 0.8 * len(clean.network)
    np.testing.assert_allclose(covered[keep], clean.clipped_length[keep], rtol=1e-9)
    np.testing.assert_allclose(covered, clean.length, rtol=1e-9)
    assert check_fracture_cover(tagged)["fracture_facets"] == len(facets)


def test_dfn_run_writes_network_and_fracture_tags(tmp_path):
    scene = load_scene(MODEL2, [*COARSE, "discretization.element=cst"], out=tmp_path)
    summary = run_scene(scene, MPI.COMM_WORLD, verbose=False)
    geometry = summary["results"]["geometry"]
    assert geometry["fractures_covered"] == geometry["fractures_meshed"] > 100
    assert geometry["max_length_error"] < 1e-12
    assert 0.09 < geometry["p21"] < 0.12  # the scenes ask for P21 = 0.1 in total
    assert json.loads((tmp_path / "summary.json").read_text())["status"] == "ok"
    assert "network.png" in summary["files"] and (tmp_path / "network.png").is_file()
    network = load_network(tmp_path / "network.csv")
    np.testing.assert_array_equal(network.segments, _config(scene).make_network().segments)
    with meshio.xdmf.TimeSeriesReader(tmp_path / "fractures.xdmf") as reader:
        points, cells = reader.read_points_cells()
        _, _, cell_data = reader.read_data(0)
    lines = cells[0].data
    assert cells[0].type == "line" and len(lines) == geometry["fracture_facets"]
    fracture = cell_data["fracture"][0].ravel().astype(int) - 1
    fracture_set = cell_data["fracture_set"][0].ravel().astype(int) - 1
    np.testing.assert_array_equal(fracture_set, network.set_index[fracture])
    length = np.hypot(*(points[lines[:, 1], :2] - points[lines[:, 0], :2]).T)
    per_fracture = np.bincount(fracture, weights=length, minlength=len(network))
    assert math.isclose(per_fracture.sum(), geometry["p21_meshed"] * 200 * 100, rel_tol=1e-9)


def test_polygon_domain_names_sides_and_corners(tmp_path):
    ell = "[[0, 0], [200, 0], [200, 50], [100, 50], [100, 100], [0, 100]]"
    text = MODEL1.read_text().replace("domain = [0.0, 0.0, 200.0, 100.0]", f"polygon = {ell}")
    for old, new in (("bottom", "side_1"), ("lower_left", "corner_1"), ("top", "side_5")):
        text = text.replace(f'group = "{old}"', f'group = "{new}"')
    path = tmp_path / "ell.toml"
    path.write_text(text)
    scene = load_scene(path, COARSE)
    assert {f"side_{k}" for k in range(1, 7)} <= set(scene.geometry.groups)
    tagged = build_mesh(scene.geometry, MPI.COMM_WORLD)
    assert check_fracture_cover(tagged)["fractures_covered"] > 50
    x = tagged.mesh.geometry.x
    assert not np.any((x[:, 0] > 100 + 1e-9) & (x[:, 1] > 50 + 1e-9))  # the notch is empty


def test_network_with_nothing_inside_is_a_run_error(tmp_path):
    path = _scene_with_file(tmp_path, "set,x0,y0,x1,y1\nset1,250,10,260,20\n")
    with pytest.raises(RunError, match="no fracture of the network"):
        build_mesh(load_scene(path, COARSE).geometry, MPI.COMM_WORLD)


def test_dfn_scene_imports_dfn_and_no_other_effect(tmp_path):
    modules = _run_and_list_modules(
        tmp_path, MODEL1, *COARSE, "discretization.element=cst", "output.xdmf=false"
    )
    assert "geofrac.effects.dfn" in modules and "geofrac.meshing.dfn" in modules
    assert "geofrac.effects.gravity" not in modules
    written = {p.name for p in (tmp_path / "out").iterdir() if not p.name.startswith(".")}
    assert written == {"summary.json", "network.csv", "network.png"}  # xdmf = false: no XDMF


def test_elastic_scene_imports_no_dfn_code(tmp_path):
    modules = _run_and_list_modules(tmp_path, JOBS / "quickstart.toml")
    assert not [m for m in modules if m.startswith(("geofrac.dfn", "geofrac.meshing.dfn"))]


def _clipped_length(x0, y0, x1, y1, box):
    """Length of the segment inside the rectangle ``box`` = (xmin, ymin, xmax, ymax)."""
    t0, t1 = 0.0, 1.0
    dx, dy = x1 - x0, y1 - y0
    for p, q in ((-dx, x0 - box[0]), (dx, box[2] - x0), (-dy, y0 - box[1]), (dy, box[3] - y0)):
        if p == 0.0:
            if q < 0.0:
                return 0.0
            continue
        t = q / p
        t0, t1 = (max(t0, t), t1) if p < 0.0 else (t0, min(t1, t))
    return max(t1 - t0, 0.0) * math.hypot(dx, dy)


def test_the_result_block_gives_each_sets_p21_and_orientation_against_its_targets(tmp_path):
    """Model 1, coarse: P21 and the axial mean from network.csv, in 1/mm and degrees."""
    from geofrac.effects.dfn import result
    from geofrac.model.scene import Units

    scene = load_scene(MODEL1, [*COARSE, "discretization.element=cst"], out=tmp_path)
    summary = run_scene(scene, MPI.COMM_WORLD, verbose=False)
    with open(tmp_path / "network.csv") as f:
        rows = [line.split(",") for line in f.read().splitlines()[1:]]
    segments = np.array([[float(v) for v in row[1:]] for row in rows])
    p21 = sum(_clipped_length(*s, (0.0, 0.0, 200.0, 100.0)) for s in segments) / (200 * 100)
    doubled = 2 * np.arctan2(segments[:, 3] - segments[:, 1], segments[:, 2] - segments[:, 0])
    mean = math.degrees(math.atan2(np.sin(doubled).mean(), np.cos(doubled).mean())) / 2 % 180
    lines = result(_config(scene), scene, summary["results"])
    assert (
        lines[0].startswith(f"dfn: {len(rows)} fractures (") and f"P21 {p21:.4g} 1/mm" in lines[0]
    )
    gap = p21 - 0.1  # the set's p21
    assert lines[1] == (
        f"set set1: {len(rows)} fractures, P21 {p21:.4g} 1/mm (target 0.1; difference "
        f"{gap:+.3g} 1/mm, {100 * gap / 0.1:+.3g} %)"
    )
    turn = mean - 47.473  # the set's mean (Table 2.1)
    assert lines[2] == (
        f"set set1: mean orientation {mean:.4g} deg (set's 47.473 deg; difference "
        f"{turn:+.3g} deg, {100 * turn / 47.473:+.3g} %)"
    )
    bare = result(_config(scene), dataclasses.replace(scene, units=Units()), summary["results"])
    assert "1/mm" not in "".join(bare) and "1/" not in bare[0]
