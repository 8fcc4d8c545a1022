"""``geofrac bench mpm``: accuracy against cost of the MPM variants (Edo (2016), chapter 4).

Cases (``--cases``):

- ``bar``: the quasi-static bar of §4.5.1 (:func:`geofrac.mpm.bar.quasi_static_bar`)
  at W = ρ₀|b|L₀ in ``--W`` (the thesis's 1000, 12500, 100000) for every shape and scheme:
  the RMS stress error against eq. 4.73 (normalised by ρ₀|b|L₀); plot ``mpm_bar.png``
  (after Fig. 4.13-4.15);
- ``translating``: the translating bar of §4.5.3 (:func:`translating_bar`: the scene
  ``jobs/mpm_translating_bar.toml`` run through the driver's step, so ``geofrac run``
  of the same variant reports the same numbers) to ``--t-end`` (100, Fig. 4.20-4.21)
  for every shape and scheme, without and with MLS smoothing
  (radius ``--smoothing`` cells) of each kind of ``--smoothing-kinds`` (``standard``, the
  thesis's, and ``consistent``): the largest drift of the total energy over every step,
  max |E(t) − E₀|/E₀, with the stored energy as ½ V σ : D⁻¹ : σ (``energy_drift_max``) and
  as stress work (``energy_drift_work_max``, :mod:`geofrac.mpm.energy`); plot
  ``mpm_translating.png``.

  Before the 1D cases (bar, translating, impact) an untimed impact bar per shape,
  scheme and smoothing they use compiles numba's 1D steps (or loads them from its cache):
  ``warmup_seconds_1d`` in the report, so no row's particle-steps/s includes it.

- ``impact``: the bar with an initial velocity v₀ = c/50 towards its fixed base
  (§4.5.2, :func:`geofrac.mpm.bar.impact_bar`) at t = 0.8 L₀/c, every shape and scheme,
  without and with MLS smoothing: the RMS of σ/σ₇₅ − 1 behind the wave (eq. 4.75) and
  the largest |σ/σ₇₅|; plot ``mpm_impact.png`` (after Fig. 4.17-4.18);
- ``block``: throughput of a 2D elastic block of ``--particles`` particles (default
  100,000) on a fixed floor under gravity (:func:`geofrac.mpm.block.gravity_block`),
  MUSL with each shape, without and with smoothing: particle-steps per second over
  ``--steps`` steps, after one untimed warm-up step (numba's compilation or cache
  load, recorded as ``warmup_seconds``). Under ``mpiexec -n N`` the block is
  decomposed over the N ranks (:mod:`geofrac.mpm.parallel`): ``ranks`` is N,
  ``particle_steps_per_s`` counts all particles over the slowest rank's wall time and
  ``per_rank`` gives each rank's own particle-steps per second of that time. The
  smoothed record (radius ``--smoothing`` cells) has ``cost_ratio``, the plain
  record's particle-steps/s over its own (the same block, shape and ranks), printed
  after the table with both rates; its warm-up step includes the first MLS neighbour
  search (``warmup_seconds``), and ``neighbour_builds`` / ``neighbour_build_seconds``
  count the searches within the timed steps (the neighbour lists are reused while
  the particles move less than their margin).
- ``ranks``: rank invariance over long runs (:func:`geofrac.mpm.invariance.compare_ranks`,
  run under ``mpiexec -n 2``): the translating bar to ``--t-end`` and a 2D block sliding
  on a frictional floor for 1e5 steps, each stepped serially and decomposed, every shape
  and scheme: ``rank_difference_max``, the largest difference of particle fields and
  energies over the run relative to their scale (0: bitwise equal), and
  ``rank_difference_t``, the first time they differ.

Every record has particle-steps per second beside its error. The engine is the
compiled one (:mod:`geofrac.mpm.kernels`); ``--backend numpy`` runs the block on the
numpy reference instead. The bars run on rank 0 only (``ranks`` 1). Measured
(2 cores; ``mpiexec -n 2 geofrac bench mpm --cases block --shapes mpm --particles
100000 --steps 50``): see ``docs/mpm.md``. Prints a table; ``--json F`` writes the
report, ``--out DIR`` the plots.
"""

from __future__ import annotations

import argparse
import math
import time
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

from geofrac.bench.args import name_list, number_list

if TYPE_CHECKING:
    import numpy as np

    from geofrac.mpm.block import Throughput

__all__ = [
    "COLUMNS",
    "TRANSLATING_SCENE",
    "EnergyHistory",
    "add_arguments",
    "run",
    "translating_bar",
    "translating_overrides",
]

#: (key, header, format) of the printed table.
COLUMNS = (
    ("case", "case", "s"),
    ("shape", "shape", "s"),
    ("scheme", "scheme", "s"),
    ("smoothing", "smoothing", "s"),
    ("W", "W", "g"),
    ("particles", "particles", "d"),
    ("ranks", "ranks", "d"),
    ("steps", "steps", "d"),
    ("particle_steps_per_s", "particle-steps/s", ".3g"),
    ("stress_error_rms", "stress error (RMS/ρ0|b|L0)", ".4f"),
    ("energy_drift_max", "energy drift max", ".4f"),
    ("energy_drift_work_max", "drift (stress work)", ".4f"),
    ("rank_difference_max", "1 vs N ranks", ".3g"),
)


#: Cases of ``--cases``.
CASES = ("bar", "translating", "impact", "block", "ranks")


# The translating bar (Edo (2016), 4.5.3, Fig. 4.19-4.21): length 5, E = 500, ρ = 1, centred
# at x = 25 in a box 0 … 50 with walls (fixed nodes) at both ends, initial velocity 2.0,
# cell 0.5, Courant number 0.1; it flies, hits a wall, bounces, and so on. The energies
# (kinetic, strain, total) are normalised by the initial (kinetic) energy; without
# dissipation the total should stay 1. The thesis does not give the particle count; the
# scene has two per cell (20), as the quasi-static bar.

#: The translating bar's scene: the bench runs it (with overrides), as ``geofrac run`` does.
TRANSLATING_SCENE = Path(__file__).resolve().parents[2] / "jobs" / "mpm_translating_bar.toml"


@dataclass(frozen=True)
class EnergyHistory:
    """Energies of a translating-bar run, normalised by the initial energy.

    Attributes:
        t: times, shape=(k,).
        kinetic: shape=(k,).
        strain: ½ V σ : D⁻¹ : σ, shape=(k,).
        total: kinetic + strain, shape=(k,).
        drift_max: max |E(t) − E₀| / E₀ over the run (every step), E = kinetic + strain.
        finite: the run ended without a non-finite state.
        steps: time steps taken.
        seconds: wall time of the steps.
        particles: number of particles.
        stored_work: the stored energy as stress work W (:mod:`~geofrac.mpm.energy`),
            shape=(k,).
        drift_work_max: max |K + W − E₀| / E₀ over the run (every step).
        budget: the cumulative budget terms of :data:`~geofrac.mpm.energy.COLUMNS`
            normalised by E₀, name -> shape=(k,).
        closure_max: the budget's largest closure error over E₀ (round-off).
    """

    t: np.ndarray
    kinetic: np.ndarray
    strain: np.ndarray
    total: np.ndarray
    drift_max: float
    finite: bool
    steps: int
    seconds: float
    particles: int
    stored_work: np.ndarray
    drift_work_max: float
    budget: dict[str, np.ndarray]
    closure_max: float


def translating_overrides(
    shape: str,
    scheme: str,
    smoothing: float | None,
    *,
    t_end: float,
    smoothing_kind: str = "standard",
) -> list[str]:
    """The ``--set`` overrides of :data:`TRANSLATING_SCENE` for one variant."""
    sets = [f"mpm.shape={shape}", f"mpm.scheme={scheme}", f"mpm.t_end={t_end!r}"]
    if smoothing is not None:
        sets += [
            'effects=["mls_smoothing"]',
            f"mls_smoothing.radius={smoothing!r}",
            f"mls_smoothing.kind={smoothing_kind}",
        ]
    return sets


def translating_bar(
    shape: str,
    scheme: str = "musl",
    smoothing: float | None = None,
    *,
    t_end: float = 100.0,
    steps: int | None = None,
    samples: int = 2000,
    smoothing_kind: str = "standard",
) -> EnergyHistory:
    """Run the translating bar of Edo (2016), §4.5.3 to ``t_end`` (or for ``steps`` steps).

    The scene ``jobs/mpm_translating_bar.toml`` with :func:`translating_overrides`, on one
    process, stepped by :func:`geofrac.mpm.driver.advance`: the same grid, walls, time
    step and energies as ``geofrac run jobs/mpm_translating_bar.toml --set ...``.

    Args:
        shape: shape functions.
        scheme: update scheme.
        smoothing: MLS radius factor (None: no smoothing).
        t_end: end time (Edo (2016), Fig. 4.21, runs to about 100).
        steps: run exactly this many steps of the Courant time step instead.
        samples: about this many energy samples are kept (the drifts use every step).
        smoothing_kind: ``standard`` (Edo (2016)'s) or ``consistent``
            (:data:`~geofrac.mpm.schemes.SMOOTHINGS`).
    """
    import numpy as np
    from mpi4py import MPI

    from geofrac.errors import RunError
    from geofrac.mpm.driver import advance, prepare, start_log
    from geofrac.mpm.elastic import Elastic
    from geofrac.mpm.energy import COLUMNS, CSV_COLUMNS
    from geofrac.mpm.schemes import time_step
    from geofrac.scene import load_scene

    if steps is not None:  # the scene's rule dt = t_end / ceil(t_end / dt_courant)
        E, rho, cell = 500.0, 1.0, 0.5
        t_end = steps * time_step(0.1, cell, Elastic(E), density=rho, dim=1)
    scene = load_scene(
        TRANSLATING_SCENE,
        translating_overrides(shape, scheme, smoothing, t_end=t_end, smoothing_kind=smoothing_kind),
    )
    comm = MPI.COMM_SELF
    run = prepare(scene, comm)
    log = start_log(run, comm)
    e0 = log.e0
    every = max(1, run.steps // samples)
    rows = [[0.0, *log.first_row()]]
    finite = True
    k = 0
    t0 = time.perf_counter()
    try:
        for k in range(1, run.steps + 1):
            row = advance(run, comm, log, k=k)
            if k % every == 0 or k == run.steps:
                rows.append([k * run.settings.dt, *row])
    except RunError:
        finite = False
    seconds = time.perf_counter() - t0
    arr = np.array(rows)
    col = {name: i - 1 for i, name in enumerate(CSV_COLUMNS) if i >= 1}
    budget = {c: arr[:, col[c]] / e0 for c in COLUMNS}
    drift_max = drift_work_max = float("inf")
    if finite:
        assert log.drift_max is not None and log.drift_work_max is not None  # E₀ > 0
        drift_max, drift_work_max = float(log.drift_max), float(log.drift_work_max)
    return EnergyHistory(
        t=arr[:, 0],
        kinetic=arr[:, col["kinetic"]] / e0,
        strain=arr[:, col["strain"]] / e0,
        total=arr[:, col["total"]] / e0,
        drift_max=drift_max,
        finite=finite,
        steps=k,
        seconds=seconds,
        particles=run.total,
        stored_work=budget["stored_work"],
        drift_work_max=drift_work_max,
        budget=budget,
        closure_max=log.closure / e0,
    )


def add_arguments(p: argparse.ArgumentParser) -> None:
    """Options of this bench."""
    from geofrac.mpm.schemes import SCHEMES
    from geofrac.mpm.shapes import SHAPES

    p.add_argument(
        "--cases",
        type=name_list(CASES, "case"),
        default=["bar", "translating"],
        help=f"comma-separated from {', '.join(CASES)} (default: bar,translating)",
    )
    p.add_argument(
        "--particles", type=int, default=100_000, help="particles of the block case (100000)"
    )
    p.add_argument("--steps", type=int, default=5, help="timed steps of the block case (5)")
    p.add_argument(
        "--W",
        type=number_list(float, lambda v: math.isfinite(v) and v > 0, "finite positive"),
        default=[1000.0, 12500.0, 100000.0],
        help="comma-separated W = ρ0|b|L0 of the bar",
    )
    p.add_argument(
        "--t-end", type=float, default=100.0, help="end time of the translating bar (100)"
    )
    p.add_argument(
        "--smoothing",
        type=float,
        default=2.0,
        help="MLS radius in cells of the smoothed runs: translating bar, impact, block (2.0)",
    )
    p.add_argument(
        "--smoothing-kinds",
        type=name_list(("standard", "consistent"), "smoothing kind"),
        default=["standard", "consistent"],
        help="comma-separated smoothing kinds of the smoothed translating-bar runs "
        "(default: standard,consistent)",
    )
    p.add_argument(
        "--shapes",
        type=name_list(SHAPES, "shape"),
        default=list(SHAPES),
        help="comma-separated shapes (default: all)",
    )
    p.add_argument(
        "--schemes",
        type=name_list(SCHEMES, "scheme"),
        default=list(SCHEMES),
        help="comma-separated schemes (default: all)",
    )
    p.add_argument(
        "--backend",
        choices=["numba", "numpy"],
        default="numba",
        help="the block's MPM step: compiled kernels (numba, default) or the numpy reference",
    )
    p.add_argument("--json", type=Path, help="write the JSON report to this file")
    p.add_argument(
        "--out", type=Path, default=Path("results/bench_mpm"), help="directory of the plot"
    )


def _plot(runs: dict[tuple[str, str, float], Any], Ws: list[float], path: Path) -> None:
    """σ/(ρ₀|b|L₀) against x/Δ per W (MUSL, each shape) beside eq. 4.73."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import numpy as np

    from geofrac.bench.report import save_figure
    from geofrac.mpm.bar import self_weight_stress

    E, rho0, L0 = 1e6, 1.0, 50.0  # the bar of geofrac.mpm.bar.quasi_static_bar
    fig, axes = plt.subplots(1, len(Ws), figsize=(4.2 * len(Ws), 4.2), constrained_layout=True)
    axes = [axes] if len(Ws) == 1 else list(axes)
    for ax, W in zip(axes, Ws, strict=True):
        b = W / (rho0 * L0)
        delta = L0 - rho0 * b * L0**2 / (2 * E)
        for (shape, scheme, w), res in runs.items():
            if w == W and scheme == "musl":
                ax.plot(res.x / delta, res.stress / W, ".", ms=3, label=f"{shape} (MUSL)")
        x = np.linspace(0.0, delta, 200)
        ax.plot(
            x / delta,
            self_weight_stress(x, E=E, rho0=rho0, b=b, L0=L0) / W,
            "k-",
            lw=1,
            label="eq. 4.73",
        )
        ax.set_xlabel("x / Δ")
        ax.set_title(f"W = {W:g}")
    save_figure(
        fig,
        axes,
        path,
        title="Quasi-static bar at t = L0/c (Edo (2016), Fig. 4.13-4.15)",
        ylabel="σ / ρ0|b|L0",
    )


def _smoothing_panels(
    runs: dict[tuple[str, str, str], Any],
    path: Path,
    title: str,
    ylabel: str,
    xlabel: str,
    draw: Any,
    reference: Any,
) -> None:
    """Plot one panel per smoothing label.

    ``draw(ax, shape, scheme, run)`` plots a run, ``reference(ax)`` the reference lines
    of every panel.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from geofrac.bench.report import save_figure

    labels = list(dict.fromkeys(k[2] for k in runs))
    fig, axes = plt.subplots(
        1, len(labels), figsize=(5.5 * len(labels), 4.2), constrained_layout=True, sharey=True
    )
    axes = [axes] if len(labels) == 1 else list(axes)
    for ax, label in zip(axes, labels, strict=True):
        for (shape, scheme, lab), run in runs.items():
            if lab == label:
                draw(ax, shape, scheme, run)
        reference(ax)
        ax.set_xlabel(xlabel)
        ax.set_title(f"smoothing: {label}")
    save_figure(fig, axes, path, title=title, ylabel=ylabel)


def _plot_energy(histories: dict[tuple[str, str, str], Any], path: Path) -> None:
    """Total energy E(t)/E₀ per variant, without and with smoothing (Fig. 4.20-4.21)."""

    def _draw(ax: Any, shape: str, scheme: str, h: Any) -> None:
        ax.plot(h.t, h.total, lw=1, label=f"{shape} ({scheme})")

    def reference(ax: Any) -> None:
        for level in (0.98, 1.02):
            ax.axhline(level, color="k", lw=0.5, ls=":")

    _smoothing_panels(
        histories, path, "Translating bar (Edo (2016), 4.5.3): total energy", "E(t) / E0", "t",
        _draw, reference,
    )  # fmt: skip


def _plot_impact(impacts: dict[tuple[str, str, str], Any], path: Path) -> None:
    """σ/σ₇₅ against X/L₀ (MUSL, each shape), without and with smoothing (Fig. 4.17-4.18)."""

    def _draw(ax: Any, shape: str, scheme: str, r: Any) -> None:
        if scheme == "musl":
            ax.plot(r.x0 / r.x0.max(), r.stress, ".-", ms=3, lw=0.7, label=f"{shape} (MUSL)")

    def reference(ax: Any) -> None:
        ax.axhline(1.0, color="k", lw=0.8, label="eq. 4.75")

    _smoothing_panels(
        impacts, path, "Bar with initial velocity at t = 0.8 L0/c", "σ / (−E v0/c)",
        "X / L0 (initial position)", _draw, reference,
    )  # fmt: skip


def _record(
    case: str,
    scheme: str,
    shape: str,
    smoothing: float | None,
    dim: int,
    particles: int,
    steps: int,
    seconds: float,
    ranks: int = 1,
    **measured: Any,
) -> dict[str, Any]:
    """One JSON record.

    ``measured`` may give ``W``, ``stress_error_rms``, ``energy_drift_max``,
    ``energy_drift_work_max``, ``stress_overshoot``, ``warmup_seconds``, ``per_rank``,
    ``backend``, ``kind`` (the smoothing kind), ``rank_difference_max``,
    ``rank_difference_t``, ``cost_ratio``, ``neighbour_builds`` and
    ``neighbour_build_seconds``; the others are None.
    """
    label = "none" if smoothing is None else f"mls {smoothing:g} cells"
    if smoothing is not None and measured.get("kind", "standard") != "standard":
        label += f" {measured['kind']}"
    return {
        "case": case,
        "scheme": scheme,
        "shape": shape,
        "smoothing": label,
        "dim": dim,
        "particles": particles,
        "ranks": ranks,
        "backend": measured.get("backend", "numba"),
        "W": measured.get("W"),
        "steps": steps,
        "seconds": seconds,
        "particle_steps_per_s": particles * steps / seconds,
        "stress_error_rms": measured.get("stress_error_rms"),
        "energy_drift_max": measured.get("energy_drift_max"),
        "energy_drift_work_max": measured.get("energy_drift_work_max"),
        "stress_overshoot": measured.get("stress_overshoot"),
        "warmup_seconds": measured.get("warmup_seconds"),
        "per_rank": measured.get("per_rank"),
        "rank_difference_max": measured.get("rank_difference_max"),
        "rank_difference_t": measured.get("rank_difference_t"),
        "cost_ratio": measured.get("cost_ratio"),
        "neighbour_builds": measured.get("neighbour_builds"),
        "neighbour_build_seconds": measured.get("neighbour_build_seconds"),
    }


def _ranks(comm: Any, shape: str, scheme: str, t_end: float, progress: Any) -> list[dict]:
    """The ``ranks`` case of one shape and scheme (collective; records on rank 0)."""
    from geofrac.mpm.invariance import compare_ranks

    records = []
    for case in ("translating", "sliding"):
        d = compare_ranks(comm, case, shape, scheme=scheme, t_end=t_end)
        if d is not None:
            first = d.first_above(0.0)
            n = 20 if case == "translating" else 32
            records.append(
                _record(
                    f"ranks_{case}", scheme, shape, None, 1 if case == "translating" else 2, n,
                    d.steps, sum(d.seconds), d.ranks, rank_difference_max=d.worst,
                    rank_difference_t=first,
                )
            )  # fmt: skip
            msg = f"differ from t = {first:.4g} on, up to {d.worst:.3g}" if first else "bitwise"
        progress.step(f"ranks {case} {shape} {scheme}: " + (msg if d is not None else ""))
    return records


def run(args: argparse.Namespace, comm: Any) -> dict[str, Any]:
    """Run the variants; print the table (rank 0); return the JSON report."""
    from geofrac.bench.report import format_table
    from geofrac.io.summary import versions, write_json
    from geofrac.log import Progress, echo
    from geofrac.mpm.bar import impact_bar, quasi_static_bar
    from geofrac.mpm.block import gravity_block

    cases, shapes, schemes, Ws = args.cases, args.shapes, args.schemes, args.W
    if not args.t_end > 0 or not args.smoothing > 0:
        raise SystemExit("--t-end and --smoothing must be > 0")
    if args.particles < 4 or args.steps < 1:
        raise SystemExit("--particles must be >= 4 and --steps >= 1")
    records: list[dict[str, Any]] = []
    runs = {}
    histories = {}
    smoothings = (None, args.smoothing)
    kinds = args.smoothing_kinds
    variants = [(None, "standard")] + [(args.smoothing, k) for k in kinds]
    total = (
        len(shapes)
        * len(schemes)
        * (len(Ws) * ("bar" in cases) + len(variants) * ("translating" in cases))
    )
    total += 2 * len(shapes) * ("block" in cases) + 2 * len(shapes) * len(schemes) * (
        "impact" in cases
    )
    total += len(shapes) * len(schemes) * 2 * ("ranks" in cases)
    impacts = {}
    warmup_1d = 0.0
    if comm.rank == 0 and {"translating", "impact", "bar"} & set(cases):
        # numba compiles (or loads from its cache) each shape/scheme/smoothing's 1D step on
        # first use: an untimed impact bar per variant keeps that out of the rows
        t0 = time.perf_counter()
        smoothed = {"translating", "impact"} & set(cases)  # the bars run unsmoothed only
        for shape in shapes:
            for scheme in schemes:
                for sm in smoothings if smoothed else (None,):
                    impact_bar(shape, scheme, sm)
        warmup_1d = time.perf_counter() - t0
        echo(
            comm,
            f"bench mpm: warm-up of the 1D steps (compilation or cache load) "
            f"{warmup_1d:.2g} s, not timed",
        )
    progress = Progress(comm, total, "bench mpm", unit="cases")
    for shape in shapes if "ranks" in cases else ():
        for scheme in schemes:
            records += _ranks(comm, shape, scheme, args.t_end, progress)
    # the block runs on every rank, decomposed over comm; the bars on rank 0
    ratios = []
    for shape in shapes if "block" in cases else ():
        plain: Throughput | None = None
        for sm in smoothings:
            tp = gravity_block(
                args.particles,
                "musl",
                shape,
                smoothing=sm,
                steps=args.steps,
                comm=comm,
                backend=args.backend,
            )
            ratio = None
            if sm is not None:
                assert plain is not None  # the plain run (smoothing None) comes first
                ratio = plain.particle_steps_per_s / tp.particle_steps_per_s
            records.append(
                _record(
                    "block2d", "musl", shape, sm, 2, tp.particles, tp.steps, tp.seconds,
                    tp.ranks, warmup_seconds=tp.warmup_seconds, per_rank=list(tp.per_rank),
                    backend=args.backend, cost_ratio=ratio,
                    neighbour_builds=None if sm is None else tp.neighbour_builds,
                    neighbour_build_seconds=None if sm is None else tp.neighbour_build_seconds,
                )
            )  # fmt: skip
            progress.step(
                f"block {shape} {records[-1]['smoothing']}: "
                f"{tp.particle_steps_per_s:.3g} p-steps/s on {tp.ranks} rank(s) "
                f"(warm-up {tp.warmup_seconds:.2g} s)"
            )
            if sm is None:
                plain = tp
            else:
                assert plain is not None  # as above
                ratios.append(
                    f"block {shape}, {tp.ranks} rank(s), {tp.particles} particles, "
                    f"{tp.steps} steps: plain {plain.particle_steps_per_s:.3g} "
                    f"p-steps/s, MLS {sm:g} cells {tp.particle_steps_per_s:.3g} p-steps/s, "
                    f"cost ratio {ratio:.2f}; warm-up (compile/load, first step, first "
                    f"neighbour search) {plain.warmup_seconds:.2g} s / "
                    f"{tp.warmup_seconds:.2g} s, not timed; neighbour searches in the "
                    f"timed steps: {tp.neighbour_builds} ({tp.neighbour_build_seconds:.2g} s)"
                )
    if comm.rank == 0:
        for shape in shapes if "translating" in cases else ():
            for scheme in schemes:
                for sm, kind in variants:
                    hist = translating_bar(shape, scheme, sm, t_end=args.t_end, smoothing_kind=kind)
                    records.append(
                        _record(
                            "translating_bar", scheme, shape, sm, 1, hist.particles,
                            hist.steps, hist.seconds, energy_drift_max=hist.drift_max,
                            energy_drift_work_max=hist.drift_work_max, kind=kind,
                        )
                    )  # fmt: skip
                    label = records[-1]["smoothing"]
                    histories[(shape, scheme, label)] = hist
                    progress.step(
                        f"translating {shape} {scheme} {label}: drift {hist.drift_max:.4f}"
                    )
        for shape in shapes if "impact" in cases else ():
            for scheme in schemes:
                for sm in smoothings:
                    imp = impact_bar(shape, scheme, sm)
                    records.append(
                        _record(
                            "impact_bar", scheme, shape, sm, 1, len(imp.x0), imp.steps,
                            imp.seconds, stress_error_rms=imp.error,
                            stress_overshoot=imp.overshoot,
                        )
                    )  # fmt: skip
                    impacts[(shape, scheme, records[-1]["smoothing"])] = imp
                    progress.step(
                        f"impact {shape} {scheme} {records[-1]['smoothing']}: "
                        f"error {imp.error:.4f}, overshoot {imp.overshoot:.3f}"
                    )
        for W in Ws if "bar" in cases else ():
            for shape in shapes:
                for scheme in schemes:
                    res = quasi_static_bar(shape, scheme, W)
                    runs[(shape, scheme, W)] = res
                    n = len(res.x)
                    records.append(
                        _record(
                            "quasi_static_bar",
                            scheme,
                            shape,
                            None,
                            1,
                            n,
                            res.steps,
                            res.seconds,
                            W=W,
                            stress_error_rms=res.error,
                        )
                    )
                    progress.step(f"{shape} {scheme} W={W:g}: error {res.error:.4f}")
    records = comm.bcast(records, root=0)
    report = {
        "bench": "mpm",
        "warmup_seconds_1d": comm.bcast(warmup_1d, root=0),
        "engine": f"{args.backend}; block decomposed over {comm.size} rank(s), bars on one",
        "versions": versions(),
        "records": records,
        "rates": {},
    }
    if comm.rank == 0:
        echo(comm, format_table(records, COLUMNS))
        for line in ratios:
            echo(comm, line)
        args.out.mkdir(parents=True, exist_ok=True)
        if runs:
            _plot(runs, Ws, args.out / "mpm_bar.png")
            echo(comm, f"plot: {args.out / 'mpm_bar.png'}")
        if impacts:
            _plot_impact(impacts, args.out / "mpm_impact.png")
            echo(comm, f"plot: {args.out / 'mpm_impact.png'}")
        if histories:
            _plot_energy(histories, args.out / "mpm_translating.png")
            echo(comm, f"plot: {args.out / 'mpm_translating.png'}")
        if args.json is not None:
            write_json(args.json, report)
    return report
