"""``geofrac bench mesh-dependence`` on the coarse symmetric beam."""

import argparse
import json

import numpy as np
import pytest
from mpi4py import MPI

from geofrac.bench.mesh_dependence import band_h, run
from tests.conftest import REPO

SMALL = REPO / "tests" / "fracture" / "scenes" / "sym_notched_beam_small.toml"


def test_band_h_is_the_mean_edge_length_inside_the_band():
    coords = np.array(
        [[0.0, 0.0], [3.0, 0.0], [0.0, 4.0], [100.0, 0.0], [101.0, 0.0], [100.0, 1.0]]
    )
    cells = np.array([[0, 1, 2], [3, 4, 5]])  # a 3-4-5 triangle inside, a small one outside
    assert band_h(coords, cells, band=25.0) == pytest.approx(4.0)


def test_bench_runs_each_mesher_with_the_users_overrides(tmp_path):
    args = argparse.Namespace(
        algorithms=["delaunay", "meshadapt"],
        scene=SMALL,
        picture=tmp_path / "paths.png",
        json=tmp_path / "paths.json",
        overrides=["cracking.max_events=25"],
    )
    records = run(args, MPI.COMM_WORLD)
    assert [r["case"] for r in records] == ["delaunay", "meshadapt"]
    assert records[0]["nodes"] != records[1]["nodes"]  # two meshes of one file
    for r in records:
        assert r["events"] <= 25 and r["overrides"] == ["cracking.max_events=25"]
        assert 3.0 < r["h"] < 5.0  # h_fine = 4 in the band
        assert 0.0 <= r["distance_below_pad"] <= r["distance"] < 40.0
        assert r["distance_over_h"] == pytest.approx(r["distance"] / r["h"])
    if MPI.COMM_WORLD.rank == 0:
        assert (tmp_path / "paths.png").stat().st_size > 10_000
        assert json.loads((tmp_path / "paths.json").read_text())["bench"] == "mesh-dependence"
