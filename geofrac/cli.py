"""Command line: ``geofrac run | check | bench | validate``; works the same under ``mpiexec -n N``.

Messages come from rank 0 only. Exit codes: 0 success, 1 the run failed
(:class:`~geofrac.errors.RunError`), 2 the scene or the command line is wrong
(:class:`~geofrac.scene.SceneError`). An unexpected exception on any rank under MPI
aborts the whole job (``MPI_Abort``) instead of leaving the other ranks waiting.
"""

from __future__ import annotations

import argparse
import sys
import time
import traceback
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

from geofrac import __version__
from geofrac.bench import BENCHES, load_bench
from geofrac.errors import RunError
from geofrac.log import echo, format_seconds
from geofrac.scene import Scene, SceneError, load_scene_collective

if TYPE_CHECKING:
    from mpi4py import MPI

__all__ = ["main", "quick_time"]


def quick_time(root: Path | None = None) -> str:
    """``geofrac validate --quick``'s wall time as measured and dated in docs/validation.json.

    The README and docs/guide.md quote the same text (a test compares them).
    """
    import json

    root = root or Path(__file__).resolve().parent.parent
    try:
        run = json.loads((root / "docs" / "validation.json").read_text())["quick_run"]
        return f"about {run['seconds']:.0f} s on 2 cores, measured {run['date']}"
    except (OSError, ValueError, KeyError, TypeError):
        return "not measured yet"


def _set_option(p: argparse.ArgumentParser, example: str) -> None:
    p.add_argument(
        "--set",
        dest="overrides",
        action="append",
        default=[],
        metavar="KEY=VALUE",
        help=f"override a scene entry (TOML value), e.g. --set {example} (repeatable)",
    )


def _scene_args(p: argparse.ArgumentParser) -> None:
    p.add_argument("scene", help="scene file (TOML), e.g. jobs/quickstart.toml")
    _set_option(p, "discretization.element=cst")
    p.add_argument(
        "--allow-large",
        action="store_true",
        help="run a scene whose estimated size is beyond the caps of docs/scenes.md",
    )


def _parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="geofrac", description=__doc__.splitlines()[0])
    parser.add_argument("--version", action="version", version=f"geofrac {__version__}")
    sub = parser.add_subparsers(dest="command", required=True)

    run = sub.add_parser("run", help="validate and run a scene")
    _scene_args(run)
    run.add_argument(
        "--out", metavar="DIR", help="output directory (default: the scene's output.dir)"
    )
    run.add_argument(
        "-q", "--quiet", action="store_true", help="print only errors and the output path"
    )
    again = run.add_mutually_exclusive_group()
    again.add_argument(
        "--overwrite",
        action="store_true",
        help="replace the completed run in the output directory (only when this run "
        "succeeds; without it a second run into a completed directory is refused)",
    )
    again.add_argument(
        "--resume",
        action="store_true",
        help="continue the interrupted run in the output directory from its newest checkpoint",
    )
    run.set_defaults(func=_run)

    check = sub.add_parser("check", help="validate a scene without meshing or solving")
    _scene_args(check)
    check.set_defaults(func=_check)

    bench = sub.add_parser("bench", help="accuracy-cost benchmarks")
    benches = bench.add_subparsers(dest="bench", required=True, metavar="NAME")
    for name, (_, text) in BENCHES.items():
        p = benches.add_parser(name, help=text, description=text)
        load_bench(name).add_arguments(p)
        _set_option(p, "solver.preset=direct (applied to every case)")
        p.set_defaults(func=_bench)

    validate = sub.add_parser(
        "validate",
        help="run the validation suite and write its page under the output directory",
        description="Run the validation cases (closed forms, experiments, the literature, "
        "Edo (2016)) and write the validation page from what they measure: "
        "OUT/validation.md, its data OUT/validation.json and its figures OUT/img/validation/. "
        "Nothing in the source tree changes unless --update-docs is given. Exit code 1 when "
        "a case fails to run or differs from its reference for no known reason.",
    )
    validate.add_argument(
        "--quick",
        action="store_true",
        help=f"only the cases that finish in minutes ({quick_time()}); the page keeps the "
        "other cases' values from the last full run",
    )
    validate.add_argument("--cases", help="comma-separated case names (default: all)")
    validate.add_argument(
        "--out",
        type=Path,
        default=Path("results/validation"),
        help="where the runs and the page are written (default: results/validation)",
    )
    page = validate.add_mutually_exclusive_group()
    page.add_argument(
        "--page",
        type=Path,
        help="write the page here instead of OUT/validation.md (its data goes beside it as "
        ".json, its figures to img/validation/)",
    )
    page.add_argument(
        "--update-docs",
        action="store_true",
        help="for maintainers: rewrite the project's docs/validation.md, .json and "
        "img/validation/ (commit them with the change that moved the numbers)",
    )
    validate.add_argument("--list", action="store_true", help="list the cases and exit")
    validate.set_defaults(func=_validate)
    return parser


def _load(args: argparse.Namespace, comm: MPI.Comm, out: str | None = None) -> Scene:
    """Validate the scene on every rank and print its warnings (rank 0)."""
    scene = load_scene_collective(
        comm, args.scene, args.overrides, out=out, allow_large=args.allow_large
    )
    for warning in scene.warnings:
        echo(comm, f"warning: {warning}", err=True)
    return scene


def _check(args: argparse.Namespace, comm: MPI.Comm) -> int:
    scene = _load(args, comm)
    echo(comm, f"ok: {args.scene}: {_describe(scene)}")
    if scene.size is not None:
        echo(comm, f"size: {scene.size.summary()} ({scene.size.method}; caps in docs/scenes.md)")
    if scene.initial_stress is not None:
        return _check_balance(scene, comm)
    return 0


def _check_balance(scene: Scene, comm: MPI.Comm) -> int:
    """Mesh and report the initial stress's out-of-balance force; 1 if a run would refuse it."""
    from geofrac.fem.stages import TOLERANCE, refusal
    from geofrac.runner import initial_balance

    try:
        value = initial_balance(scene, comm)
    except RunError as exc:
        echo(comm, f"error: {exc}", err=True)
        return 1
    echo(
        comm,
        f"initial stress ({scene.initial_stress.kind}): out of balance {value:.2e} of the "  # type: ignore[union-attr]
        f"applied force (tolerance {TOLERANCE:g})",
    )
    if value > TOLERANCE:
        echo(comm, f"error: {refusal(value)}", err=True)
        return 1
    return 0


def _describe(scene: Scene) -> str:
    """What a validated scene is, in one line."""
    effects = ", ".join(scene.effect_names) or "none"
    if scene.mpm is not None:
        m = scene.mpm
        source = f"{len(m.bodies)} bodies" if m.bodies else m.particles.kind
        return (
            f"MPM {m.dim}D, {m.scheme}/{m.shape}, particles from {source}, "
            f"t_end {m.t_end:g}; effects: {effects}"
        )
    if scene.blocks is not None:
        b = scene.blocks
        source = "the terrain of Edo (2016), §5.4" if b.source == "terrain" else "its geometry"
        return f"{b.dim}D blocks from {source}"
    groups = ", ".join(f"{n} ({d}D)" for n, d in scene.geometry.groups.items())  # type: ignore[union-attr]
    return (
        f"{scene.gdim}D, element {scene.discretization.element}, "  # type: ignore[union-attr]
        f"effects: {effects}; groups: {groups}"
    )


def _run(args: argparse.Namespace, comm: MPI.Comm) -> int:
    from geofrac import interrupt
    from geofrac.timing import Timings

    timings = Timings()
    with timings.phase("load"):
        scene = _load(args, comm, args.out)
        from geofrac.io.outdir import preflight

        where = "--out" if args.out else "output.dir"
        again = {"overwrite": args.overwrite, "resume": args.resume}
        preflight(scene.output.dir, comm, file=args.scene, key=where, **again)
    echo(comm, f"geofrac {__version__}: scene '{scene.name}' ({args.scene}) on {comm.size} rank(s)")
    quiet = args.quiet
    from geofrac import pipeline

    method = pipeline.get(scene.method)  # MPM imports no DOLFINx
    # after the imports: PETSc's initialisation installs its own SIGTERM handler (which
    # aborts), and the handlers installed last are the ones that act
    interrupt.install()
    try:
        summary = pipeline.run_scene(scene, comm, timings, verbose=not quiet, resume=args.resume)
    except interrupt.Interrupted as exc:
        stage = scene.output.dir / "incomplete"
        echo(comm, f"interrupted: {exc}; partial results in {stage}", err=True)
        if (stage / "checkpoint").is_dir() or comm.rank != 0:  # echo prints on rank 0 only
            echo(
                comm,
                f"resume with: geofrac run {args.scene} --resume"
                + "".join(f" --set {o}" for o in args.overrides)
                + (f" --out {args.out}" if args.out else ""),
                err=True,
            )
        return 128 + exc.signum if exc.signum else 1
    except RunError as exc:
        echo(comm, f"error: {exc}", err=True)
        if getattr(exc, "partial", None) is not None:
            echo(comm, f"the failed run's files and summary.json: {exc.partial}", err=True)  # type: ignore[attr-defined]
        return 1
    finally:
        interrupt.uninstall()
    if not quiet:
        for line in pipeline.report(method, summary, scene):
            echo(comm, line)
    echo(comm, f"output: {scene.output.dir}")
    return 0


def _bench(args: argparse.Namespace, comm: MPI.Comm) -> int:
    start = time.perf_counter()
    load_bench(args.bench).run(args, comm)
    echo(comm, f"bench {args.bench} done in {format_seconds(time.perf_counter() - start)}")
    return 0


def _validate(args: argparse.Namespace, comm: MPI.Comm) -> int:
    import datetime
    import json

    from geofrac.validation import select
    from geofrac.validation.suite import merge, run_cases, write_page

    root = Path(__file__).resolve().parent.parent
    if not (root / "jobs").is_dir():
        raise RunError(
            f"validate: no jobs/ beside the geofrac package in {root} (a source "
            "checkout is needed: the cases are its scenes)"
        )
    names = [n.strip() for n in args.cases.split(",") if n.strip()] if args.cases else None
    try:
        cases = select(names, quick=args.quick)
    except ValueError as exc:
        echo(comm, f"error: --cases: {exc}", err=True)
        return 2
    if args.list:
        for c in cases:
            echo(comm, f"{c.name:22s} {c.chapter}: {c.title}{'' if c.quick else ' (full only)'}")
        return 0
    docs_page = root / "docs" / "validation.md"
    page = docs_page if args.update_docs else args.page or args.out / "validation.md"
    data_path = page.with_suffix(".json")
    # the other cases' rows and the time left: this page's data if it exists (measured on
    # this machine), else the project's page (the last full run, on the CI machine)
    stored_path = data_path if data_path.exists() else docs_page.with_suffix(".json")
    stored = _read_json(stored_path) if comm.rank == 0 else None
    stored = comm.bcast(stored, root=0)
    command = ("" if comm.size == 1 else f"mpiexec -n {comm.size} ") + "geofrac validate"
    command += " --quick" if args.quick else ""
    if names:
        command += f" --cases {','.join(names)}"
    from geofrac import interrupt

    start = time.perf_counter()
    interrupt.install()
    try:
        results = run_cases(
            cases,
            args.out,
            comm,
            root=root,
            say=lambda text: echo(comm, text),
            figures=page.parent / "img" / "validation",
            measured=_measured_seconds(stored),
        )
    except interrupt.Interrupted as exc:
        echo(comm, f"validate: {exc}; {page} was not rewritten", err=True)
        return 128 + exc.signum if exc.signum else 1
    finally:
        interrupt.uninstall()
    seconds = time.perf_counter() - start
    if comm.rank == 0:
        stamp = datetime.date.today().isoformat()
        full = not args.quick and not names
        data = merge(stored, results, command, seconds=seconds, full=full, stamp=stamp)
        if args.quick and not names:  # the time --help, the README and the guide quote
            data["quick_run"] = data["last_run"]
        page.parent.mkdir(parents=True, exist_ok=True)
        _point_at_existing_figures(data, page.parent, docs_page.parent)
        data_path.write_text(json.dumps(data, indent=1) + "\n")
        write_page(data, page)
    bad = [r for r in results if r.status.startswith(("failed", "differs: not explained"))]
    count = f"{len(results)} case{'' if len(results) == 1 else 's'}"
    echo(comm, f"validate: {count} in {format_seconds(seconds)}; wrote {page}")
    for r in bad:
        echo(comm, f"  {r.case.name}: {r.status}", err=True)
    return 1 if bad else 0


def _read_json(path: Path) -> dict[str, Any] | None:
    """A page's data, or None when it is missing or unreadable."""
    import json

    try:
        data = json.loads(path.read_text())
    except (OSError, ValueError):
        return None
    return data if isinstance(data, dict) else None


def _point_at_existing_figures(data: dict[str, Any], here: Path, docs: Path) -> None:
    """Rows kept from the project's page show the project's figures (relative links)."""
    import os

    for entry in data.get("cases", {}).values():
        figure = entry.get("figure") if isinstance(entry, dict) else None
        if not figure or (here / figure).exists() or not (docs / figure).exists():
            continue
        entry["figure"] = os.path.relpath(docs / figure, here.resolve())


def _measured_seconds(stored: dict[str, Any] | None) -> dict[str, float]:
    """Each case's measured wall time in a page's data (seconds; none where not run)."""
    cases = (stored or {}).get("cases", {})
    return {
        name: float(entry["seconds"])
        for name, entry in cases.items()
        if isinstance(entry, dict)
        and isinstance(entry.get("seconds"), int | float)
        and entry["seconds"] > 0
    }


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``geofrac`` console script."""
    args = _parser().parse_args(argv)
    from mpi4py import MPI

    comm = MPI.COMM_WORLD
    try:
        return int(args.func(args, comm))
    except SceneError as exc:
        echo(comm, f"error: {exc}", err=True)
        return 2
    except RunError as exc:
        echo(comm, f"error: {exc}", err=True)
        return 1
    except BaseException:
        if comm.size > 1:
            traceback.print_exc()
            sys.stderr.flush()
            comm.Abort(1)
        raise


if __name__ == "__main__":
    sys.exit(main())
