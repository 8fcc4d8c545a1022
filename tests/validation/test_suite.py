"""The validation suite: its references, statuses, page, and the page against a fresh run.

The page ``docs/validation.md`` is written by ``geofrac validate`` from its data
``docs/validation.json``. A reduced set of its cases (``ci=True``, seconds each) is run
afresh here and must give the page's numbers and statuses, so the page cannot go stale.
"""

import json
import math
from pathlib import Path

import pytest
from mpi4py import MPI

from geofrac.validation import (
    CASES,
    CHAPTERS,
    CONSISTENCY,
    REPRODUCTION,
    SECTIONS,
    VALIDATION,
    Case,
    Reference,
    select,
)
from geofrac.validation.cases import (
    GALVEZ_PEAK,
    declared_units,
    jaeger_slip_stress,
    lame_inner_displacement,
    timoshenko_tip,
)
from geofrac.validation.suite import merge, run_cases, status_of, write_page
from tests.conftest import REPO

PAGE = REPO / "docs" / "validation.md"
DATA = REPO / "docs" / "validation.json"

#: Relative tolerance of a fresh run's value against the page's: the cases are
#: deterministic (direct solvers, explicit MPM, seeded generators); this leaves room for
#: another BLAS or CPU rounding differently, nothing more.
FRESH_RTOL = 1e-6


def _case(reference: Reference, known: str | None = None) -> Case:
    return Case(
        "x",
        "Elements",
        "t",
        "q",
        reference,
        lambda s, o: 0.0,
        scene="jobs/x.toml",
        known=known,
        section=VALIDATION,
    )


def test_reference_kinds():
    value = Reference(2.0, "s", rtol=0.05)
    assert value.holds(2.09) and not value.holds(2.11) and not value.holds(math.nan)
    assert value.difference(2.1) == pytest.approx(0.05)
    band = Reference(30.0, "s", kind="range", high=40.0)
    assert band.holds(35.0) and not band.holds(29.85)
    assert band.difference(35.0) == 0.0
    assert band.difference(29.85) == pytest.approx(-0.005)
    assert band.difference(44.0) == pytest.approx(0.1)
    bound = Reference(1e-10, "s", kind="at_most")
    assert bound.holds(1e-16) and not bound.holds(1e-9)
    assert math.isnan(bound.difference(1e-16))


def test_status_says_why_a_case_differs_and_flags_unexplained_ones():
    ref = Reference(1.0, "s", rtol=0.01)
    assert status_of(_case(ref), 1.005) == "reproduced"
    assert status_of(_case(ref, "the mesh"), 1.5) == "differs: the mesh"
    assert "not explained" in status_of(_case(ref), 1.5)
    assert status_of(_case(ref), math.nan, "RunError: x").startswith("failed")
    assert status_of(_case(Reference(1.0, "s", kind="at_most")), math.nan).startswith("failed")


def test_closed_forms_against_hand_values():
    # Edo (2016), eq. 2.24-2.25 for jobs/quickstart.toml: 1000/25 + 5*10/200
    assert timoshenko_tip(1.0, 10.0, 1.0, E=100.0, nu=0.2) == pytest.approx(40.25, rel=1e-14)
    # 1.3*10/3000 * (0.4 + 4)
    assert lame_inner_displacement(10.0, 1.0, 2.0, E=1000.0, nu=0.3) == pytest.approx(
        1.3 * 10 / 3000 * 4.4, rel=1e-14
    )
    # β = 45°, μ = 0.5: 2c / (0.5 * 1); never below atan μ
    assert jaeger_slip_stress(45.0, 1.0, 0.5) == pytest.approx(4.0, rel=1e-12)
    assert jaeger_slip_stress(25.0, 1.0, 0.5) == math.inf


def test_every_case_is_well_formed():
    names = [c.name for c in CASES]
    assert len(set(names)) == len(names)
    for case in CASES:
        assert case.chapter in CHAPTERS
        assert (case.scene is None) != (case.bench is None), case.name
        if case.scene is not None:
            assert (REPO / case.scene).is_file(), case.name
            assert case.scene.startswith("jobs/validation/"), case.name
        assert case.reference.source
        if case.ci:
            assert case.quick, case.name
    # every chapter has a case, and one against an independent source where the
    # chapter has one
    assert {c.chapter for c in CASES} == set(CHAPTERS)
    independent = {c.chapter for c in CASES if c.reference.independent}
    assert {
        "Elements",
        "Cracking",
        "MPM dynamics",
        "MPM under gravity and friction",
        "Blocks",
    } <= independent


def test_jobs_validation_holds_the_cases_scenes_and_nothing_else():
    # users open jobs/validation/ to rerun the suite's cases: each is a link to the scene
    # of jobs/ that the docs and tests use (no copy to drift), and none is stray
    folder = REPO / "jobs" / "validation"
    assert {f"jobs/validation/{p.name}" for p in folder.iterdir()} == {
        c.scene for c in CASES if c.scene is not None
    }
    for link in folder.iterdir():
        assert link.is_symlink() and link.resolve() == (REPO / "jobs" / link.name).resolve()


def test_every_case_declares_its_section():
    """Each registry entry says what its reference is; none is left to the page to guess."""
    for case in CASES:
        assert case.section in SECTIONS, case.name
        # a reference that is Edo (2016)'s own number cannot validate the physics
        if case.section == VALIDATION:
            assert case.reference.independent, case.name
    by_name = {c.name: c for c in CASES}
    # checked against the scene's own inputs: the DFN's sets and target P21, the block
    # count the terrain was built to, the meshed cylinder's volume
    for name in ("dfn_orientation", "dfn_p21", "terrain_blocks", "blocks_cylinder"):
        assert by_name[name].section == CONSISTENCY, name
    for name in ("cantilever_rate_rgnt", "efmm_table31", "efmm_spread", "landslide_8deg"):
        assert by_name[name].section == REPRODUCTION, name
    for name in ("notched_beam", "notched_beam_peak", "cantilever_tip", "mpm_impact"):
        assert by_name[name].section == VALIDATION, name
    with pytest.raises(ValueError, match="section"):
        Case("x", "Elements", "t", "q", Reference(1.0, "s"), lambda s, o: 0.0, scene="x")


def _sections(text: str) -> dict[str, str]:
    """The page's text under each ``## `` heading, by heading."""
    parts = text.split("\n## ")[1:]
    return {p.split("\n", 1)[0]: p.split("\n", 1)[1] for p in parts}


def test_the_page_puts_each_case_under_its_section(tmp_path):
    data = json.loads(DATA.read_text())
    page = tmp_path / "validation.md"
    shown = write_page(data, page)
    text = page.read_text()
    headings = [line[3:] for line in text.splitlines() if line.startswith("## ")]
    assert headings[:3] == list(SECTIONS)  # in this order, before "Not yet run"
    sections = _sections(text)
    rows = [f"| {r.case.title}<br>`{r.case.command()}` |" for r in shown]
    assert len(set(rows)) == len(rows)  # a row names its case
    for r, row in zip(shown, rows, strict=True):
        assert row in sections[r.case.section], (r.case.name, r.case.section)
        for other in set(SECTIONS) - {r.case.section}:
            assert row not in sections[other], (r.case.name, other)


def test_quantities_are_in_the_scenes_units(tmp_path):
    by_name = {c.name: c for c in CASES}
    # jobs/dfn_model1.toml is in millimetres; jobs/blocks_cylinder.toml declares no units
    assert declared_units(by_name["dfn_p21"], REPO)["length"] == "mm"
    assert by_name["dfn_p21"].quantity_in(declared_units(by_name["dfn_p21"], REPO)) == (
        "P21 (1/mm)"
    )
    assert declared_units(by_name["blocks_cylinder"], REPO) == {}
    assert by_name["blocks_cylinder"].quantity_in({}) == "volume"
    assert by_name["blocks_cylinder"].quantity_in({"length": "m"}) == "volume (m³)"
    assert by_name["jaeger_60"].quantity_in({"stress": "MPa"}) == "σ1 at slip (MPa)"
    assert by_name["cantilever_rate_rgnt"].quantity_in({"length": "mm"}).endswith("R/2))")
    # the page: the same cells
    data = json.loads(DATA.read_text())
    page = tmp_path / "validation.md"
    write_page(data, page)
    text = page.read_text()
    assert "| P21 (1/mm) |" in text and "| volume |" in text
    # no metre where the scene has millimetres or nothing (the 3D DFN's P32 is in 1/m:
    # its scene declares metres)
    assert all("(1/m)" not in line for line in text.splitlines() if "P21" in line)
    assert "(m³)" not in text
    assert "| P32 (1/m) |" in text


def test_the_peak_load_is_read_in_kn_from_the_scenes_force_unit():
    case = {c.name: c for c in CASES}["notched_beam_peak"]
    summary = {
        "scene": {"input": {"units": {"force": "N"}}},
        "results": {"cracking": {"peak_reaction": 1518.5}},
    }
    assert case.measure(summary, Path(".")) == pytest.approx(1.5185, rel=1e-12)
    summary["scene"]["input"]["units"] = {"force": "kN"}
    assert case.measure(summary, Path(".")) == pytest.approx(1518.5, rel=1e-12)
    summary["scene"]["input"] = {}
    with pytest.raises(ValueError, match="force unit"):
        case.measure(summary, Path("."))
    assert case.reference is GALVEZ_PEAK and "Gálvez" in case.reference.source
    assert case.quantity_in({"force": "N"}).endswith("(kN)")


def test_a_pending_reference_compares_nothing():
    pending = Reference(math.nan, "s", kind="pending")
    assert not pending.holds(1.0) and math.isnan(pending.difference(1.0))
    assert pending.text() == "not yet transcribed"
    assert status_of(_case(pending, "why"), 1.0) == "no reference: why"
    assert status_of(_case(pending), math.nan).startswith("failed")


def test_select_by_name_and_subset():
    assert [c.name for c in select(["mpm_bar", "hole_scf"])] == ["hole_scf", "mpm_bar"]
    with pytest.raises(ValueError, match="unknown validation case"):
        select(["nope"])
    assert all(c.quick for c in select(quick=True))
    assert {c.name for c in select(ci=True)} < {c.name for c in select(quick=True)}


def test_page_is_written_from_its_data():
    """docs/validation.md is exactly what its data renders to: not edited by hand."""
    data = json.loads(DATA.read_text())
    assert set(data["cases"]) == {c.name for c in CASES}
    assert data["full_run"] is not None  # the page states the full suite's time
    text = PAGE.read_text()
    assert f"{data['full_run']['seconds']:.0f}" in text or "min" in text
    rendered = Path(PAGE.parent / ".validation_check.md")
    try:
        write_page(data, rendered)
        assert rendered.read_text() == text
    finally:
        rendered.unlink(missing_ok=True)


def test_merge_keeps_the_full_runs_values_and_time():
    case = select(["mpm_bar"])[0]
    from geofrac.validation.suite import Result

    full = merge(
        None, [Result(case, 0.0065, 1.0)], "geofrac validate", seconds=100.0, full=True, stamp="d1"
    )
    quick = merge(full, [], "geofrac validate --quick", seconds=5.0, full=False, stamp="d2")
    assert quick["full_run"]["seconds"] == 100.0 and quick["last_run"]["date"] == "d2"
    assert quick["cases"]["mpm_bar"]["value"] == 0.0065


def test_a_fresh_run_of_the_ci_cases_gives_the_pages_numbers(tmp_path):
    data = json.loads(DATA.read_text())["cases"]
    cases = select(ci=True)
    results = run_cases(cases, tmp_path, MPI.COMM_SELF, root=REPO, say=lambda text: None)
    for r in results:
        page = data[r.case.name]
        assert r.error is None, (r.case.name, r.error)
        assert r.value == pytest.approx(page["value"], rel=FRESH_RTOL), r.case.name
        stored = status_of(r.case, page["value"], page.get("error"))
        assert r.status == stored, r.case.name


def test_cli_lists_cases_refuses_unknown_ones_and_writes_a_page(cli, tmp_path):
    code, out, _ = cli("validate", "--list")
    assert code == 0 and "cantilever_tip" in out and "(full only)" in out
    code, _, err = cli("validate", "--cases", "nope")
    assert code == 2 and "unknown validation case" in err
    page = tmp_path / "validation.md"
    code, out, _ = cli(
        "validate", "--cases", "patch_test", "--page", page, "--out", tmp_path / "runs"
    )
    assert code == 0, out
    data = json.loads(page.with_suffix(".json").read_text())
    assert data["cases"]["patch_test"]["value"] < 1e-10
    # a selection is not the full suite: the full run stays the project's (its rows kept)
    project = json.loads((REPO / "docs" / "validation.json").read_text())
    assert data["full_run"] == project["full_run"] and data["last_run"]["cases"] == 1
    assert "patch_test" in page.read_text() or "patch test" in page.read_text()


def test_validate_writes_its_page_under_the_output_directory_not_into_docs(cli, tmp_path):
    docs = [REPO / "docs" / "validation.md", REPO / "docs" / "validation.json"]
    before = [p.read_bytes() for p in docs]
    code, out, _ = cli("validate", "--cases", "patch_test", "--out", tmp_path / "v")
    assert code == 0, out
    assert [p.read_bytes() for p in docs] == before  # the checkout is untouched
    page = tmp_path / "v" / "validation.md"
    assert f"wrote {page}" in out
    data = json.loads(page.with_suffix(".json").read_text())
    assert data["cases"]["patch_test"]["value"] < 1e-10
    # the cases not run keep the project's last values, as the project's page shows them
    stored = json.loads(docs[1].read_text())["cases"]
    assert data["cases"]["cantilever_tip"]["value"] == stored["cantilever_tip"]["value"]
    for entry in data["cases"].values():  # every figure link resolves from the page
        if entry.get("figure"):
            assert (page.parent / entry["figure"]).exists(), entry["figure"]


def test_the_time_left_counts_each_case_as_measured_before(tmp_path):
    cases = select(["patch_test", "cantilever_tip"], quick=False)
    said: list[str] = []
    slow = {"patch_test": 1.0, "cantilever_tip": 1e6}  # the second took a million times more
    run_cases(cases, tmp_path, MPI.COMM_WORLD, root=REPO, say=said.append, measured=slow)
    eta = next(line for line in said if line.startswith("validate [2/2]"))
    assert eta.endswith("min left"), eta  # >= 0.1 s so far x 1e6: thousands of minutes
    said.clear()
    run_cases(cases, tmp_path / "again", MPI.COMM_WORLD, root=REPO, say=said.append)
    eta = next(line for line in said if line.startswith("validate [2/2]"))
    assert eta.endswith(" s left"), eta  # the cases' own estimates: seconds
