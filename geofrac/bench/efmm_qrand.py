"""``geofrac bench efmm-qrand``: EFMM's accuracy as the integration domains vary (Table 3.1).

On the cantilever of Edo (2016), §3.4.1 (``jobs/cantilever_efmm.toml``) each mesh is solved with
EFMM for q_rand = 0, 0.1, …, 0.8 (§3.4.2) and, for q_rand > 0, several domain seeds
(``--seeds``; q_rand = 0 has one solution, the incentres). Per mesh the bench reports
the mean and the standard deviation (population, over all solves) of the displacement
error ||E||_u and the energy error ||E||_e (eq. 3.30), their ratio, and the thesis's
Table 3.1 beside them; ``efmm-qrand.json`` and ``efmm-qrand.png`` go to ``--out``.
"""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import TYPE_CHECKING, Any

from geofrac.bench.args import number_list

if TYPE_CHECKING:
    from mpi4py import MPI

__all__ = ["THESIS_TABLE", "add_arguments", "run"]

_DEFAULT_SCENE = Path(__file__).resolve().parents[2] / "jobs" / "cantilever_efmm.toml"

#: Edo (2016), Table 3.1: ny -> (mean ||E||_u, std ||E||_u, mean ||E||_e, std ||E||_e).
THESIS_TABLE: dict[int, tuple[float, float, float, float]] = {
    2: (5.96e-2, 1.20e-3, 2.58e-1, 2.07e-3),
    4: (1.03e-2, 4.24e-4, 1.04e-1, 1.09e-3),
    6: (3.70e-3, 3.53e-4, 5.90e-2, 2.66e-4),
    8: (1.73e-3, 1.98e-4, 3.87e-2, 3.26e-4),
    10: (9.98e-4, 1.54e-4, 2.79e-2, 1.98e-4),
    12: (6.31e-4, 1.13e-4, 2.14e-2, 1.01e-4),
    14: (4.37e-4, 1.15e-4, 1.71e-2, 3.67e-5),
    16: (3.25e-4, 1.08e-4, 1.41e-2, 6.95e-5),
    18: (2.45e-4, 8.65e-5, 1.18e-2, 3.02e-5),
    20: (1.90e-4, 7.29e-5, 1.00e-2, 3.75e-5),
    22: (1.62e-4, 9.03e-5, 8.84e-3, 8.18e-5),
    24: (1.34e-4, 8.40e-5, 7.70e-3, 4.30e-5),
}

_depths = number_list(int, lambda v: v >= 1, "positive")
_qs = number_list(float, lambda v: 0.0 <= v <= 1.0, "in [0, 1]")


def add_arguments(p: argparse.ArgumentParser) -> None:
    """Options of this bench."""
    p.add_argument(
        "--meshes",
        type=_depths,
        default=sorted(THESIS_TABLE),
        help="comma-separated depths ny, nx = 4 ny (default: 2,4,...,24 as in Edo (2016))",
    )
    p.add_argument(
        "--q-rand",
        type=_qs,
        default=[round(0.1 * i, 1) for i in range(9)],
        help="comma-separated q_rand values (default: 0,0.1,...,0.8 as in Edo (2016))",
    )
    p.add_argument(
        "--seeds",
        type=int,
        default=3,
        help="domain seeds per q_rand > 0 (default: 3)",
    )
    p.add_argument(
        "--scene",
        type=Path,
        default=_DEFAULT_SCENE,
        help=f"base scene (default: {_DEFAULT_SCENE})",
    )
    p.add_argument(
        "--out", type=Path, default=Path("results/bench-efmm-qrand"), help="output directory"
    )
    p.add_argument("--json", type=Path, help="also write the JSON report to this file")


def _rows(records: list[dict[str, Any]], depths: list[int]) -> list[dict[str, Any]]:
    import numpy as np

    rows = []
    for ny in depths:
        mine = [r for r in records if r["ny"] == ny]
        u = np.array([r["error_u"] for r in mine])
        en = np.array([r["error_energy"] for r in mine])
        row: dict[str, Any] = {
            "mesh": f"{4 * ny}x{ny}",
            "solves": len(mine),
            "u_mean": float(u.mean()),
            "u_std": float(u.std()),
            "energy_mean": float(en.mean()),
            "energy_std": float(en.std()),
        }
        row["u_std_over_mean"] = row["u_std"] / row["u_mean"]
        row["energy_std_over_mean"] = row["energy_std"] / row["energy_mean"]
        if ny in THESIS_TABLE:
            s = THESIS_TABLE[ny]
            row |= {"thesis_u_mean": s[0], "thesis_u_std": s[1], "thesis_energy_mean": s[2]}
            row |= {"thesis_energy_std": s[3]}
        rows.append(row)
    return rows


def run(args: argparse.Namespace, comm: MPI.Comm) -> dict[str, Any]:
    """Run the study; return the JSON report (identical on every rank)."""
    from geofrac.bench.report import format_table, save_report
    from geofrac.io.summary import versions
    from geofrac.log import Progress, echo
    from geofrac.runner import solve_scene
    from geofrac.scene import SceneError, load_scene_collective

    if args.seeds < 1:
        raise SceneError("--seeds", "", f"must be >= 1, got {args.seeds}")
    cases = [
        (ny, q, seed)
        for ny in args.meshes
        for q in args.q_rand
        for seed in (range(1) if q == 0 else range(args.seeds))
    ]
    progress = Progress(comm, len(cases), "bench efmm-qrand", unit="solves")
    records = []
    for ny, q, seed in cases:
        overrides = [
            "discretization.element=efmm",
            f"discretization.q_rand={q}",
            f"discretization.domain_seed={seed}",
            f"geometry.parameters.nx={4 * ny}",
            f"geometry.parameters.ny={ny}",
            "output.probes={}",
            *args.overrides,
        ]
        scene = load_scene_collective(comm, args.scene, overrides)
        solution = solve_scene(scene, comm, verbose=False)
        try:
            errors = solution.results["errors"]
            clamped = solution.problem.describe()["clamped_crossings"]
        finally:
            solution.problem.destroy()
        records.append(
            {
                "ny": ny,
                "q_rand": q,
                "seed": seed,
                "error_u": errors["u"],
                "error_energy": errors["energy"],
                "clamped_crossings": clamped,
            }
        )
        progress.step(f"{4 * ny}x{ny} q_rand {q:.1f} seed {seed}: ||E||_u {errors['u']:.3e}")
    rows = _rows(records, args.meshes)
    report = {
        "bench": "efmm-qrand",
        "scene": str(args.scene),
        "overrides": list(args.overrides),
        "ranks": comm.size,
        "versions": versions(),
        "q_rand": list(args.q_rand),
        "seeds": args.seeds,
        "std_definition": "population standard deviation over every solve of the mesh "
        "(q_rand = 0 once, each q_rand > 0 once per seed)",
        "records": records,
        "table": rows,
        "std_below_mean_by_10x": {
            "u": all(r["u_std_over_mean"] <= 0.1 for r in rows),
            "energy": all(r["energy_std_over_mean"] <= 0.1 for r in rows),
        },
    }
    if comm.rank == 0:
        columns = (
            ("mesh", "mesh", "s"),
            ("solves", "solves", "d"),
            ("u_mean", "||E||_u mean", ".3e"),
            ("u_std", "std", ".2e"),
            ("u_std_over_mean", "std/mean", ".3f"),
            ("thesis_u_mean", "Edo (2016) mean", ".2e"),
            ("thesis_u_std", "Edo (2016) std", ".2e"),
            ("energy_mean", "||E||_e mean", ".3e"),
            ("energy_std", "std", ".2e"),
            ("energy_std_over_mean", "std/mean", ".3f"),
            ("thesis_energy_mean", "Edo (2016) mean", ".2e"),
            ("thesis_energy_std", "Edo (2016) std", ".2e"),
        )
        echo(comm, format_table(rows, columns))
        ok = report["std_below_mean_by_10x"]
        echo(
            comm,
            f"std at least 10x below the mean on every mesh: displacement {ok['u']}, "
            f"energy {ok['energy']}",
        )
        save_report(report, args.out / "efmm-qrand.json", args.json)
        _plot(rows, args.out / "efmm-qrand.png")
        echo(comm, f"wrote {args.out / 'efmm-qrand.json'} and {args.out / 'efmm-qrand.png'}")
    return report


def _plot(rows: list[dict[str, Any]], path: Path) -> None:
    """Mean error with ±1 std bars against √nodes, ours and Edo (2016)'s, both norms."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import numpy as np
    from matplotlib.ticker import FormatStrFormatter

    from geofrac.bench.report import save_figure

    ny = np.array([int(r["mesh"].split("x")[1]) for r in rows])
    sqrt_nodes = np.sqrt((4 * ny + 1) * (ny + 1))
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.8), constrained_layout=True)
    panels = (("u", "||E||_u", "displacement error"), ("energy", "||E||_e", "energy error"))
    for ax, (key, label, what) in zip(axes, panels, strict=True):
        ax.set_title(f"{what} {label}", fontsize=10)
        means = [r[f"{key}_mean"] for r in rows]
        ax.errorbar(sqrt_nodes, means, [r[f"{key}_std"] for r in rows], fmt="o-", capsize=3,
                    label=f"geofrac {label}")  # fmt: skip
        thesis = np.array([(s, r[f"thesis_{key}_mean"], r[f"thesis_{key}_std"])
                         for s, r in zip(sqrt_nodes, rows, strict=True)
                         if f"thesis_{key}_mean" in r])  # fmt: skip
        if len(thesis):
            ax.errorbar(thesis[:, 0], thesis[:, 1], thesis[:, 2], fmt="s--", capsize=3,
                        label=f"Edo (2016), Table 3.1 {label}")  # fmt: skip
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("√(number of nodes)")
        ax.xaxis.set_major_formatter(FormatStrFormatter("%g"))
        ax.xaxis.set_minor_formatter(FormatStrFormatter("%g"))
    save_figure(
        fig,
        axes,
        path,
        title="EFMM with random integration domains (Edo (2016), §3.4.2, Table 3.1)",
        ylabel="mean ± std over q_rand 0-0.8 and seeds",
    )
