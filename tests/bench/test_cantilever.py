"""The cantilever accuracy-cost study on the seed's meshes (seed Fig. 2.8)."""

import json

import pytest

from geofrac.bench.report import fit_rate


@pytest.fixture(scope="module")
def report(tmp_path_factory):
    from geofrac.cli import main

    out = tmp_path_factory.mktemp("bench")
    code = main(
        [
            "bench",
            "cantilever",
            "--elements",
            "cst,p2",
            "--out",
            str(out),
            "--json",
            str(out / "x.json"),
            "--repeat",
            "1",
        ]
    )
    assert code == 0
    return out, json.loads((out / "x.json").read_text())


def test_json_contract(report):
    out, data = report
    assert data["bench"] == "cantilever"
    assert (out / "cantilever.png").is_file()
    assert json.loads((out / "cantilever.json").read_text())["records"] == data["records"]
    keys = {
        "element",
        "mesh",
        "nodes",
        "dofs",
        "error_u",
        "error_energy",
        "time_assemble_s",
        "time_solve_s",
    }
    for record in data["records"]:
        assert keys <= set(record)
    meshes = [r["mesh"] for r in data["records"] if r["element"] == "cst"]
    assert meshes == ["4x40", "5x50", "6x60", "7x70", "8x80", "9x90", "10x100", "11x110"]
    assert [r["nodes"] for r in data["records"][:2]] == [5 * 41, 6 * 51]


def test_rates_are_fitted_from_the_records(report):
    _, data = report
    for element, rates in data["rates"].items():
        rows = [r for r in data["records"] if r["element"] == element]
        assert rates["u"] == pytest.approx(
            fit_rate([r["nodes"] for r in rows], [r["error_u"] for r in rows])
        )


def test_convergence_rates_match_the_seed_and_theory(report):
    _, data = report
    assert 1.9 <= data["rates"]["cst"]["u"] <= 2.1  # seed Fig. 2.8: R = 2.0
    assert data["rates"]["p2"]["u"] >= 2.8
    assert 0.9 <= data["rates"]["cst"]["energy"] <= 1.1  # seed Fig. 3.11: FEM R = 0.9
    for cst, p2 in zip(data["records"][:8], data["records"][8:], strict=True):
        assert p2["error_u"] < cst["error_u"]


def test_unknown_element_is_a_clear_error(cli):
    code, _, err = cli("bench", "cantilever", "--elements", "cst,q9", "--repeat", "1")
    assert code == 2
    assert "q9" in err and "unknown element" in err
