"""``geofrac bench mpm``: accuracy against cost of the MPM variants (seed chapter 4).

Case so far: the quasi-static bar of seed 4.5.1 (:mod:`geofrac.mpm.bar`) at the seed's
W = ρ₀|b|L₀ = 1000, 12500 and 100000 (``--W``), for every shape (``mpm``, ``ugimp``,
``cpgimp``) and scheme (``musl``, ``usf``, ``usavg``): the RMS stress error against eq.
4.73 (normalised by ρ₀|b|L₀) beside particle-steps per second. The engine is the pure
numpy reference and runs on one rank (under ``mpiexec`` rank 0 runs it, ``ranks`` in
the records says 1). Prints a table; ``--json F`` writes the records, ``--out DIR`` the
stress profiles (``mpm_bar.png``, after Fig. 4.13-4.15).
"""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

__all__ = ["COLUMNS", "add_arguments", "run"]

#: (key, header, format) of the printed table.
COLUMNS = (
    ("shape", "shape", "s"),
    ("scheme", "scheme", "s"),
    ("W", "W", "g"),
    ("particles", "particles", "d"),
    ("steps", "steps", "d"),
    ("particle_steps_per_s", "particle-steps/s", ".3g"),
    ("stress_error_rms", "stress error (RMS/ρ0|b|L0)", ".4f"),
)


def add_arguments(p: argparse.ArgumentParser) -> None:
    """Options of this bench."""
    p.add_argument(
        "--W", default="1000,12500,100000", help="comma-separated W = ρ0|b|L0 of the bar"
    )
    p.add_argument("--shapes", default="mpm,ugimp,cpgimp", help="comma-separated shapes")
    p.add_argument("--schemes", default="musl,usf,usavg", help="comma-separated schemes")
    p.add_argument("--json", type=Path, help="write the JSON report to this file")
    p.add_argument(
        "--out", type=Path, default=Path("results/bench_mpm"), help="directory of the plot"
    )


def _names(text: str, allowed: tuple[str, ...], option: str) -> list[str]:
    names = [t.strip() for t in text.split(",") if t.strip()]
    bad = [n for n in names if n not in allowed]
    if bad or not names:
        raise SystemExit(f"{option}: choose from {', '.join(allowed)} (got {text!r})")
    return names


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
        ax.plot(x / delta, self_weight_stress(x, E, rho0, b, L0) / W, "k-", lw=1, label="eq. 4.73")
        ax.set_xlabel("x / Δ")
        ax.set_title(f"W = {W:g}")
    save_figure(
        fig, axes, path, "Quasi-static bar at t = L0/c (seed Fig. 4.13-4.15)", "σ / ρ0|b|L0"
    )


def run(args: argparse.Namespace, comm: Any) -> dict[str, Any]:
    """Run the variants; print the table (rank 0); return the JSON report."""
    from geofrac.bench.report import format_table
    from geofrac.io.summary import versions, write_json
    from geofrac.log import Progress, echo
    from geofrac.mpm.bar import quasi_static_bar
    from geofrac.mpm.schemes import SCHEMES
    from geofrac.mpm.shapes import SHAPES

    shapes = _names(args.shapes, SHAPES, "--shapes")
    schemes = _names(args.schemes, SCHEMES, "--schemes")
    try:
        Ws = [float(w) for w in args.W.split(",") if w.strip()]
    except ValueError:
        raise SystemExit(f"--W: a comma-separated list of numbers, got {args.W!r}") from None
    if not Ws or min(Ws) <= 0:
        raise SystemExit(f"--W: every W must be > 0, got {args.W!r}")
    records: list[dict[str, Any]] = []
    runs = {}
    if comm.rank == 0:
        progress = Progress(comm, len(Ws) * len(shapes) * len(schemes), "bench mpm")
        for W in Ws:
            for shape in shapes:
                for scheme in schemes:
                    res = quasi_static_bar(shape, scheme, W)
                    runs[(shape, scheme, W)] = res
                    n = len(res.x)
                    records.append(
                        {
                            "case": "quasi_static_bar",
                            "scheme": scheme,
                            "shape": shape,
                            "smoothing": "none",
                            "dim": 1,
                            "particles": n,
                            "ranks": 1,
                            "W": W,
                            "steps": res.steps,
                            "seconds": res.seconds,
                            "particle_steps_per_s": n * res.steps / res.seconds,
                            "stress_error_rms": res.error,
                            "energy_drift_max": None,
                        }
                    )
                    progress.step(f"{shape} {scheme} W={W:g}: error {res.error:.4f}")
    records = comm.bcast(records, root=0)
    report = {
        "bench": "mpm",
        "engine": "numpy reference, one rank",
        "versions": versions(),
        "records": records,
        "rates": {},
    }
    if comm.rank == 0:
        echo(comm, format_table(records, COLUMNS))
        args.out.mkdir(parents=True, exist_ok=True)
        _plot(runs, Ws, args.out / "mpm_bar.png")
        echo(comm, f"plot: {args.out / 'mpm_bar.png'}")
        if args.json is not None:
            write_json(args.json, report)
    return report
