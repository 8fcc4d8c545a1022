"""Render the pictures of docs/blocks.md from block runs (pyvista off-screen, matplotlib).

    python docs/render_blocks.py [--zoom Z] OUT.png RUN_DIR [RUN_DIR ...]

Each RUN_DIR is the output directory of a block scene (``blocks.vtu``, ``summary.json``
for the scene's name and ``[units]``). 2D runs are drawn side by side with matplotlib; a
3D run is rendered with pyvista, each block shrunk towards its centre so the blocks stand
apart (the immobile block, ``kind`` 1, as a translucent grey surface), with axes around
the moving blocks.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np
import pyvista as pv
from matplotlib.collections import PolyCollection


def _polygons(grid: pv.UnstructuredGrid) -> list[np.ndarray]:
    offsets = grid.cell_offsets
    conn = grid.cell_connectivity
    pts = grid.points[:, :2]
    return [pts[conn[offsets[i] : offsets[i + 1]]] for i in range(grid.n_cells)]


def _scene(run: Path) -> tuple[str, str]:
    """The run's scene name and its declared length unit ("" when it declares none)."""
    scene = json.loads((run / "summary.json").read_text())["scene"]
    return scene["name"], scene["input"].get("units", {}).get("length", "")


def _label(text: str, unit: str) -> str:
    return f"{text} ({unit})" if unit else text


def render_2d(out: Path, runs: list[Path]) -> None:
    """2D block runs coloured by area, one panel per run, axes and a colour bar each."""
    fig, axes = plt.subplots(
        1, len(runs), figsize=(4.4 * len(runs), 4.6), squeeze=False, layout="constrained"
    )
    for ax, run in zip(axes[0], runs, strict=True):
        name, length = _scene(run)
        grid = pv.read(run / "blocks.vtu")
        polys = PolyCollection(_polygons(grid), edgecolor="k", linewidth=0.4, cmap="viridis")
        polys.set_array(grid.cell_data["volume"])
        ax.add_collection(polys)
        ax.set_aspect("equal")
        ax.autoscale_view()
        ax.set_title(f"{run.name} ({name})", fontsize=10)
        ax.set_xlabel(_label("x", length))
        ax.set_ylabel(_label("y", length))
        area = f"{length}²" if length else ""
        fig.colorbar(polys, ax=ax, orientation="horizontal", label=_label("block area", area))
    fig.savefig(out, dpi=130)


def render_3d(out: Path, run: Path, zoom: float = 1.0) -> None:
    """The blocks of a 3D run, shrunk, coloured by volume; the immobile block translucent.

    Axes with the scene's length unit frame the moving blocks; the colour bar names the
    volume and its unit; the title names the scene.
    """
    pv.OFF_SCREEN = True
    name, length = _scene(run)
    grid = pv.read(run / "blocks.vtu")
    kind = np.asarray(grid.cell_data["kind"])
    plotter = pv.Plotter(off_screen=True, window_size=(1100, 800))
    moving = grid.extract_cells(np.flatnonzero(kind == 0))
    volume = _label("block volume", f"{length}³" if length else "") + ", log scale"
    plotter.add_mesh(
        moving.shrink(0.8),
        scalars="volume",
        cmap="viridis",
        log_scale=True,
        scalar_bar_args={
            "title": volume,
            "vertical": True,
            "position_x": 0.86,
            "position_y": 0.2,
            "height": 0.6,
            "title_font_size": 14,
            "label_font_size": 12,
        },
    )
    if np.any(kind == 1):
        immobile = grid.extract_cells(np.flatnonzero(kind == 1)).extract_surface()
        plotter.add_mesh(immobile, color="lightgrey", opacity=0.35, label="immobile block")
    axes = plotter.show_bounds(
        bounds=moving.bounds,
        xtitle=_label("x", length),
        ytitle=_label("y", length),
        ztitle=_label("z", length),
        location="outer",
        show_xlabels=True,
        n_zlabels=4,
        n_xlabels=3,
        n_ylabels=3,
        font_size=12,
    )
    axes.SetCornerOffset(0.08)  # the axes stand off the box's corner: its labels stay apart
    plotter.add_text(f"{name}: {moving.n_cells:,} moving blocks, each shrunk to 80 %",
                     position="upper_left", font_size=10)  # fmt: skip
    plotter.camera_position = "iso"
    if zoom > 1:  # close up on the moving blocks
        plotter.reset_camera(bounds=moving.bounds)
    plotter.camera.zoom(0.85 * zoom)  # room for the title above the axes
    plotter.screenshot(str(out))


def main(argv: list[str]) -> None:
    """Render ``[--zoom Z] OUT.png RUN_DIR...``.

    2D runs side by side, or the first 3D run (``Z`` > 1: a close-up of its moving blocks).
    """
    zoom = 1.0
    if argv[0] == "--zoom":
        zoom, argv = float(argv[1]), argv[2:]
    out, runs = Path(argv[0]), [Path(a) for a in argv[1:]]
    dims = {pv.read(r / "blocks.vtu").celltypes[0] == pv.CellType.POLYGON for r in runs}
    if dims == {True}:
        render_2d(out, runs)
    else:
        render_3d(out, runs[0], zoom)
    print(f"wrote {out}")


if __name__ == "__main__":
    main(sys.argv[1:])
