"""``geofrac bench dfn``: DFN generation and meshing cost for Models 1 and 2 of Edo (2016).

For each model scene (``jobs/dfn_model1.toml``, ``jobs/dfn_model2.toml``, Edo (2016), §2.5.1) and
each scale s (default 1 and 4: the thesis's mesh and one with 4× the elements, mesh sizes
divided by √s) the network is generated, cleaned and meshed by gmsh on rank 0 and
distributed by DOLFINx, and the cover check (every fracture is a chain of tagged
facets) runs. Each record has the wall times of the four phases, mesh counts and
quality, the network's intensity P21 and, per fracture set, a Kolmogorov–Smirnov test of
the lengths against the truncated power law (Edo (2016), eq. 2.28) and the orientation mean and
standard deviation against Table 2.1. Writes ``dfn.json`` and one picture per model
(``dfn_<model>.png``: the network coloured by set, and a close-up of the mesh).
"""

from __future__ import annotations

import argparse
import math
import time
from pathlib import Path
from typing import TYPE_CHECKING, Any

from geofrac.bench.args import name_list, number_list

if TYPE_CHECKING:
    from collections.abc import Sequence

    from mpi4py import MPI

    from geofrac.dfn.sampling import FractureSet, Network
    from geofrac.meshing.distribute import TaggedMesh
    from geofrac.model.scene import Units

__all__ = ["add_arguments", "network_statistics", "run"]

_JOBS = Path(__file__).resolve().parents[2] / "jobs"
MODELS = {"model1": _JOBS / "dfn_model1.toml", "model2": _JOBS / "dfn_model2.toml"}

COLUMNS = (
    ("model", "model", "s"),
    ("scale", "scale", "g"),
    ("fractures", "fractures", "d"),
    ("p21", "P21 [1/mm]", ".4f"),
    ("nodes", "nodes", "d"),
    ("cells", "triangles", "d"),
    ("fracture_facets", "fracture edges", "d"),
    ("time_generate_s", "generate [s]", ".3f"),
    ("time_clean_s", "clean [s]", ".3f"),
    ("time_mesh_s", "gmsh [s]", ".2f"),
    ("time_distribute_s", "distribute [s]", ".2f"),
    ("min_angle_deg", "min angle", ".2f"),
    ("min_junction_angle_deg", "min junction", ".2f"),
    ("shortest_edge", "shortest edge", ".3g"),
)


_models = name_list(tuple(MODELS), "model")
_scales = number_list(float, lambda v: math.isfinite(v) and v > 0, "finite positive")


def add_arguments(p: argparse.ArgumentParser) -> None:
    """Options of this bench."""
    p.add_argument(
        "--models",
        type=_models,
        default=list(MODELS),
        help=f"comma-separated models from {', '.join(MODELS)} (default: all)",
    )
    p.add_argument(
        "--scales",
        type=_scales,
        default=[1.0, 4.0],
        help="element-count multipliers of the scene's mesh (mesh sizes / sqrt(scale)) "
        "(default: 1,4)",
    )
    p.add_argument("--out", type=Path, default=Path("results/bench-dfn"), help="output directory")
    p.add_argument("--json", type=Path, help="also write the JSON report to this file")
    p.add_argument("--no-plot", action="store_true", help="skip the pictures")


def network_statistics(network: Network, sets: Sequence[FractureSet]) -> list[dict[str, Any]]:
    """Per set: count, KS test of the lengths, orientation mean and spread.

    Args:
        network: a :class:`~geofrac.dfn.sampling.Network`.
        sets: its :class:`~geofrac.dfn.sampling.FractureSet` definitions, in set order.

    Returns:
        One dict per set: ``set``, ``count``, ``ks_d``, ``ks_p`` (lengths against the
        truncated power law), ``mean_deg`` / ``std_deg`` (sample, axial) beside
        ``mean_expected_deg`` / ``std_expected_deg`` (normal sets).
    """
    import numpy as np

    from geofrac.dfn.sampling import power_law_cdf
    from geofrac.dfn.stats import ks_pvalue, ks_statistic, orientation_summary

    out = []
    for k, fset in enumerate(sets):
        mask = network.set_index == k
        lengths = network.lengths[mask]
        row: dict[str, Any] = {"set": fset.name, "count": int(mask.sum())}
        if len(lengths):

            def cdf(x: np.ndarray, s: FractureSet = fset) -> np.ndarray:
                return power_law_cdf(x, s.lmin, s.lmax, exponent=s.exponent)

            d = ks_statistic(lengths, cdf)
            row |= {"ks_d": d, "ks_p": ks_pvalue(d, len(lengths))}
        if len(lengths) > 1:
            summary = orientation_summary(network.angles_deg[mask])
            row |= {"mean_deg": summary["mean"], "std_deg": summary["std"]}
        row["mean_expected_deg"] = float(np.mod(fset.mean_deg, 180.0))
        if fset.distribution == "normal":
            row["std_expected_deg"] = fset.spread
        out.append(row)
    return out


def _case(comm: MPI.Comm, model: str, scale: float) -> tuple[dict[str, Any], Any, Units]:
    """Mesh one model at one scale; return (record, tagged mesh, the scene's units)."""
    from geofrac.effects.dfn import DfnConfig
    from geofrac.meshing.distribute import build_mesh, check_fracture_cover
    from geofrac.scene import load_scene_collective

    path = MODELS[model]
    base = load_scene_collective(comm, path, [])
    config = base.effect_config("dfn", DfnConfig)
    assert config is not None  # the model declares the dfn effect
    factor = scale**-0.5
    overrides = [
        f"dfn.mesh_size={config.mesh.size * factor!r}",
        f"dfn.fracture_mesh_size={config.mesh.fracture_size * factor!r}",
        f"dfn.tolerance={config.tolerance * factor!r}",
    ]
    scene = load_scene_collective(comm, path, overrides)
    config = scene.effect_config("dfn", DfnConfig)
    assert config is not None  # the model declares the dfn effect
    start = time.perf_counter()
    assert scene.geometry is not None  # the dfn effect's builder
    tagged = build_mesh(scene.geometry, comm)
    total = comm.allreduce(time.perf_counter() - start, op=_max())
    report = dict(tagged.report)
    report |= check_fracture_cover(tagged)
    record = {
        "model": model,
        "scale": scale,
        "scene": str(path),
        "mesh_size": config.mesh.size,
        "tolerance": config.tolerance,
        **{k: v for k, v in report.items() if k != "cleaning"},
        "cleaning": report["cleaning"],
        "time_distribute_s": total
        - report["time_generate_s"]
        - report["time_clean_s"]
        - report["time_mesh_s"],
        "time_total_s": total,
        "sets": network_statistics(tagged.fractures.network, config.sets),
    }
    return record, tagged, scene.units


def _max() -> Any:
    from mpi4py import MPI

    return MPI.MAX


def _plot(tagged: TaggedMesh, path: Path, title: str, units: Units) -> None:
    """The network coloured by set (left) and a close-up of the mesh around it (right).

    ``units``: the scene's, for the axes.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import numpy as np
    from matplotlib.collections import LineCollection

    clean = tagged.fractures
    net = clean.network
    colors = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    fig, axes = plt.subplots(1, 2, figsize=(13, 4.2), width_ratios=[2, 1], constrained_layout=True)
    domain = np.vstack([clean.domain, clean.domain[:1]])
    for i, ax in enumerate(axes):
        ax.plot(domain[:, 0], domain[:, 1], "k-", lw=0.8, label="domain" if i == 0 else None)
        ax.set_aspect("equal")
        ax.set_xlabel(units.label("x", "length"))
        ax.set_ylabel(units.label("y", "length"))
    for k, name in enumerate(net.set_names):
        mask = net.set_index[clean.edge_fracture] == k
        axes[0].add_collection(
            LineCollection(
                clean.segments[mask], colors=colors[k % len(colors)], lw=0.9, label=f"set {name}"
            )
        )
    axes[0].legend(loc="upper right", fontsize=8)
    axes[0].set_title(title, fontsize=10)
    mesh = tagged.mesh
    x = mesh.geometry.x[:, :2]
    cells = mesh.geometry.dofmap
    half = 6.0 * float(tagged.report.get("longest_edge", 1.0))
    degree = np.bincount(clean.edges.ravel(), minlength=len(clean.vertices))
    lo, hi = clean.domain.min(axis=0) + half, clean.domain.max(axis=0) - half
    degree[~np.all((clean.vertices > lo) & (clean.vertices < hi), axis=1)] = 0
    centre = clean.vertices[np.argmax(degree)]  # the busiest junction away from the sides
    near = np.all(np.abs(x[cells].mean(axis=1) - centre) < half, axis=1)
    tri = x[cells[near]]
    axes[1].add_collection(
        LineCollection(
            np.concatenate([tri, tri[:, :1]], axis=1), colors="0.6", lw=0.4, label="mesh edges"
        )
    )
    axes[1].add_collection(LineCollection(clean.segments, colors="C3", lw=1.6, label="fractures"))
    axes[1].legend(loc="lower right", fontsize=8, framealpha=0.9)
    axes[1].set_xlim(centre[0] - half, centre[0] + half)
    axes[1].set_ylim(centre[1] - half, centre[1] + half)
    axes[1].set_title("close-up: fractures are chains of element edges", fontsize=10)
    fig.savefig(path, dpi=90)
    plt.close(fig)


def run(args: argparse.Namespace, comm: MPI.Comm) -> None:
    """Mesh every model at every scale, print the table, write the JSON and pictures."""
    from geofrac.bench.report import format_table, save_report
    from geofrac.io.summary import versions
    from geofrac.log import echo

    if comm.rank == 0:
        args.out.mkdir(parents=True, exist_ok=True)
    records = []
    for model in args.models:
        for scale in args.scales:
            record, tagged, units = _case(comm, model, scale)
            records.append(record)
            echo(
                comm,
                f"{model} x{scale:g}: {record['fractures']} fractures, {record['nodes']} nodes, "
                f"{record['cells']} triangles; generate {record['time_generate_s']:.3f} s, "
                f"mesh {record['time_mesh_s']:.2f} s",
            )
            if scale == args.scales[0] and not args.no_plot and comm.size == 1:
                _plot(
                    tagged,
                    args.out / f"dfn_{model}.png",
                    f"{model}: {record['fractures']} fractures, P21 {record['p21']:.3f}"
                    + (f"/{units.length}" if units.length else ""),
                    units,
                )
    echo(comm, format_table(records, COLUMNS))
    nan = float("nan")
    for r in records:
        if r["scale"] != args.scales[0]:
            continue
        for s in r["sets"]:
            echo(
                comm,
                f"{r['model']} {s['set']}: {s['count']} fractures, lengths KS p = "
                f"{s.get('ks_p', nan):.3f}; orientation mean {s.get('mean_deg', nan):.2f}° "
                f"(expected {s['mean_expected_deg']:.2f}°), "
                f"std {s.get('std_deg', nan):.2f}° "
                f"(expected {s.get('std_expected_deg', nan):.2f}°)",
            )
    report = {"bench": "dfn", "ranks": comm.size, "versions": versions(), "records": records}
    if comm.rank == 0:
        save_report(report, args.out / "dfn.json", args.json)
    echo(comm, f"wrote {args.out / 'dfn.json'}")
