"""The manufactured 3D study: RGNQ converges; JSON contract."""

import json

import numpy as np
import pytest

from geofrac.analytic import ManufacturedBox, displacement_gradient


def test_manufactured_gradient_matches_its_displacement():
    ex = ManufacturedBox(0.01, 1.0, 2.0)
    x = np.random.default_rng(0).random((5, 3))
    g = np.stack([np.stack(np.broadcast_arrays(*row), axis=-1) for row in ex.gradient(*x.T)], 1)
    np.testing.assert_allclose(g, displacement_gradient(ex, x), rtol=1e-13, atol=1e-16)


@pytest.fixture(scope="module")
def report(tmp_path_factory):
    from geofrac.cli import main

    out = tmp_path_factory.mktemp("mms3d")
    argv = ["bench", "mms3d", "--elements", "p1,rgnq", "--meshes", "2,3,4", "--repeat", "1"]
    assert main([*argv, "--out", str(out), "--json", str(out / "m.json")]) == 0
    return out, json.loads((out / "m.json").read_text())


def test_rgnq_converges_at_rate_two_in_3d(report):
    out, data = report
    assert (out / "mms3d.png").is_file()
    assert data["rate_definition"].startswith("R = -d log(error) / d log(nodes^(1/3))")
    assert data["rates"]["rgnq"]["u"] >= 1.9
    assert data["rates"]["p1"]["u"] >= 1.9
    rows = [r for r in data["records"] if r["element"] == "rgnq"]
    assert [r["mesh"] for r in rows] == ["2x2x2", "3x3x3", "4x4x4"]
    assert [r["dofs"] for r in rows] == [6 * r["nodes"] for r in rows]


def test_2d_element_is_refused(cli):
    code, _, err = cli("bench", "mms3d", "--elements", "rgnt", "--repeat", "1")
    assert code == 2
    assert "rgnt" in err and "3D" in err
