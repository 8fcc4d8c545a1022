"""``geofrac bench cracking``: events per second and time per phase of the crack driver.

Cases (``--cases``): ``beam`` (jobs/notched_beam.toml at the size of Edo (2016), RGNT), ``model2``
(jobs/crack_model2.toml: DFN Model 2 at the thesis's size, RGNT, 115k DOFs),
``model2_contact`` (the same with crack-face contact), ``model_1m`` (Model 2's network on a
mesh of 0.27 mm instead of 0.84 mm: about 1.0M DOFs), ``plate`` (jobs/plate_hole.toml) and
``patch`` (the patch test over the thesis's node counts, error (2.22) per mesh). Each event
case runs ``--events`` events on the ranks it is started with and reports events/s, the
seconds of each phase (assemble, solve, criterion/stress, update) as the maximum over
ranks, the seconds of each part of the work per rank
(:data:`geofrac.fracture.linear.PARTS`), factorisations and the peak memory per rank.
Run it under ``mpiexec -n 2`` for the 2-rank figures.
"""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import TYPE_CHECKING, Any

from geofrac.fracture import SOLVERS

if TYPE_CHECKING:
    from mpi4py import MPI

__all__ = ["CASES", "PATCH_H", "add_arguments", "event_case", "run"]

_JOBS = Path(__file__).resolve().parents[2] / "jobs"

#: case -> (scene, extra overrides)
CASES: dict[str, tuple[str, tuple[str, ...]]] = {
    "beam": ("notched_beam", ()),
    "model2": ("crack_model2", ()),
    "model2_contact": ("crack_model2", ("cracking.contact=true",)),
    "model_1m": ("crack_model2", ("dfn.mesh_size=0.27",)),
    "plate": ("plate_hole", ()),
}

#: Mesh sizes of meshes/patch_core.geo for the node counts 218 ... 9857 of Edo (2016).
PATCH_H = (0.475, 0.26, 0.182, 0.128, 0.0904, 0.056)


def add_arguments(p: argparse.ArgumentParser) -> None:
    """Options of this bench."""
    p.add_argument(
        "--cases",
        default="beam,model2",
        help="comma-separated: beam, model2, model2_contact, model_1m, plate, patch",
    )
    p.add_argument("--events", type=int, default=30, help="events per case (default 30)")
    p.add_argument(
        "--solver",
        choices=SOLVERS,
        default="update",
        help="cracking.solver of every case (default update)",
    )
    p.add_argument("--json", type=Path, help="write the JSON records to this file")


def run(args: argparse.Namespace, comm: MPI.Comm) -> list[dict[str, Any]]:
    """Run the cases; print a table (rank 0); return the records."""
    from geofrac.io.summary import write_json
    from geofrac.log import echo
    from geofrac.runner import solve_scene
    from geofrac.scene import load_scene_collective

    if args.events < 1:
        raise SystemExit("--events must be >= 1")
    user = tuple(getattr(args, "overrides", None) or ())
    records = []
    for case in [c.strip() for c in args.cases.split(",") if c.strip()]:
        if case == "patch":
            for h in PATCH_H:
                scene = load_scene_collective(
                    comm, _JOBS / "crack_patch_test.toml", [f"geometry.parameters.h={h}", *user]
                )
                sol = solve_scene(scene, comm, verbose=False)
                res = sol.results["cracking"]
                sol.problem.destroy()
                assert scene.discretization is not None  # a fem scene has one
                records.append(
                    {
                        "case": "patch",
                        "element": scene.discretization.element,
                        "ranks": comm.size,
                        "dofs": res["dofs"],
                        "nodes": sol.mesh_counts()["vertices"],
                        "h": h,
                        "displacement_error_l2": res["displacement_error_l2"],
                    }
                )
                echo(
                    comm,
                    f"patch h={h}: {records[-1]['nodes']} nodes, "
                    f"error {res['displacement_error_l2']:.3e}",
                )
            continue
        if case not in CASES:
            raise SystemExit(f"unknown case '{case}'; choose from {', '.join([*CASES, 'patch'])}")
        name, extra = CASES[case]
        records.append(
            event_case(
                case, name, (*extra, *user), events=args.events, solver=args.solver, comm=comm
            )
        )
    if args.json is not None and comm.rank == 0:
        write_json(args.json, records)
    return records


def event_case(
    case: str, name: str, extra: tuple[str, ...], *, events: int, solver: str, comm: MPI.Comm
) -> dict[str, Any]:
    """Run ``events`` events of scene ``jobs/<name>.toml``; print and return its record.

    The record holds the DOFs, events, events/s, solver counts, the end reason, the
    seconds of each phase (maximum over ranks) and the scene's ``results.cracking``
    under ``results``; with ``cracking.contact``, the contact iterations per event, the
    pairs held after cycles and the worst gap.
    """
    from geofrac.log import echo
    from geofrac.runner import solve_scene
    from geofrac.scene import load_scene_collective

    overrides = [*extra, f"cracking.max_events={events}", f"cracking.solver={solver}"]
    scene = load_scene_collective(comm, _JOBS / f"{name}.toml", overrides)
    sol = solve_scene(scene, comm, verbose=False)
    res = sol.results["cracking"]
    sol.problem.destroy()
    assert scene.discretization is not None  # a fem scene has one
    record = {
        "case": case,
        "element": scene.discretization.element,
        "ranks": comm.size,
        "dofs": res["dofs"],
        "events": res["events"],
        "events_per_s": res["events_per_s"],
        "solver": solver,
        "factorizations": res["factorizations"],
        "cg_iterations": res["cg_iterations"],
        "refinement_solves": res["refinement_solves"],
        "end_reason": res["end_reason"],
        **{f"{k}_s": v for k, v in res["phase_s"].items()},
        "phase_s_per_rank": res["phase_s_per_rank"],
        "part_s_per_rank": res["part_s_per_rank"],
        "peak_rss_mb_per_rank": res["peak_rss_mb_per_rank"],
        "results": res,
    }
    contact = res.get("contact")
    if contact is not None:
        record["contact_iterations_per_event"] = contact["iterations_per_event"]
        record["contact_frozen_pairs"] = contact["frozen_pairs"]
        record["contact_worst_gap"] = contact["worst_gap"]
        record["contact_worst_gap_relative"] = contact["worst_gap_relative"]
    echo(
        comm,
        f"{case}: {record['dofs']} DOFs, {record['events']} events on {comm.size} rank(s): "
        f"{record['events_per_s']:.2f} events/s; assemble {record['assemble_s']:.1f} s, solve "
        f"{record['solve_s']:.1f} s, criterion {record['criterion_s']:.1f} s, update "
        f"{record['update_s']:.1f} s; {record['factorizations']} factorisations, "
        f"{record['cg_iterations']} CG iterations, "
        f"{record['refinement_solves']} refinement solves; end {record['end_reason']}",
    )
    parts = ", ".join(
        f"{k} {'/'.join(f'{v:.1f}' for v in per_rank)}"
        for k, per_rank in res["part_s_per_rank"].items()
        if max(per_rank) > 0
    )
    echo(comm, f"{case}: seconds per part of the work (rank 0/1/...): {parts}")
    echo(
        comm,
        f"{case}: peak memory per rank (MiB): "
        + ", ".join(f"{v:.0f}" for v in res["peak_rss_mb_per_rank"])
        + f"; {sum(res['peak_rss_mb_per_rank']) / 1024:.2f} GiB in all",
    )
    if contact is not None:
        echo(
            comm,
            f"{case}: contact: {contact['iterations_per_event']:.2f} iterations/event, "
            f"{contact['pairs']} face pairs ({contact['open']} open, {contact['stick']} stick, "
            f"{contact['slip']} slip), {contact['frozen_pairs']} held after cycles, worst gap "
            f"{contact['worst_gap']:.3g} ({contact['worst_gap_relative']:.2%} of the control "
            "displacement)",
        )
    return record
