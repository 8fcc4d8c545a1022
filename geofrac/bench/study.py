"""The accuracy-cost loop shared by the convergence benches (cantilever, mms3d).

A study is a list of cases (element, mesh label, scene overrides). Each case is solved
with :func:`geofrac.runner.solve_scene`; assemble+solve are timed ``repeat`` times and
the fastest kept; one record per case carries sizes, errors and phase times. The
report adds convergence rates and, for a target relative displacement error, the
wall time and DOFs each element needs (interpolated log-log between the meshes that
bracket it). Output: a table and summary lines on rank 0, ``NAME.json`` and
``NAME.png`` in the output directory.
"""

from __future__ import annotations

import argparse
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from mpi4py import MPI

__all__ = [
    "COLUMNS",
    "Case",
    "add_common_arguments",
    "at_time",
    "equal_time",
    "parse_elements",
    "run_study",
    "to_target",
]

#: Table columns of every convergence study.
COLUMNS = (
    ("element", "element", "s"),
    ("mesh", "mesh", "s"),
    ("nodes", "nodes", "d"),
    ("dofs", "DOFs", "d"),
    ("error_u", "||e||_u", ".4e"),
    ("error_u_relative", "rel. ||e||_u", ".3e"),
    ("error_energy", "||e||_energy", ".4e"),
    ("time_assemble_s", "assemble [s]", ".4f"),
    ("time_solve_s", "solve [s]", ".4f"),
    ("time_total_s", "total [s]", ".4f"),
)


@dataclass(frozen=True)
class Case:
    """One solve of a study.

    Attributes:
        element: element name.
        mesh: mesh label for the table, e.g. ``"4x40"``.
        overrides: ``--set`` style overrides that select the element and the mesh.
    """

    element: str
    mesh: str
    overrides: tuple[str, ...]


def add_common_arguments(
    p: argparse.ArgumentParser, name: str, default_elements: str, *, default_scene: Path | None
) -> None:
    """Options every convergence bench has: elements, scene, output, repeat, target."""
    from geofrac.elements import available

    p.add_argument(
        "--elements",
        default=default_elements,
        help=f"comma-separated elements from {', '.join(available())} "
        f"(default: {default_elements})",
    )
    p.add_argument(
        "--scene",
        type=Path,
        default=default_scene,
        help=f"base scene (default: {default_scene or 'the set-up s scene'})",
    )
    p.add_argument(
        "--out", type=Path, default=Path(f"results/bench-{name}"), help="output directory"
    )
    p.add_argument("--json", type=Path, help="also write the JSON report to this file")
    p.add_argument(
        "--repeat",
        type=int,
        default=3,
        help="time assemble+solve this many times per case and keep the fastest (default: 3)",
    )
    p.add_argument(
        "--target",
        type=float,
        default=1e-3,
        help="relative displacement error whose cost is reported per element (default: 1e-3)",
    )


def parse_elements(text: str, dim: int) -> list[str]:
    """Element names from a comma-separated list, each checked against the registry.

    Raises:
        SceneError: an unknown element or one that does not support ``dim``.
    """
    from geofrac.elements import available, get
    from geofrac.scene import SceneError

    elements = [e.strip() for e in text.split(",") if e.strip()]
    for e in elements:
        if e not in available():
            raise SceneError(
                "--elements", e, f"unknown element (available: {', '.join(available())})"
            )
        if dim not in get(e).dims:
            raise SceneError("--elements", e, f"element '{e}' does not support {dim}D")
    return elements


def to_target(records: Sequence[dict[str, Any]], target: float) -> dict[str, Any]:
    """Cost of reaching a relative displacement error ``target`` on one element's meshes.

    Wall time (assemble + solve) and DOFs are interpolated linearly in log-log between
    the last mesh above and the first mesh at or below the target.

    Args:
        records: one element's records, ordered by refinement.
        target: relative displacement error to reach.

    Returns:
        ``reached``; when reached ``time_s``, ``dofs`` and ``mesh`` (the first mesh at or
        below the target); otherwise ``best_error`` (the smallest error measured).
    """
    import numpy as np

    errors = [r["error_u_relative"] for r in records]
    hit = next((i for i, e in enumerate(errors) if e <= target), None)
    if hit is None:
        return {"reached": False, "best_error": float(min(errors))}
    out: dict[str, Any] = {"reached": True, "mesh": records[hit]["mesh"]}
    for key, name in (("time_total_s", "time_s"), ("dofs", "dofs")):
        if hit == 0:
            out[name] = float(records[0][key])
            continue
        e0, e1 = np.log(errors[hit - 1]), np.log(errors[hit])
        y0, y1 = np.log(records[hit - 1][key]), np.log(records[hit][key])
        s = (np.log(target) - e0) / (e1 - e0) if e1 != e0 else 1.0
        out[name] = float(np.exp(y0 + s * (y1 - y0)))
    return out


def at_time(records: Sequence[dict[str, Any]], budget: float) -> float | None:
    """Relative displacement error one element reaches in wall time ``budget``.

    Interpolated log-log between the two meshes whose assemble+solve times bracket the
    budget; None when the budget lies outside the element's measured times.

    Args:
        records: one element's records, ordered by refinement.
        budget: wall time in seconds.
    """
    import numpy as np

    times = np.array([r["time_total_s"] for r in records], dtype=float)
    errors = np.array([r["error_u_relative"] for r in records], dtype=float)
    order = np.argsort(times)
    times, errors = times[order], errors[order]
    if len(times) == 0 or not times[0] <= budget <= times[-1]:
        return None
    i = int(np.searchsorted(times, budget))
    if i == 0 or times[i] == times[i - 1]:
        return float(errors[i])
    s = (np.log(budget) - np.log(times[i - 1])) / (np.log(times[i]) - np.log(times[i - 1]))
    return float(np.exp(np.log(errors[i - 1]) + s * (np.log(errors[i]) - np.log(errors[i - 1]))))


def equal_time(by_element: dict[str, list[dict[str, Any]]]) -> dict[str, Any]:
    """Each element's relative displacement error at common wall times.

    Two budgets bound the range every element was measured over: the largest of the
    elements' fastest times and the smallest of their slowest times (when the ranges
    do not overlap the second is below the first and some errors are None).
    """
    low = max(min(r["time_total_s"] for r in rows) for rows in by_element.values())
    high = min(max(r["time_total_s"] for r in rows) for rows in by_element.values())
    budgets = [float(low), float(high)]
    return {
        "time_s": budgets,
        "error_u_relative": {
            e: [at_time(rows, t) for t in budgets] for e, rows in by_element.items()
        },
    }


def run_study(
    args: argparse.Namespace,
    comm: MPI.Comm,
    name: str,
    *,
    title: str,
    cases: Sequence[Case],
    dim: int,
    extra: dict[str, Any] | None = None,
) -> dict[str, Any]:
    """Solve every case, print the table, rates and target costs, write JSON and PNG.

    Args:
        args: parsed options (``scene``, ``overrides``, ``repeat``, ``target``, ``out``,
            ``json``).
        comm: MPI communicator.
        name: bench name (file names ``NAME.json``, ``NAME.png``).
        title: plot title.
        cases: the cases, grouped by element, each group ordered by refinement.
        dim: spatial dimension; the rate R is measured against h ∝ nodes^(-1/dim).
        extra: more JSON-ready entries for the report.

    Returns:
        the report, identical on every rank.
    """
    from geofrac.bench.report import fit_rate, format_table, plot_accuracy_cost, save_report
    from geofrac.io.summary import versions
    from geofrac.log import Progress, echo
    from geofrac.runner import solve_scene
    from geofrac.scene import SceneError, load_scene_collective
    from geofrac.timing import Timings

    if args.repeat < 1:
        raise SceneError("--repeat", "", f"must be >= 1, got {args.repeat}")
    if not 0 < args.target < 1:
        raise SceneError("--target", "", f"must be in (0, 1), got {args.target}")
    progress = Progress(comm, len(cases), f"bench {name}", unit="cases")
    records = []
    for case in cases:
        overrides = [*case.overrides, "output.probes={}", *args.overrides]
        scene = load_scene_collective(comm, args.scene, overrides)
        timings = Timings()
        solution = solve_scene(scene, comm, timings, verbose=False)
        try:
            for _ in range(args.repeat - 1):  # keep the fastest of `repeat` assemble+solve
                again = Timings()
                with again.phase("assemble"):
                    solution.problem.assemble()
                with again.phase("solve"):
                    solution.problem.solve()
                for phase in ("assemble", "solve"):
                    timings.local[phase] = min(timings.local[phase], again.local[phase])
        finally:
            solution.problem.destroy()
        t = timings.reduced(comm)
        errors = solution.results["errors"]
        counts = solution.mesh_counts()
        record = {
            "element": case.element,
            "mesh": case.mesh,
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
        records.append(record)
        progress.step(
            f"{case.element} {case.mesh}: {record['dofs']} DOFs, ||e||_u = {record['error_u']:.3e}"
        )
    elements = list(dict.fromkeys(c.element for c in cases))
    by_element = {e: [r for r in records if r["element"] == e] for e in elements}
    rates = {
        e: {
            key: fit_rate([r["nodes"] for r in rows], [r[f"error_{key}"] for r in rows], dim=dim)
            for key in ("u", "energy")
        }
        for e, rows in by_element.items()
    }
    target = {e: to_target(rows, args.target) for e, rows in by_element.items()}
    reached = sorted((v["time_s"], e) for e, v in target.items() if v["reached"])
    same_time = equal_time(by_element)
    report = {
        "bench": name,
        "scene": str(args.scene),
        "overrides": list(args.overrides),
        "ranks": comm.size,
        "versions": versions(),
        "rate_definition": f"R = -d log(error) / d log(nodes^(1/{dim})), least squares "
        "over the meshes",
        **(extra or {}),
        "records": records,
        "rates": rates,
        "target": {
            "error_u_relative": args.target,
            "fastest": reached[0][1] if reached else None,
            "elements": target,
        },
        "equal_time": same_time,
    }
    if comm.rank == 0:
        echo(comm, format_table(records, COLUMNS))
        for e, r in rates.items():
            echo(comm, f"rate R ({e}): displacement {r['u']:.2f}, energy {r['energy']:.2f}")
        echo(comm, _target_line(args.target, target, reached))
        echo(comm, _time_line(same_time))
        save_report(report, args.out / f"{name}.json", args.json)
        plot_accuracy_cost(records, args.out / f"{name}.png", title)
        echo(comm, f"wrote {args.out / f'{name}.json'} and {args.out / f'{name}.png'}")
    return report


def _time_line(same_time: dict[str, Any]) -> str:
    lines = []
    for k, t in enumerate(same_time["time_s"]):
        parts = [
            f"{e} {errs[k]:.2e}" if errs[k] is not None else f"{e} -"
            for e, errs in same_time["error_u_relative"].items()
        ]
        lines.append(f"relative displacement error in {t:.3g} s: " + "; ".join(parts))
    return "\n".join(lines)


def _target_line(
    target: float, costs: dict[str, dict[str, Any]], reached: list[tuple[float, str]]
) -> str:
    parts = [
        f"{e} {costs[e]['time_s']:.3g} s ({costs[e]['dofs']:.0f} DOFs, mesh {costs[e]['mesh']})"
        for _, e in reached
    ]
    parts += [
        f"{e} not reached (best {v['best_error']:.2e})"
        for e, v in costs.items()
        if not v["reached"]
    ]
    head = f"relative displacement error {target:.0e}"
    if reached:
        head += f": fastest {reached[0][1]}"
    return f"{head}; " + "; ".join(parts)
