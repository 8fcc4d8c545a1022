"""``geofrac bench granular``: crack events along grain interfaces (Edo (2016), §3.5-3.6).

Cases (``--cases``, default all): ``beam`` (jobs/grain_notched_beam.toml, §3.5.1),
``holes1``, ``holes3``, ``holes5`` (jobs/grain_holes{1,3,5}.toml, §3.5.2), ``dcn0``,
``dcn4a``, ``dcn4b`` (jobs/grain_dcn_0pct.toml and the two 4 % layouts, §3.6), all at
the thesis's size (``--set KEY=VALUE`` applies to every case). Each runs ``--events`` events
(default: the scene's ``max_events``) with the ranks it is started with and reports
events/s, the seconds per phase (assemble, solve, criterion, update; maximum over
ranks), the end reason, the cracked and pre-cracked
interfaces, the grains per field (EFMM, quadratic, linear, rotation, fragment) and, for
the beam, where the crack first reaches the top face (``crack_top_x_mm``).
"""

from __future__ import annotations

import argparse
import tomllib
from pathlib import Path
from typing import TYPE_CHECKING, Any

from geofrac.bench.cracking import event_case
from geofrac.fracture import SOLVERS

if TYPE_CHECKING:
    from mpi4py import MPI

__all__ = ["CASES", "add_arguments", "run"]

_JOBS = Path(__file__).resolve().parents[2] / "jobs"

#: case -> scene in jobs/
CASES = {
    "beam": "grain_notched_beam",
    "holes1": "grain_holes1",
    "holes3": "grain_holes3",
    "holes5": "grain_holes5",
    "dcn0": "grain_dcn_0pct",
    "dcn4a": "grain_dcn_4pct_seed1",
    "dcn4b": "grain_dcn_4pct_seed2",
}


def add_arguments(p: argparse.ArgumentParser) -> None:
    """Options of this bench."""
    p.add_argument("--cases", default=",".join(CASES), help="comma-separated: " + ", ".join(CASES))
    p.add_argument("--events", type=int, help="events per case (default: the scene's max_events)")
    p.add_argument("--solver", choices=SOLVERS, default="update", help="cracking.solver")
    p.add_argument("--json", type=Path, help="write the JSON records to this file")


def run(args: argparse.Namespace, comm: MPI.Comm) -> list[dict[str, Any]]:
    """Run the cases; print one line per case (rank 0); return the records."""
    from geofrac.io.summary import write_json

    cases = [c.strip() for c in args.cases.split(",") if c.strip()]
    for case in cases:
        if case not in CASES:
            raise SystemExit(f"unknown case '{case}'; choose from {', '.join(CASES)}")
    if args.events is not None and args.events < 1:
        raise SystemExit("--events must be >= 1")
    records = []
    for case in cases:
        name = CASES[case]
        events = args.events
        if events is None:
            with open(_JOBS / f"{name}.toml", "rb") as f:
                events = int(tomllib.load(f)["cracking"]["max_events"])
        extra = tuple(getattr(args, "overrides", None) or ())
        rec = event_case(case, name, extra, events=events, solver=args.solver, comm=comm)
        res = rec.pop("results")
        rec |= {
            k: res[k]
            for k in (
                "cracked_interfaces",
                "precracked_interfaces",
                "grains",
                "grains_by_field",
                "crack_top_x_mm",
            )
            if k in res
        }
        records.append(rec)
    if args.json is not None and comm.rank == 0:
        write_json(args.json, records)
    return records
