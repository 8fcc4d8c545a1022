"""Draw the notched beam's crack paths on grain interfaces and on element edges together.

Run from the repository root after the two runs::

    geofrac run jobs/grain_notched_beam.toml --out GRAIN
    geofrac run jobs/notched_beam.toml --out EDGE
    python docs/grain_paths.py GRAIN EDGE [--png PATH]

Each directory holds one completed run (``events.csv``, ``summary.json``,
``results.h5``). The picture (default ``grain_beam_paths.png`` in the current directory)
shows the part of the beam around the notch: the beam's outline (the boundary edges of the
edge run's mesh, read from its ``results.h5``), one dot per event at the point
``events.csv`` gives for it (an interface's point for the grain run, an edge's midpoint
for the edge run), and a star where each run's crack first reaches the top face
(``crack_face`` of its summary; none if it did not). The edge scene's ``face_band`` (the
experiment's 30-40 mm) is shaded just above the top face. Axes carry the length unit of
the scenes' ``[units]`` (none if undeclared).
"""

from __future__ import annotations

import argparse
import csv
import json
from pathlib import Path

import h5py
import matplotlib
import numpy as np

matplotlib.use("Agg")
import matplotlib.pyplot as plt
from matplotlib.collections import LineCollection

#: The part of the beam drawn: x from the face origin (the centre), y down from the top.
X_RANGE = (-110.0, 190.0)
Y_BELOW_TOP = 165.0


def _outline(run: Path) -> np.ndarray:
    """The boundary edges of the run's mesh, shape=(k, 2, 2)."""
    with h5py.File(run / "results.h5", "r") as f:
        x = f["Mesh/mesh/geometry"][:, :2]
        cells = f["Mesh/mesh/topology"][:]
    edges = np.sort(np.concatenate([cells[:, [i, (i + 1) % 3]] for i in range(3)]), axis=1)
    unique, count = np.unique(edges, axis=0, return_counts=True)
    return x[unique[count == 1]]


def _events(run: Path) -> np.ndarray:
    """Each event's point, shape=(events, 2)."""
    with open(run / "events.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    return np.array([(float(r["x"]), float(r["y"])) for r in rows]).reshape(-1, 2)


def _label(text: str, unit: str) -> str:
    return f"{text} ({unit})" if unit else text


def main() -> None:
    """Draw the picture (see the module text)."""
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("grain", type=Path, help="output directory of jobs/grain_notched_beam.toml")
    p.add_argument("edge", type=Path, help="output directory of jobs/notched_beam.toml")
    p.add_argument("--png", type=Path, default=Path("grain_beam_paths.png"), help="the picture")
    args = p.parse_args()

    outline = _outline(args.edge)
    top = float(outline[:, :, 1].max())
    edge_input = json.loads((args.edge / "summary.json").read_text())["scene"]["input"]
    unit = edge_input.get("units", {}).get("length", "")
    origin = float(edge_input["cracking"].get("face_origin", 0.0))

    fig, ax = plt.subplots(figsize=(7.5, 5.4))
    ax.add_collection(LineCollection(outline, colors="k", linewidths=1.0, label="beam outline"))
    band = edge_input["cracking"].get("face_band")
    if band:
        ax.fill_between(
            [origin + band[0], origin + band[1]],
            top,
            top + 6.0,
            color="0.75",
            lw=0,
            label=f"experiment: top at {band[0]:g}-{band[1]:g} {unit}",
        )
    for run, kind, colour in (
        (args.grain, "grain interfaces", "tab:red"),
        (args.edge, "element edges", "tab:blue"),
    ):
        summary = json.loads((run / "summary.json").read_text())
        cracking = summary["results"]["cracking"]
        points = _events(run)
        name = summary["scene"]["name"]
        ax.plot(
            points[:, 0],
            points[:, 1],
            "o",
            ms=3.5,
            color=colour,
            label=f"{name}: {kind}, {len(points)} events",
        )
        face = cracking.get("crack_face")
        if face:
            x = origin + float(face["x_from_origin"])
            ax.plot(
                [x],
                [top],
                "*",
                ms=14,
                color=colour,
                mec="k",
                mew=0.6,
                label=f"{name}: top at x = {x:.1f} {unit} (event {face['event']})",
            )
    ax.set_xlim(origin + X_RANGE[0], origin + X_RANGE[1])
    ax.set_ylim(top - Y_BELOW_TOP, top + 10.0)
    ax.set_aspect("equal")
    ax.set_xlabel(_label("x", unit))
    ax.set_ylabel(_label("y", unit))
    ax.set_title("Notched beam: crack paths on grain interfaces and on element edges", fontsize=10)
    fig.legend(
        *ax.get_legend_handles_labels(), loc="lower center", ncol=2, fontsize=8, frameon=False
    )
    fig.tight_layout(rect=(0.0, 0.15, 1.0, 1.0))
    args.png.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(args.png, dpi=110)
    plt.close(fig)
    print(f"wrote {args.png}")


if __name__ == "__main__":
    main()
