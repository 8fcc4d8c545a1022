"""Render the pictures of docs/blocks.md from block runs (pyvista off-screen, matplotlib).

    python docs/render_blocks.py [--zoom Z] OUT.png RUN_DIR [RUN_DIR ...]

Each RUN_DIR is the output directory of a block scene (``blocks.vtu``). 2D runs are
drawn side by side with matplotlib; a 3D run is rendered with pyvista, each block shrunk
towards its centre so the blocks stand apart (the immobile block, ``kind`` 1, as a
translucent grey surface).
"""

from __future__ import annotations

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


def render_2d(out: Path, runs: list[Path]) -> None:
    """Rings of 2D block runs, coloured by area, one panel per run."""
    fig, axes = plt.subplots(1, len(runs), figsize=(4.2 * len(runs), 4.4), squeeze=False)
    for ax, run in zip(axes[0], runs, strict=True):
        grid = pv.read(run / "blocks.vtu")
        polys = PolyCollection(_polygons(grid), edgecolor="k", linewidth=0.4, cmap="viridis")
        polys.set_array(grid.cell_data["volume"])
        ax.add_collection(polys)
        ax.set_aspect("equal")
        ax.autoscale_view()
        ax.set_title(run.name, fontsize=10)
        ax.set_axis_off()
    fig.tight_layout()
    fig.savefig(out, dpi=130)


def render_3d(out: Path, run: Path, zoom: float = 1.0) -> None:
    """The blocks of a 3D run, shrunk, coloured by volume; the immobile block translucent."""
    pv.OFF_SCREEN = True
    grid = pv.read(run / "blocks.vtu")
    kind = np.asarray(grid.cell_data["kind"])
    plotter = pv.Plotter(off_screen=True, window_size=(1000, 750))
    moving = grid.extract_cells(np.flatnonzero(kind == 0))
    plotter.add_mesh(
        moving.shrink(0.8), scalars="volume", cmap="viridis", log_scale=True, show_scalar_bar=True
    )
    if np.any(kind == 1):
        immobile = grid.extract_cells(np.flatnonzero(kind == 1)).extract_surface()
        plotter.add_mesh(immobile, color="lightgrey", opacity=0.35)
    plotter.camera_position = "iso"
    if zoom > 1:  # close up on the moving blocks
        plotter.reset_camera(bounds=moving.bounds)
    plotter.camera.zoom(zoom)
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
