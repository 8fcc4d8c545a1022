"""``geofrac bench cantilever``: accuracy against cost on the Timoshenko cantilever.

For each element and each seed mesh ny × nx (4×40 … 11×110, seed 2.4.1) the scene
``jobs/cantilever.toml`` is solved; the bench reports nodes, DOFs, the displacement
L2 error (seed eq. 2.22), the energy error (seed eq. 3.30b) and the assemble/solve wall
times, fits the rate R against √nodes (seed Fig. 2.8: R = 2.0 for CST) and writes
``cantilever.json`` and ``cantilever.png`` to the output directory.
"""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

__all__ = ["add_arguments", "run"]

#: Seed meshes: ny (depth) values; nx = 10 ny.
SEED_MESHES = (4, 5, 6, 7, 8, 9, 10, 11)
_DEFAULT_SCENE = Path(__file__).resolve().parents[2] / "jobs" / "cantilever.toml"

COLUMNS = (
    ("element", "element", "s"),
    ("mesh", "mesh", "s"),
    ("nodes", "nodes", "d"),
    ("dofs", "DOFs", "d"),
    ("error_u", "||e||_u", ".4e"),
    ("error_energy", "||e||_energy", ".4e"),
    ("time_assemble_s", "assemble [s]", ".4f"),
    ("time_solve_s", "solve [s]", ".4f"),
    ("time_total_s", "total [s]", ".4f"),
)


def _int_list(text: str) -> list[int]:
    try:
        values = [int(v) for v in text.split(",") if v.strip()]
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"expected comma-separated integers, got {text!r}"
        ) from None
    if not values or min(values) < 1:
        raise argparse.ArgumentTypeError(f"expected positive integers, got {text!r}")
    return values


def add_arguments(p: argparse.ArgumentParser) -> None:
    """Options of this bench."""
    from geofrac.elements import available

    p.add_argument(
        "--elements",
        default="cst,p2",
        help=f"comma-separated elements from {', '.join(available())} (default: cst,p2)",
    )
    p.add_argument(
        "--meshes",
        type=_int_list,
        default=list(SEED_MESHES),
        help="comma-separated depths ny; nx = 10 ny (default: the seed's 4,...,11)",
    )
    p.add_argument(
        "--scene",
        type=Path,
        default=_DEFAULT_SCENE,
        help="base scene (default: jobs/cantilever.toml)",
    )
    p.add_argument(
        "--out", type=Path, default=Path("results/bench-cantilever"), help="output directory"
    )
    p.add_argument("--json", type=Path, help="also write the JSON report to this file")
    p.add_argument(
        "--repeat",
        type=int,
        default=3,
        help="time assemble+solve this many times per case and keep the fastest (default: 3)",
    )


def run(args: argparse.Namespace, comm: Any) -> dict[str, Any]:
    """Run the study; return the JSON report (identical on every rank)."""
    from geofrac.bench.report import fit_rate, format_table, plot_accuracy_cost
    from geofrac.elements import available
    from geofrac.io.summary import versions, write_json
    from geofrac.log import Progress, echo
    from geofrac.runner import solve_scene
    from geofrac.scene import SceneError, load_scene_collective
    from geofrac.timing import Timings

    if args.repeat < 1:
        raise SceneError("--repeat", "", f"must be >= 1, got {args.repeat}")
    elements = [e.strip() for e in args.elements.split(",") if e.strip()]
    for e in elements:
        if e not in available():
            raise SceneError(
                "--elements", e, f"unknown element (available: {', '.join(available())})"
            )
    cases = [(e, ny) for e in elements for ny in args.meshes]
    progress = Progress(comm, len(cases), "bench cantilever")
    records = []
    for element, ny in cases:
        overrides = [
            f"discretization.element={element}",
            f"geometry.parameters.nx={10 * ny}",
            f"geometry.parameters.ny={ny}",
            "output.probes={}",
            *args.overrides,
        ]
        scene = load_scene_collective(comm, args.scene, overrides)
        timings = Timings()
        solution = solve_scene(scene, comm, timings, verbose=False)
        for _ in range(args.repeat - 1):  # keep the fastest of `repeat` assemble+solve cycles
            again = Timings()
            with again.phase("assemble"):
                solution.problem.assemble()
            with again.phase("solve"):
                solution.problem.solve()
            for phase in ("assemble", "solve"):
                timings.local[phase] = min(timings.local[phase], again.local[phase])
        t = timings.reduced(comm)
        errors = solution.results["errors"]
        counts = solution.mesh_counts()
        record = {
            "element": element,
            "mesh": f"{ny}x{10 * ny}",
            "nodes": counts["vertices"],
            "cells": counts["cells"],
            "dofs": solution.problem.element.num_dofs,
            "error_u": errors["u"],
            "error_energy": errors["energy"],
            "error_u_relative": errors["u_relative"],
            "error_energy_relative": errors["energy_relative"],
            "time_mesh_s": t["mesh"],
            "time_compile_s": t["compile"],
            "time_assemble_s": t["assemble"],
            "time_solve_s": t["solve"],
            "time_total_s": t["assemble"] + t["solve"],
            "repeat": args.repeat,
            "solver": solution.results["solver"]["preset"],
        }
        solution.problem.destroy()
        records.append(record)
        progress.step(
            f"{element} {record['mesh']}: {record['dofs']} DOFs, ||e||_u = {record['error_u']:.3e}"
        )

    rates = {
        e: {
            key: fit_rate(
                [r["nodes"] for r in records if r["element"] == e],
                [r[f"error_{key}"] for r in records if r["element"] == e],
            )
            for key in ("u", "energy")
        }
        for e in elements
    }
    report = {
        "bench": "cantilever",
        "scene": str(args.scene),
        "overrides": list(args.overrides),
        "ranks": comm.size,
        "versions": versions(),
        "rate_definition": "R = -d log(error) / d log(sqrt(nodes)), least squares over the meshes",
        "seed_reference": "Fig. 2.8: R = 2.0 (CST), R = 2.1 (RGNT) in the displacement norm",
        "records": records,
        "rates": rates,
    }
    if comm.rank == 0:
        echo(comm, format_table(records, COLUMNS))
        for e, r in rates.items():
            echo(comm, f"rate R ({e}): displacement {r['u']:.2f}, energy {r['energy']:.2f}")
        args.out.mkdir(parents=True, exist_ok=True)
        write_json(args.out / "cantilever.json", report)
        if args.json is not None:
            write_json(args.json, report)
        plot_accuracy_cost(
            records,
            args.out / "cantilever.png",
            "Timoshenko cantilever (seed 2.4.1): accuracy vs cost",
        )
        echo(comm, f"wrote {args.out / 'cantilever.json'} and {args.out / 'cantilever.png'}")
    return report
