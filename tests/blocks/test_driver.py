"""Small versions of the jobs/ block scenes, run end to end (1 and 2 ranks)."""

import csv
import json

import numpy as np
import pytest
import pyvista as pv
from mpi4py import MPI

from geofrac.blocks.output import read_block_file
from geofrac.meshing.terrain import TerrainSpec, ground
from geofrac.pipeline import run_scene
from geofrac.scene import load_scene
from tests.conftest import JOBS

# the terrain at the scale of Edo (2016), h = 25 m: a few hundred blocks
SMALL_TERRAIN = ["blocks.terrain.h=25", "blocks.terrain.h_immobile=150"]


def _run(tmp_path, job, overrides, comm=MPI.COMM_SELF):
    out = tmp_path / "out" if comm.size == 1 else comm.bcast(tmp_path / "out", root=0)
    scene = load_scene(JOBS / job, overrides, out=out)
    return run_scene(scene, comm, verbose=False), out


def test_square_blocks_scene_writes_what_it_says(tmp_path):
    summary, out = _run(
        tmp_path, "blocks_square.toml", ["geometry.parameters.h=0.2", "output.block_file=true"]
    )
    q = summary["results"]["quality"]
    assert summary["status"] == "ok"
    assert abs(q["volume_rel_error"]) < 1e-12 and q["invalid_blocks"] == 0
    assert q["validator"]["checked"] == q["count"]
    grid = pv.read(out / "blocks.vtu")
    assert grid.n_cells == q["count"]
    assert np.all(grid.celltypes == pv.CellType.POLYGON)
    assert abs(grid.cell_data["volume"].sum() - 1.0) < 1e-12
    blocks = read_block_file(out / "blocks.txt")
    assert blocks.num_blocks == q["count"]
    with open(out / "volume_histogram.csv") as f:
        rows = list(csv.DictReader(f))
    assert sum(int(r["count"]) for r in rows) == q["count"]
    assert json.loads((out / "summary.json").read_text())["status"] == "ok"
    assert "section.png" in summary["files"] and (out / "section.png").is_file()


def test_cylinder_blocks_fill_the_meshed_cylinder(tmp_path):
    summary, out = _run(tmp_path, "blocks_cylinder.toml", ["geometry.parameters.h=0.25"])
    q = summary["results"]["quality"]
    assert abs(q["volume_rel_error"]) < 1e-12
    assert q["invalid_blocks"] == 0 and q["pairing"]["ok"]
    assert abs(q["total_volume"] - np.pi * 0.25 * 2.0) < 0.05  # the mesh is polyhedral
    grid = pv.read(out / "blocks.vtu")
    assert np.all(grid.celltypes == pv.CellType.POLYHEDRON)


def test_terrain_scene_has_one_immobile_block_and_fills_the_box(tmp_path):
    summary, _ = _run(tmp_path, "terrain_100k.toml", SMALL_TERRAIN)
    r = summary["results"]
    q = r["quality"]
    assert q["count"] == r["mesh"]["vertices"] + 1  # the layer's blocks + the immobile one
    assert abs(q["volume_rel_error"]) < 1e-12
    assert q["invalid_blocks"] == 0 and q["pairing"]["ok"]
    # the layer's slip and side faces pair with the immobile block's pit (the two share
    # that surface, point for point, so neither gap nor overlap): more faces are matched
    # than in the layer alone
    layer, _ = _run(
        tmp_path / "layer", "terrain_100k.toml", [*SMALL_TERRAIN, "blocks.immobile=false"]
    )
    alone = layer["results"]["quality"]["pairing"]
    assert q["pairing"]["boundary_closed"] and alone["ok"]
    assert q["pairing"]["matched"] > alone["matched"]
    spec = TerrainSpec(h=25, h_immobile=150)
    x0, x1, y0, y1 = spec.extent
    g = np.linspace(0, 1, 401)
    x, y = np.meshgrid(x0 + (x1 - x0) * g, y0 + (y1 - y0) * g)
    box = np.trapezoid(np.trapezoid(ground(x, y, spec) - spec.base_z, x[0], axis=1), y[:, 0])
    assert abs(q["total_volume"] - box) < 0.03 * box  # piecewise-linear surfaces


def test_bad_quality_fails_the_run_and_leaves_no_outputs(tmp_path, monkeypatch):
    from geofrac.blocks import driver
    from geofrac.errors import RunError

    monkeypatch.setattr(driver, "_problems", lambda report: ["injected failure"])
    with pytest.raises(RunError, match="injected failure"):
        _run(tmp_path, "blocks_square.toml", ["geometry.parameters.h=0.3"])
    out = tmp_path / "out"
    assert not (out / "blocks.vtu").exists()
    assert json.loads((out / "incomplete" / "summary.json").read_text())["status"].startswith(
        "error"
    )
    assert not (out / "summary.json").exists()


@pytest.mark.mpi(min_size=2)
def test_terrain_blocks_are_the_same_on_one_and_two_ranks(tmp_path):
    comm = MPI.COMM_WORLD
    base = comm.bcast(tmp_path, root=0)
    par, _ = _run(base / "par", "terrain_100k.toml", SMALL_TERRAIN, comm)
    ser = None
    if comm.rank == 0:
        ser, _ = _run(base / "ser", "terrain_100k.toml", SMALL_TERRAIN)
    ser = comm.bcast(ser, root=0)
    a, b = par["results"]["quality"], ser["results"]["quality"]
    assert a["count"] == b["count"]
    assert a["pairing"]["matched"] == b["pairing"]["matched"]
    for key in ("total_volume",):
        assert abs(a[key] - b[key]) < 1e-9 * abs(b[key])
    for key in ("volume", "equivalent_diameter", "aspect_ratio"):
        for stat in ("min", "max", "mean"):
            assert abs(a[key][stat] - b[key][stat]) <= 1e-9 * abs(b[key][stat])


def test_a_mesh_with_a_non_manifold_vertex_is_refused_with_a_clear_error(tmp_path):
    from geofrac.errors import RunError

    geo = tmp_path / "touching.geo"  # two squares that share only the corner (1, 1)
    geo.write_text(
        "h = 0.25;\n"
        "Point(1) = {0, 0, 0, h}; Point(2) = {1, 0, 0, h}; Point(3) = {1, 1, 0, h};\n"
        "Point(4) = {0, 1, 0, h}; Point(5) = {2, 1, 0, h}; Point(6) = {2, 2, 0, h};\n"
        "Point(7) = {1, 2, 0, h};\n"
        "Line(1) = {1, 2}; Line(2) = {2, 3}; Line(3) = {3, 4}; Line(4) = {4, 1};\n"
        "Line(5) = {3, 5}; Line(6) = {5, 6}; Line(7) = {6, 7}; Line(8) = {7, 3};\n"
        "Curve Loop(1) = {1, 2, 3, 4}; Plane Surface(1) = {1};\n"
        "Curve Loop(2) = {5, 6, 7, 8}; Plane Surface(2) = {2};\n"
        'Physical Surface("domain") = {1, 2};\n'
    )
    scene = tmp_path / "scene.toml"
    scene.write_text(f'method = "blocks"\n[geometry]\nfile = "{geo.as_posix()}"\n[blocks]\n')
    with pytest.raises(RunError, match="do not form one fan"):
        run_scene(load_scene(scene, out=tmp_path / "out"), MPI.COMM_SELF, verbose=False)
    summary = json.loads((tmp_path / "out" / "incomplete" / "summary.json").read_text())
    assert summary["status"].startswith("error: cannot build blocks")


def test_the_result_block_checks_the_volumes_against_the_unit_square(tmp_path):
    """blocks_square: the blocks of the unit square sum to its area 1 (in m² when declared)."""
    from geofrac.blocks.driver import BLOCKS

    summary, _ = _run(
        tmp_path, "blocks_square.toml", ["geometry.parameters.h=0.2", "units.length=m"]
    )
    q = summary["results"]["quality"]
    scene = load_scene(JOBS / "blocks_square.toml", ["units.length=m"])
    lines = BLOCKS.result(scene, summary)
    assert lines[0].startswith(f"blocks: {q['count']}, area min ") and lines[0].endswith(" m²")
    gap = q["total_volume"] - 1.0
    assert lines[1] == (
        f"area check: the blocks sum to {q['total_volume']:.10g} m², the domain 1 m² "
        f"(difference {gap:+.3g} m², {100 * gap:+.3g} %)"
    )
    assert lines[2].startswith("checks: 0 invalid, faces paired (")
    bare = BLOCKS.result(load_scene(JOBS / "blocks_square.toml"), summary)
    assert "m²" not in "".join(bare) and "the domain 1 (difference" in bare[1]
