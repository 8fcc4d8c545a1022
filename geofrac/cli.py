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
from typing import TYPE_CHECKING

from geofrac import __version__
from geofrac.bench import BENCHES, load_bench
from geofrac.errors import RunError
from geofrac.log import echo, format_seconds
from geofrac.scene import Scene, SceneError, load_scene_collective

if TYPE_CHECKING:
    from mpi4py import MPI

__all__ = ["main"]


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
    run.add_argument(
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
        help="run the validation suite and write docs/validation.md",
        description="Run the validation cases (closed forms, the literature, Edo (2016)) "
        "and rewrite the validation page from what they measure. Exit code 1 when a case "
        "fails to run or differs from its reference for no known reason.",
    )
    validate.add_argument(
        "--quick",
        action="store_true",
        help="only the cases that finish in minutes (under 10 on 2 cores); the page keeps "
        "the other cases' values from the last full run",
    )
    validate.add_argument("--cases", help="comma-separated case names (default: all)")
    validate.add_argument(
        "--out",
        type=Path,
        default=Path("results/validation"),
        help="where the runs write (default: results/validation)",
    )
    validate.add_argument(
        "--page",
        type=Path,
        help="the page to write (default: docs/validation.md of the repository; its data "
        "goes beside it as .json, its figures to img/validation/)",
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
        echo(comm, f"size: {scene.size.summary()} (estimate; caps in docs/scenes.md)")
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
        for line in pipeline.report(method, summary):
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
    page = args.page or root / "docs" / "validation.md"
    data_path = page.with_suffix(".json")
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
        )
    except interrupt.Interrupted as exc:
        echo(comm, f"validate: {exc}; {page} was not rewritten", err=True)
        return 128 + exc.signum if exc.signum else 1
    finally:
        interrupt.uninstall()
    seconds = time.perf_counter() - start
    if comm.rank == 0:
        stored = json.loads(data_path.read_text()) if data_path.exists() else None
        stamp = datetime.date.today().isoformat()
        full = not args.quick and not names
        data = merge(stored, results, command, seconds=seconds, full=full, stamp=stamp)
        data_path.write_text(json.dumps(data, indent=1) + "\n")
        write_page(data, page)
    bad = [r for r in results if r.status.startswith(("failed", "differs: not explained"))]
    count = f"{len(results)} case{'' if len(results) == 1 else 's'}"
    echo(comm, f"validate: {count} in {format_seconds(seconds)}; wrote {page}")
    for r in bad:
        echo(comm, f"  {r.case.name}: {r.status}", err=True)
    return 1 if bad else 0


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
