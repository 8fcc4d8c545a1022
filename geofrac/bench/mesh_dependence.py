"""``geofrac bench mesh-dependence``: does the crack follow the stress or the mesh?

Runs the symmetric notched beam (jobs/sym_notched_beam.toml, whose exact crack path is
the axis x = 0) on each gmsh 2D mesher (``geometry.algorithm``), with the user's ``--set``
overrides on every run (e.g. ``--set cracking.criterion=...`` for a new criterion), and
reports per mesher: nodes, the mean edge length h in the fine band |x| < 25 mm, events,
the largest distance of every cracked edge from the axis until the crack enters the load
pad's zone (y ≥ 95 mm, :func:`geofrac.validation.paths.spread_until`: the issue's
measure), that of the main crack until it reaches the top face
(:func:`geofrac.validation.paths.axis_deviation`; also without the pad's zone), and
where it reaches the top. ``--picture`` draws the three paths side by
side (docs/img/cracking/mesh_dependence_before.png is today's criterion).

    python -m geofrac bench mesh-dependence --picture docs/img/cracking/mesh_dependence_before.png
"""

from __future__ import annotations

import argparse
from dataclasses import asdict
from pathlib import Path
from typing import TYPE_CHECKING, Any, cast

import numpy as np

from geofrac.bench.args import name_list
from geofrac.meshing.geo import ALGORITHMS

if TYPE_CHECKING:
    from mpi4py import MPI

__all__ = ["BAND", "SCENE", "add_arguments", "band_h", "draw_paths", "run"]

SCENE = Path(__file__).resolve().parents[2] / "jobs" / "sym_notched_beam.toml"
#: half-width of the fine band of meshes/sym_notched_beam.geo (mm): h is measured in it.
BAND = 25.0
#: the picture's window around the axis (mm).
WINDOW = 45.0


def add_arguments(p: argparse.ArgumentParser) -> None:
    """Options of this bench."""
    p.add_argument(
        "--algorithms",
        type=name_list(tuple(ALGORITHMS), "mesher"),
        default=list(ALGORITHMS),
        help="comma-separated gmsh meshers (default: frontal-delaunay,delaunay,meshadapt)",
    )
    p.add_argument("--scene", type=Path, default=SCENE, help="the specimen (default: %(default)s)")
    p.add_argument("--picture", type=Path, help="draw the crack paths side by side into this PNG")
    p.add_argument("--json", type=Path, help="write the JSON records to this file")


def band_h(coords: np.ndarray, cells: np.ndarray, *, band: float = BAND) -> float:
    """Mean edge length of the triangles whose centroid lies in |x| < ``band``.

    Args:
        coords: node coordinates, shape=(num_nodes, 2).
        cells: triangles, shape=(num_cells, 3).
        band: the band's half-width.
    """
    x = coords[cells]  # shape=(num_cells, 3, 2)
    inside = np.abs(x[:, :, 0].mean(axis=1)) < band
    lengths = np.linalg.norm(x - np.roll(x, 1, axis=1), axis=2)[inside]
    return float(lengths.mean())


def run(args: argparse.Namespace, comm: MPI.Comm) -> list[dict[str, Any]]:
    """Run the specimen on each mesher; print the table (rank 0); return the records."""
    from geofrac.effects.cracking import scene_driver
    from geofrac.io.summary import write_json
    from geofrac.log import echo
    from geofrac.scene import load_scene_collective
    from geofrac.validation.paths import PAD_ZONE, CrackEvents, axis_deviation, spread_until

    user = tuple(getattr(args, "overrides", None) or ())
    records, panels = [], []
    for algorithm in args.algorithms:
        scene = load_scene_collective(comm, args.scene, [f"geometry.algorithm={algorithm}", *user])
        d = scene_driver(scene, comm)
        try:
            res = d.run()
            mesh = d.state.mesh
            cracked = d.state.cracked.copy()
            rows = list(d.rows)
        finally:
            d.destroy()
        h = band_h(mesh.coords, mesh.cells)
        top = float(mesh.coords[:, 1].max())
        events = CrackEvents.from_rows(rows)
        reach = 0.75 * h
        dev = axis_deviation(events, face_y=top, reach=reach)
        low = axis_deviation(events, face_y=top, reach=reach, below=top - PAD_ZONE)
        every, stop = spread_until(events, y_stop=top - PAD_ZONE)
        record = {
            "case": algorithm,
            "nodes": len(mesh.coords),
            "h": h,
            "events": int(cast("int", res["events"])),  # the driver's JSON results
            "end_reason": res["end_reason"],
            "distance": dev.distance,
            "distance_over_h": dev.distance / h,
            "distance_below_pad": low.distance,
            "every_edge_to_pad": every,
            "every_edge_to_pad_over_h": every / h,
            "pad_zone_event": stop,
            "deviation": asdict(dev),
            "crack_top_x_mm": res.get("crack_top_x_mm"),
            "overrides": list(user),
        }
        records.append(record)
        panels.append((algorithm, record, mesh, cracked))
    if comm.rank == 0:
        echo(comm, _table(records))
        if args.picture is not None:
            draw_paths(panels, args.picture, title=", ".join(user) or "today's criterion")
            echo(comm, f"picture: {args.picture}")
        if args.json is not None:
            write_json(args.json, {"bench": "mesh-dependence", "records": records, "rates": {}})
    return records


def _table(records: list[dict[str, Any]]) -> str:
    """The records as a Markdown table."""
    lines = [
        "| mesher | nodes | h (mm) | events | every cracked edge until the crack enters the "
        "pad zone: largest distance from the axis (mm) | / h | main crack: largest distance "
        "(mm) | below the pad zone (mm) | reaches the top at x (mm), event |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for r in records:
        dev = r["deviation"]
        top = (
            f"{dev['face_x']:+.1f}, {dev['reached_event']}"
            if dev["reached_event"] is not None
            else "not reached"
        )
        stop = r["pad_zone_event"]
        lines.append(
            f"| {r['case']} | {r['nodes']} | {r['h']:.2f} | {r['events']} | "
            f"{r['every_edge_to_pad']:.2f} ({'event ' + str(stop) if stop else 'never'}) | "
            f"{r['every_edge_to_pad_over_h']:.2f} | "
            f"{r['distance']:.1f} at ({dev['x']:.1f}, {dev['y']:.1f}) | "
            f"{r['distance_below_pad']:.1f} | {top} |"
        )
    return "\n".join(lines)


def draw_paths(
    panels: list[tuple[str, dict[str, Any], Any, np.ndarray]], path: Path, *, title: str
) -> None:
    """The cracked edges of each run side by side, around the axis, over the faint mesh.

    Args:
        panels: per mesher (name, record, :class:`~geofrac.fracture.topology.EdgeMesh`,
            cracked mask shape=(num_edges,)).
        path: the PNG to write.
        title: what ran (the overrides).
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.collections import LineCollection

    from geofrac.fracture.output import MODE_COLOURS

    fig, axes = plt.subplots(1, len(panels), figsize=(2.6 * len(panels) + 0.4, 4.3), sharey=True)
    axes = np.atleast_1d(axes)
    for ax, (name, record, mesh, cracked) in zip(axes, panels, strict=True):
        seg = mesh.coords[mesh.edges]
        mid = seg.mean(axis=1)
        near = np.abs(mid[:, 0]) < WINDOW + 5.0
        ax.add_collection(
            LineCollection(seg[near], colors="0.9", linewidths=0.3, antialiaseds=False)
        )
        ax.add_collection(
            LineCollection(seg[near & mesh.boundary_edges], colors="k", linewidths=0.6)
        )
        ax.axvline(0.0, color="0.4", lw=0.5, ls="--")
        ax.add_collection(LineCollection(seg[cracked], colors=MODE_COLOURS[0], linewidths=1.2))
        ax.set_xlim(-WINDOW, WINDOW)
        ax.set_ylim(-2.0, mesh.coords[:, 1].max() + 2.0)
        ax.set_aspect("equal")
        ax.set_xlabel("x (mm)")
        ax.set_title(
            f"{name}\n{record['nodes']} nodes, h = {record['h']:.2f} mm\n"
            f"max |x| = {record['distance']:.1f} mm ({record['distance_over_h']:.1f} h)",
            fontsize=8,
        )
        ax.tick_params(labelsize=7)
    axes[0].set_ylabel("y (mm)")
    fig.suptitle(f"symmetric notched beam, crack paths by mesher ({title})", fontsize=9)
    fig.tight_layout(rect=(0.0, 0.0, 1.0, 0.95))
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    plt.close(fig)
