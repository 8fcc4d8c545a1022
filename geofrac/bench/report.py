"""Benchmark reporting shared by all benches: convergence rates, tables, plots.

Pure numpy and matplotlib (Agg); no MPI. Call from rank 0.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

__all__ = ["fit_rate", "format_table", "plot_accuracy_cost", "save_figure", "save_report"]


def fit_rate(nodes: Sequence[float], errors: Sequence[float], dim: int = 2) -> float:
    """Convergence rate R: minus the least-squares slope of log(error) against log(nodes^(1/dim)).

    In 2D this is the rate of Edo (2016), Figs. 2.8 and 3.10 (R = 2 for CST in the L2 norm), i.e.
    the order in the mesh size h ∝ 1/√nodes; in 3D h ∝ nodes^(-1/3).

    Args:
        nodes: node (vertex) counts, shape=(n,).
        errors: error norms, shape=(n,).
        dim: spatial dimension.
    """
    x = np.log(np.asarray(nodes, dtype=float)) / dim
    y = np.log(np.asarray(errors, dtype=float))
    if len(x) < 2:
        return float("nan")
    slope = np.polyfit(x, y, 1)[0]
    return float(-slope)


def format_table(records: Sequence[dict[str, Any]], columns: Sequence[tuple[str, str, str]]) -> str:
    """Fixed-width text table.

    Args:
        records: one dict per row.
        columns: (key, header, format spec) per column, e.g. ``("dofs", "DOFs", "d")``.
    """
    cells = [
        [format(r[k], f) if r.get(k) is not None else "-" for k, _, f in columns] for r in records
    ]
    heads = [h for _, h, _ in columns]
    widths = [max(len(h), *(len(row[i]) for row in cells)) for i, h in enumerate(heads)]
    lines = ["  ".join(h.rjust(w) for h, w in zip(heads, widths, strict=True))]
    lines.append("  ".join("-" * w for w in widths))
    lines += ["  ".join(c.rjust(w) for c, w in zip(row, widths, strict=True)) for row in cells]
    return "\n".join(lines)


def plot_accuracy_cost(
    records: Sequence[dict[str, Any]],
    path: Path,
    title: str,
    *,
    group: str = "element",
    time_key: str = "time_total_s",
    errors: Sequence[tuple[str, str]] = (
        ("error_u", "displacement L2"),
        ("error_energy", "energy"),
    ),
) -> None:
    """Two log-log panels, error vs wall time and error vs DOFs, one line per ``group``."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2, figsize=(11, 4.5), constrained_layout=True)
    names = list(dict.fromkeys(r[group] for r in records))
    styles = ["-o", "--s"]
    for color, name in zip(plt.rcParams["axes.prop_cycle"].by_key()["color"], names, strict=False):
        rows = sorted((r for r in records if r[group] == name), key=lambda r: r["dofs"])
        for (key, label), style in zip(errors, styles, strict=False):
            err = [r[key] for r in rows]
            axes[0].loglog(
                [r[time_key] for r in rows], err, style, color=color, label=f"{name}: {label}"
            )
            axes[1].loglog(
                [r["dofs"] for r in rows], err, style, color=color, label=f"{name}: {label}"
            )
    axes[0].set_xlabel("wall time, assemble + solve [s]")
    axes[1].set_xlabel("degrees of freedom")
    save_figure(fig, axes, path, title=title, ylabel="error norm")


def save_figure(fig: Figure, axes: Sequence[Axes], path: Path, *, title: str, ylabel: str) -> None:
    """Label, grid and legend every panel, set the title, write ``path`` and close.

    Each legend sits below its panel, so it hides no curve; the figure should use
    ``constrained_layout`` to make room for it.
    """
    import matplotlib.pyplot as plt

    for ax in axes:
        ax.set_ylabel(ylabel)
        ax.grid(True, which="both", alpha=0.3)
        handles, _ = ax.get_legend_handles_labels()
        ax.legend(
            fontsize=8,
            loc="upper center",
            bbox_to_anchor=(0.5, -0.14),
            ncol=2 if len(handles) > 3 else 1,
            frameon=False,
        )
    fig.suptitle(title)
    fig.savefig(path, dpi=120)
    plt.close(fig)


def save_report(report: dict[str, Any], path: Path, copy: Path | None = None) -> None:
    """Write a bench's JSON ``report`` to ``path`` (its folder is created) and to ``copy``.

    ``copy`` is the ``--json`` path of the command line, if given.
    """
    from geofrac.io.summary import write_json

    path.parent.mkdir(parents=True, exist_ok=True)
    write_json(path, report)
    if copy is not None:
        write_json(copy, report)
