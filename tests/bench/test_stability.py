"""The stability study: distorted meshes (numpy and gmsh) and the bench end to end."""

import json
import math

import numpy as np
import pytest

from geofrac.meshing.distorted import (
    GROUPS,
    build_distorted_cantilever,
    distort_to_angle,
    min_angle,
    perturbation_field,
    signed_areas,
    triangle_angles,
)

L, D = 10.0, 1.0
BOX = (0.0, L, -D / 2, D / 2)


def structured(nx: int, ny: int) -> tuple[np.ndarray, np.ndarray]:
    """Right-isosceles cantilever mesh as meshes/cantilever.geo builds it (numpy only)."""
    x, y = np.meshgrid(np.linspace(0.0, L, nx + 1), np.linspace(-D / 2, D / 2, ny + 1))
    points = np.column_stack([x.ravel(), y.ravel()])
    n = np.arange((nx + 1) * (ny + 1)).reshape(ny + 1, nx + 1)
    a, b, c, d = n[:-1, :-1].ravel(), n[:-1, 1:].ravel(), n[1:, 1:].ravel(), n[1:, :-1].ravel()
    triangles = np.concatenate([np.column_stack([a, b, c]), np.column_stack([a, c, d])])
    return points, triangles


def test_angles_of_reference_triangles():
    right = np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]])
    equilateral = np.array([[0.0, 0.0], [1.0, 0.0], [0.5, math.sqrt(3) / 2]])
    tri = np.array([[0, 1, 2]])
    assert min_angle(right, tri) == pytest.approx(45.0)
    assert triangle_angles(right, tri)[0] == pytest.approx([90.0, 45.0, 45.0])
    assert min_angle(equilateral, tri) == pytest.approx(60.0)
    assert min_angle(right, tri[:, ::-1]) == pytest.approx(45.0)  # orientation does not matter
    assert signed_areas(right, tri)[0] == pytest.approx(0.5)
    assert signed_areas(right, tri[:, ::-1])[0] == pytest.approx(-0.5)
    collinear = np.array([[0.0, 0.0], [1.0, 0.0], [2.0, 0.0]])
    assert triangle_angles(collinear, tri)[0] == pytest.approx([0.0, 180.0, 0.0])


def test_structured_mesh_has_min_angle_45():
    points, triangles = structured(20, 2)
    angles = triangle_angles(points, triangles)
    assert angles.sum(axis=1) == pytest.approx(np.full(len(triangles), 180.0))
    assert min_angle(points, triangles) == pytest.approx(45.0)
    assert np.all(signed_areas(points, triangles) > 0)


def test_perturbation_is_tangential_on_the_boundary_and_independent_of_numbering():
    points, _ = structured(20, 2)
    field = perturbation_field(points, BOX, seed=3)
    on_x = np.isclose(points[:, 0], 0.0) | np.isclose(points[:, 0], L)
    on_y = np.isclose(np.abs(points[:, 1]), D / 2)
    assert np.all(field[on_x, 0] == 0.0) and np.all(field[on_y, 1] == 0.0)
    inside = ~(on_x | on_y)
    assert np.all(field[inside] != 0.0) and np.all(np.abs(field) <= 1.0)
    perm = np.random.default_rng(1).permutation(len(points))
    assert np.array_equal(perturbation_field(points[perm], BOX, seed=3), field[perm])
    assert not np.array_equal(perturbation_field(points, BOX, seed=4), field)


@pytest.mark.parametrize("target", [30.0, 15.0, 10.0, 5.0])
def test_distortion_meets_the_angle_without_inverting(target):
    points, triangles = structured(40, 4)
    h = D / 4
    moved, amplitude = distort_to_angle(
        points, triangles, h * perturbation_field(points, BOX), target=target
    )
    assert 0.0 < amplitude < 1.0
    assert abs(min_angle(moved, triangles) - target) < 0.5
    assert np.all(signed_areas(moved, triangles) > 0)
    for axis, value in ((0, 0.0), (0, L), (1, -D / 2), (1, D / 2)):
        on = np.isclose(points[:, axis], value)
        assert np.array_equal(moved[on, axis], points[on, axis])  # stays on its side
    corners = np.isclose(points[:, 0] % L, 0.0) & np.isclose(np.abs(points[:, 1]), D / 2)
    assert corners.sum() == 4 and np.array_equal(moved[corners], points[corners])
    assert np.abs(moved - points).max() > 0.05 * h


def test_distortion_to_45_is_the_identity_and_above_is_an_error():
    points, triangles = structured(20, 2)
    field = perturbation_field(points, BOX)
    moved, amplitude = distort_to_angle(points, triangles, field, target=45.0)
    assert amplitude == 0.0 and np.array_equal(moved, points)
    with pytest.raises(ValueError, match="exceeds"):
        distort_to_angle(points, triangles, field, target=50.0)


def test_gmsh_builder_writes_the_groups_and_the_angle(tmp_path):
    import gmsh

    mesh = build_distorted_cantilever(tmp_path / "m.msh", 2, 10.0)
    assert (mesh.nodes, mesh.cells) == (3 * 21, 2 * 2 * 20)
    assert abs(mesh.min_angle - 10.0) < 0.5 and mesh.amplitude > 0.0
    assert mesh.path.read_text().startswith("$MeshFormat\n4.1")
    gmsh.initialize(["test", "-nopopup"], readConfigFiles=False)
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.open(str(mesh.path))
        model = gmsh.model
        groups = {model.getPhysicalName(d, t): (d, t) for d, t in model.getPhysicalGroups()}
        sides = {}
        for name in ("fixed", "tip", "top", "bottom"):
            sides[name] = model.mesh.getNodesForPhysicalGroup(*groups[name])[1].reshape(-1, 3)
        tags, coords, _ = model.mesh.getNodes()
        _, nodes = model.mesh.getElementsByType(2)
    finally:
        gmsh.finalize()
    assert set(groups) == set(GROUPS) and groups["domain"][0] == 2
    assert np.all(sides["fixed"][:, 0] == 0.0) and np.all(sides["tip"][:, 0] == L)
    assert np.all(sides["top"][:, 1] == D / 2) and np.all(sides["bottom"][:, 1] == -D / 2)
    assert len(sides["fixed"]) == len(sides["tip"]) == 3
    index = np.empty(tags.max() + 1, dtype=int)
    index[tags] = np.arange(len(tags))
    points, triangles = coords.reshape(-1, 3)[:, :2], index[nodes.reshape(-1, 3)]
    assert min_angle(points, triangles) == pytest.approx(mesh.min_angle)
    orientation = np.sign(signed_areas(points, triangles))
    assert np.all(orientation == orientation[0])  # no triangle inverted


def _strict_json(path):
    def reject(token):
        raise AssertionError(f"{path} contains {token}")

    return json.loads(path.read_text(), parse_constant=reject)


@pytest.fixture(scope="module")
def report(tmp_path_factory):
    from geofrac.cli import main

    out = tmp_path_factory.mktemp("stability")
    argv = ["bench", "stability", "--elements", "cst,rgnt", "--angles", "45,5"]
    argv += ["--nus", "0.3,0.499", "--ny", "2", "--out", str(out), "--json", str(out / "x.json")]
    assert main(argv) == 0
    return out, _strict_json(out / "x.json")


def _find(records, element, sweep, angle, nu):
    (r,) = [
        r
        for r in records
        if (r["element"], r["sweep"], r["angle_target"], r["nu"]) == (element, sweep, angle, nu)
    ]
    return r


def test_report_files_and_cases(report):
    out, data = report
    assert data["bench"] == "stability" and data["rates"] == {}
    assert (out / "stability.png").is_file()
    assert _strict_json(out / "stability.json")["records"] == data["records"]
    assert len(list((out / "meshes").glob("*.msh"))) == 2
    records = data["records"]
    assert len(records) == 2 * (2 + 2 * 2)  # per element: angle sweep + ν sweep on 2 meshes
    for r in records:
        assert abs(r["min_angle"] - r["angle_target"]) < 0.5
        assert r["plane"] == ("stress" if r["sweep"] == "angle" else "strain")


def test_every_case_is_finite_or_an_explicit_failure(report):
    _, data = report
    keys = ("error_u", "error_energy", "error_u_relative", "error_energy_relative")
    failed = 0
    for r in data["records"]:
        if r["status"] == "ok":
            assert all(math.isfinite(r[k]) and r[k] > 0 for k in keys)
            assert r["dofs"] > 0
        else:
            assert r["status"].startswith("error: ") and all(r[k] is None for k in keys)
            failed += 1
    assert data["failures"] == failed


def test_degradation_is_the_ratio_to_the_baseline(report):
    _, data = report
    records = data["records"]
    for element in ("cst", "rgnt"):
        base_angle = _find(records, element, "angle", 45.0, 0.3)
        base_nu = _find(records, element, "nu", 45.0, 0.3)
        assert base_angle["degradation_u"] == base_nu["degradation_energy"] == 1.0
        for r in records:
            if r["element"] != element:
                continue
            base = base_angle if r["sweep"] == "angle" else base_nu
            for key in ("u", "energy"):
                assert r[f"degradation_{key}"] == pytest.approx(
                    r[f"error_{key}_relative"] / base[f"error_{key}_relative"]
                )


def test_distortion_and_near_incompressibility_degrade_the_error(report):
    _, data = report
    records = data["records"]
    for element in ("cst", "rgnt"):
        undistorted = _find(records, element, "angle", 45.0, 0.3)
        distorted = _find(records, element, "angle", 5.0, 0.3)
        for key in ("error_u_relative", "error_energy_relative"):
            assert math.isfinite(distorted[key]) and distorted[key] > undistorted[key]
        for angle in (45.0, 5.0):  # volumetric locking in plane strain
            assert _find(records, element, "nu", angle, 0.499)["degradation_u"] > 1.5


def test_solver_failures_are_recorded_not_raised(tmp_path, cli):
    code, out, _ = cli(
        "bench", "stability", "--elements", "cst", "--angles", "45", "--nus", "0.3",
        "--ny", "2", "--out", tmp_path,
        "--set", "solver.preset=iterative", "--set", "solver.options.ksp_max_it=1",
    )  # fmt: skip
    assert code == 0
    data = _strict_json(tmp_path / "stability.json")
    assert data["failures"] == len(data["records"]) == 2
    for r in data["records"]:
        assert r["status"].startswith("error: linear solver") and r["error_u"] is None
        assert r["degradation_u"] is None
    assert "failures: 2 of 2 cases" in out


def test_non_finite_errors_are_failures(tmp_path, cli, monkeypatch):
    import geofrac.runner

    solve = geofrac.runner.solve_scene

    def nan_energy(*args, **kwargs):
        solution = solve(*args, **kwargs)
        solution.results["errors"]["energy"] = float("nan")
        return solution

    monkeypatch.setattr(geofrac.runner, "solve_scene", nan_energy)
    code, out, _ = cli(
        "bench", "stability", "--elements", "cst", "--angles", "45", "--nus", "0.3",
        "--ny", "2", "--out", tmp_path,
    )  # fmt: skip
    assert code == 0
    data = _strict_json(tmp_path / "stability.json")  # no NaN written
    assert data["failures"] == 2
    assert all(r["status"].startswith("error: non-finite error norm") for r in data["records"])
    assert "failures: 2 of 2 cases" in out


@pytest.mark.parametrize(
    ("option", "value", "message"),
    [
        ("--angles", "45,50", "(0, 45]"),
        ("--nus", "0.3,0.5", "(-1, 0.5)"),
        ("--elements", "cst,rgnq", "does not support 2D"),
    ],
)
def test_bad_options_are_clear_errors(cli, tmp_path, option, value, message):
    code, _, err = cli("bench", "stability", option, value, "--out", tmp_path)
    assert code == 2
    assert message in err
