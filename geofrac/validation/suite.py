"""Run validation cases and write the validation page (``geofrac validate``).

Each case runs its scene (in ``OUT/<case>``) or its bench, reads geofrac's value, and is
compared with its reference (:mod:`geofrac.validation.cases`). Scenes shared by several
cases run once. The page (Markdown) and its data (JSON, the numbers a test compares with
a fresh run) are written by rank 0; figures go beside the page.
"""

from __future__ import annotations

import argparse
import math
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

from geofrac.validation.cases import (
    CHAPTERS,
    CONSISTENCY,
    REPRODUCTION,
    SECTIONS,
    VALIDATION,
    Case,
    declared_units,
)

if TYPE_CHECKING:
    from mpi4py import MPI

__all__ = ["LONG_CASE_S", "Result", "merge", "run_cases", "status_of", "write_page"]

#: Cases estimated to take longer (seconds) print their run's progress lines.
LONG_CASE_S = 60.0


@dataclass
class Result:
    """One case's outcome.

    Attributes:
        case: the case.
        value: geofrac's value (nan when the run failed).
        seconds: wall time of its run (shared runs: counted once, on the first case).
        error: why the run failed, or None.
        figure: the figure's path relative to the page, or None.
    """

    case: Case
    value: float
    seconds: float
    error: str | None = None
    figure: str | None = None

    @property
    def status(self) -> str:
        """``reproduced``, ``differs: <why>``, ``no reference: <why>`` or ``failed: <why>``."""
        return status_of(self.case, self.value, self.error)


def status_of(case: Case, value: float, error: str | None = None) -> str:
    """The status a case's value earns (see :class:`Result`)."""
    if error is not None:
        return f"failed: {error}"
    if not math.isfinite(value):
        return "failed: the run gave no finite value"
    if case.reference.kind == "pending":
        return f"no reference: {case.known}" if case.known else "no reference"
    if case.reference.holds(value):
        return "reproduced"
    return f"differs: {case.known}" if case.known else "differs: not explained (a regression?)"


def _run_scene(case: Case, root: Path, out: Path, comm: MPI.Comm) -> dict[str, Any]:
    from geofrac import interrupt
    from geofrac.pipeline import get, run_scene
    from geofrac.scene import load_scene_collective

    scene = load_scene_collective(comm, root / str(case.scene), list(case.overrides), out=str(out))
    get(scene.method)  # the imports: PETSc's initialisation installs its own SIGTERM handler
    interrupt.install()
    interrupt.reassert()
    # a long case prints its run's own progress (with time left); short ones stay quiet
    return run_scene(scene, comm, verbose=case.estimate_s >= LONG_CASE_S)


def _run_bench(case: Case, out: Path, comm: MPI.Comm) -> dict[str, Any]:
    from geofrac import interrupt
    from geofrac.bench import load_bench
    from geofrac.pipeline import get

    get("fem")  # the imports: PETSc's initialisation installs its own SIGTERM handler
    interrupt.install()
    interrupt.reassert()
    assert case.bench is not None
    name, *argv = case.bench
    module = load_bench(name)
    parser = argparse.ArgumentParser(prog=f"geofrac bench {name}")
    module.add_arguments(parser)
    args = parser.parse_args([*argv, "--out", str(out)])
    args.overrides = list(case.overrides)
    return module.run(args, comm)


def run_cases(
    cases: list[Case],
    out: Path,
    comm: MPI.Comm,
    *,
    root: Path,
    say: Callable[[str], None] = print,
    figures: Path | None = None,
    measured: dict[str, float] | None = None,
) -> list[Result]:
    """Run ``cases``; return their results in the same order.

    A SIGTERM or SIGINT stops the suite: a case with a loop stops at its next event or
    step (with a checkpoint), any other case when it is done; then
    :class:`~geofrac.interrupt.Interrupted` is raised and no page should be written.

    Args:
        cases: the cases.
        out: where runs write (``out/<case>``).
        comm: the communicator every run uses.
        root: the repository (scene paths are relative to it).
        say: progress output (rank 0).
        figures: where case figures go (None: none drawn).
        measured: each case's wall time in an earlier run (seconds, by case name), for
            the time left; a case without one counts its :attr:`Case.estimate_s`.
    """
    from mpi4py import MPI

    from geofrac import interrupt

    done: dict[tuple[Any, ...], tuple[dict[str, Any] | None, Path, str | None]] = {}
    results = []
    t_start = time.perf_counter()
    keys = [(c.scene, c.bench, c.overrides) for c in cases]
    # each distinct run's time as measured before (else Case.estimate_s), scaled by this
    # machine's pace so far
    before = measured or {}
    estimates: dict[tuple[Any, ...], float] = {}
    for k, c in zip(keys, cases, strict=True):
        estimates.setdefault(k, before.get(c.name, c.estimate_s))
    for i, case in enumerate(cases, 1):
        key = keys[i - 1]
        seconds = 0.0
        if key not in done:
            where = out / case.name
            elapsed = time.perf_counter() - t_start
            spent = sum(estimates[k] for k in done)
            left = sum(v for k, v in estimates.items() if k not in done)
            eta = (
                f", about {_left(elapsed / spent * left if spent else left)} left" if i > 1 else ""
            )
            say(f"validate [{i}/{len(cases)}] {case.name}: {case.command()}{eta}")
            t0 = time.perf_counter()
            data, error = None, None
            try:
                if case.bench is not None:
                    data = _run_bench(case, where, comm)
                else:
                    data = _run_scene(case, root, where, comm)
            except interrupt.Interrupted:
                raise
            except Exception as exc:  # a failed case is reported, not fatal
                error = f"{type(exc).__name__}: {exc}".splitlines()[0][:200]
            seconds = time.perf_counter() - t0
            stop = comm.allreduce(interrupt.received(), op=MPI.MAX)
            if stop:  # a signal during a case without a loop to stop: stop after it
                raise interrupt.Interrupted(stop, f"case {case.name}")
            done[key] = (data, where, error)
        else:
            say(f"validate [{i}/{len(cases)}] {case.name}: (same run as above)")
        data, where, error = done[key]
        value = math.nan
        if data is not None:
            try:
                value = float(case.measure(data, where))
            except (KeyError, OSError, ValueError, IndexError) as exc:
                error = f"cannot read the value: {type(exc).__name__}: {exc}"[:200]
        result = Result(case, value, seconds, error)
        if figures is not None and case.plot is not None and data is not None:
            if comm.rank == 0:
                figures.mkdir(parents=True, exist_ok=True)
                path = figures / f"{case.name}.png"
                case.plot(data, where, path)
            result.figure = f"img/validation/{case.name}.png"
        quantity = case.quantity_in(declared_units(case, root))
        say(f"    {quantity}: {_number(value)} against {case.reference.text()}: {result.status}")
        results.append(result)
    return results


def _left(seconds: float) -> str:
    return f"{seconds:.0f} s" if seconds < 120 else f"{seconds / 60:.0f} min"


def _number(value: float) -> str:
    if not math.isfinite(value):
        return "—"
    return f"{value:.4g}" if abs(value) >= 1e-3 else f"{value:.2e}"


def _difference(result: Result) -> str:
    d = result.case.reference.difference(result.value)
    return "—" if not math.isfinite(d) else f"{100 * d:+.2f} %"


def merge(
    stored: dict[str, Any] | None,
    results: list[Result],
    command: str,
    *,
    seconds: float,
    full: bool,
    stamp: str,
) -> dict[str, Any]:
    """The page's data: ``stored`` (a previous run's) updated with ``results``.

    A quick run replaces the cases it ran and keeps the others' values from the last full
    run; a full run (every case) records its wall time as the suite's.

    Returns:
        ``{"full_run": {"seconds", "date", "command"} | None, "runs": [...], "cases":
        {name: {"value", "error", "seconds", "figure", "date"}}}``.
    """
    data = dict(stored or {})
    data.setdefault("full_run", None)
    cases = dict(data.get("cases", {}))
    for r in results:
        cases[r.case.name] = {
            "value": r.value if math.isfinite(r.value) else None,
            "error": r.error,
            "seconds": round(r.seconds, 2),
            "figure": r.figure,
            "date": stamp,
        }
    data["cases"] = cases
    run = {"command": command, "seconds": round(seconds, 1), "date": stamp, "cases": len(results)}
    if full:
        data["full_run"] = run
    data["last_run"] = run
    return data


def _cases(n: int) -> str:
    return f"{n} case" if n == 1 else f"{n} cases"


#: What each section of the page checks, in a few sentences.
SECTION_INTROS = {
    VALIDATION: [
        "geofrac against the physics: closed forms, experiments and the literature,",
        "independent of geofrac's own code and of Edo (2016)'s numbers.",
    ],
    CONSISTENCY: [
        "geofrac against its scene's own inputs: a generated network against the sets it",
        "was drawn from, a meshed volume against its geometry, a block count against the",
        "model it was built to, the energy a scheme creates against gravity's work. These",
        "check that a run builds and conserves what it declares, not that it is physics.",
    ],
    REPRODUCTION: [
        "geofrac against the numbers and figures of Edo (2016), the thesis it implements:",
        "agreement shows the implementation does what the thesis did, not that either",
        "matches nature.",
    ],
}

#: The crack-path rows' dependence on the mesh, as docs/cracking.md measured it.
MESH_DEPENDENCE = [
    "### Mesh dependence of the crack paths",
    "",
    "The crack-path rows above hold on each scene's default mesh. `geofrac bench",
    "mesh-dependence [--set geometry.parameters.h_fine=...]` reruns the symmetric notched",
    "beam (exact path: the axis) on the three gmsh meshers. With the default criterion",
    "every cracked edge until the crack enters the load pad's zone stayed within 1.29,",
    "0.96 and 0.98 mm of the axis at h_fine = 1.45 mm (frontal-Delaunay, Delaunay,",
    "MeshAdapt: 0.90, 0.70 and 0.69 h), 0.50, 0.53 and 0.45 mm at h_fine = 1.0 mm, but",
    "2.50, 2.54 and 1.34 mm at h_fine = 2.0 mm (1.26, 1.33 and 0.69 h): beyond one element",
    "on two of the three meshers. The notched beam's crack meets the top 34.2 mm right of",
    "the centre on its default mesh (experiment: 30-40 mm) but 67-91 mm on a 12 mm mesh.",
    "Source: docs/cracking.md,",
    '"Mesh dependence" (2026-11-26).',
    "",
]


def write_page(data: dict[str, Any], page: Path, *, root: Path | None = None) -> list[Result]:
    """Write the validation page from its data (:func:`merge`); return the results shown.

    Args:
        data: the page's data.
        page: the Markdown file to write.
        root: the repository, whose scenes give each quantity's units (default: the one
            beside the geofrac package).
    """
    from geofrac.validation.cases import CASES

    root = root or Path(__file__).resolve().parents[2]
    results = []
    for case in CASES:
        entry = data["cases"].get(case.name)
        if entry is None:
            continue
        value = math.nan if entry["value"] is None else float(entry["value"])
        r = Result(case, value, float(entry["seconds"]), entry.get("error"), entry.get("figure"))
        results.append((r, entry["date"]))
    lines = _header(data, [r for r, _ in results])
    for section in SECTIONS:
        lines += [f"## {section}", "", *SECTION_INTROS[section], ""]
        rows = [(r, d) for r, d in results if r.case.section == section]
        if not rows:
            lines += ["No case of this section has run yet.", ""]
        for chapter in CHAPTERS:
            in_chapter = [(r, d) for r, d in rows if r.case.chapter == chapter]
            lines += _chapter_table(chapter, in_chapter, root)
            if section == VALIDATION and chapter == "Cracking":
                lines += MESH_DEPENDENCE
    missing = [c for c in CASES if c.name not in data["cases"]]
    if missing:
        lines += ["## Not yet run", ""]
        lines += [f"- {c.name}: {c.title} (`{c.command()}`)" for c in missing]
        lines.append("")
    page.write_text("\n".join(lines))
    return [r for r, _ in results]


def _header(data: dict[str, Any], results: list[Result]) -> list[str]:
    """The page's title, what it is, its runs and its counts."""
    full, last = data.get("full_run"), data["last_run"]
    lines = [
        "# Validation",
        "",
        "What each capability of geofrac is checked against, and how well. This page is",
        "written by `geofrac validate` from what it measured; rerun it to check a machine",
        "or a change. Every case is a scene under `jobs/validation/` (links to the scenes",
        "of `jobs/`) or a bench: its command reruns it alone. A case is *reproduced* when",
        "geofrac's value is within the stated tolerance of the reference (inside the range,",
        "under the bound); a case that differs says why. Three sections tell what a",
        "reference is: *Validation* (closed forms, experiments, the literature),",
        "*Consistency* (the scene's own inputs) and *Reproduction of Edo (2016)* (the",
        "thesis geofrac implements). Quantities are in the units the scene declares in",
        "`[units]`; a quantity whose scene declares none is shown without a unit.",
        "",
    ]
    if full is not None:
        lines.append(
            f"- full suite (`{full['command']}`): {_cases(full['cases'])} in "
            f"{_duration(full['seconds'])} wall time, {full['date']}"
        )
    lines += [
        f"- last run (`{last['command']}`): {_cases(last['cases'])} in "
        f"{_duration(last['seconds'])}, {last['date']}; each row gives the date of its value",
        "",
    ]
    counts = {"reproduced": 0, "differs": 0, "no reference": 0, "failed": 0}
    for r in results:
        counts[r.status.split(":")[0]] += 1
    pending = (
        f", {counts['no reference']} without a reference yet" if counts["no reference"] else ""
    )
    lines += [
        f"**{counts['reproduced']} reproduced, {counts['differs']} differ, "
        f"{counts['failed']} failed{pending}.**",
        "",
    ]
    return lines


def _chapter_table(chapter: str, rows: list[tuple[Result, str]], root: Path) -> list[str]:
    """One chapter's table within a section, and its figures (nothing without rows)."""
    if not rows:
        return []
    lines = [
        f"### {chapter}",
        "",
        "| case | quantity | reference (source) | geofrac | difference | status | run |",
        "|---|---|---|---|---|---|---|",
    ]
    for r, date in rows:
        c = r.case
        tol = f"; tolerance {100 * c.reference.rtol:g} %" if c.reference.kind == "value" else ""
        cells = [
            f"{c.title}<br>`{c.command()}`",
            c.quantity_in(declared_units(c, root)),
            f"{c.reference.text()} ({c.reference.source}{tol})",
            _number(r.value),
            _difference(r),
            r.status,
            f"{r.seconds:.1f} s, {date}",
        ]
        lines.append("| " + " | ".join(x.replace("|", "\\|") for x in cells) + " |")
    lines.append("")
    for r, _ in rows:
        if r.figure:
            made = f"<!-- {r.figure} made by: geofrac validate --cases {r.case.name} -->"
            lines += [f"![{r.case.title}]({r.figure})", made, ""]
    return lines


def _duration(seconds: float) -> str:
    if seconds < 120:
        return f"{seconds:.0f} s"
    return f"{int(seconds // 60)} min {int(seconds % 60)} s"
