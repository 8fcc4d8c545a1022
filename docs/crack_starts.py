"""Where new cracks start: at an earlier crack, beside a slipping face pair, or alone.

Reads a crack run's ``events.csv`` (and ``contact.csv`` when the run had contact) and
sorts each event's edge after the first:

- *alone*: it shares no node with an edge cracked before it (a crack nucleated away from
  the existing ones);
- *beside slip*: it shares a node with a face pair slipping when it cracked;
- *at a crack*: it shares a node with an earlier crack, none slipping.

For the *alone* ones it gives the median distance (midpoint to midpoint) to the nearest
earlier crack. Pre-existing cracks (``precracked``, DFN traces) are not in the log, so
only runs without them are sorted fully::

    PYTHONPATH=$PWD .venv/bin/python docs/crack_starts.py results/plate_hole [--events N]
"""

from __future__ import annotations

import argparse
import csv
from collections import defaultdict
from pathlib import Path

import numpy as np

__all__ = ["crack_starts", "main"]


def crack_starts(run: Path, events: int | None = None) -> dict[str, float]:
    """Counts of new cracks by where they start, over the first ``events`` events."""
    with open(run / "events.csv", newline="") as f:
        rows = list(csv.DictReader(f))[:events]
    changes: dict[int, list[tuple[int, str]]] = defaultdict(list)
    path = run / "contact.csv"
    if path.is_file():
        with open(path, newline="") as f:
            for c in csv.DictReader(f):
                changes[int(c["event"])].append((int(c["edge"]), c["to"]))
    nodes_of: dict[int, tuple[int, int]] = {}
    state: dict[int, str] = {}
    cracks_at: dict[int, int] = defaultdict(int)  # cracked edges per node
    slipping_at: dict[int, int] = defaultdict(int)  # slipping pairs per node
    seen: list[tuple[float, float]] = []
    out = {"new": 0, "alone": 0, "beside_slip": 0, "at_crack": 0}
    distances = []
    for r in rows:
        k, e = int(r["event"]), int(r["edge"])
        a, b = int(r["node_a"]), int(r["node_b"])
        # the states this event's crack was chosen with: its settled changes
        for edge, to in changes.get(k, []):
            step = int(to == "slip") - int(state.get(edge) == "slip")
            for n in nodes_of.get(edge, ()):
                slipping_at[n] += step
            state[edge] = to
        xy = (float(r["x"]), float(r["y"]))
        if k > 1:
            out["new"] += 1
            if cracks_at[a] + cracks_at[b] == 0:
                out["alone"] += 1
                d = np.hypot(*(np.array(seen) - xy).T)
                distances.append(float(d.min()))
            elif slipping_at[a] + slipping_at[b] > 0:
                out["beside_slip"] += 1
            else:
                out["at_crack"] += 1
        nodes_of[e] = (a, b)
        cracks_at[a] += 1
        cracks_at[b] += 1
        seen.append(xy)
    out["alone_median_distance"] = float(np.median(distances)) if distances else float("nan")
    return out  # type: ignore[return-value]


def main() -> None:
    """Print the table for the runs on the command line."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("runs", nargs="+", type=Path, help="output directories of crack runs")
    parser.add_argument("--events", type=int, default=None, help="the first N events only")
    args = parser.parse_args()
    print("| run | new cracks | alone | beside slip | at a crack | alone: median distance |")
    print("|---|---:|---:|---:|---:|---:|")
    for run in args.runs:
        s = crack_starts(run, args.events)
        print(
            f"| {run} | {s['new']:.0f} | {s['alone']:.0f} | {s['beside_slip']:.0f} | "
            f"{s['at_crack']:.0f} | {s['alone_median_distance']:.3g} |"
        )


if __name__ == "__main__":
    main()
