"""Render docs/img/efmm_grains.png: EFMM integration domains (grains) of the Edo (2016) cantilever.

Run from the repository root after
``geofrac run jobs/cantilever_efmm.toml --set geometry.parameters.nx=16 --set
geometry.parameters.ny=4 --set discretization.q_rand=Q --set output.dir=results/grains_Q``
for Q = 0.0 and 0.5: two panels coloured by each grain's mean σx.
"""

from pathlib import Path

import pyvista as pv

pv.OFF_SCREEN = True
plotter = pv.Plotter(shape=(2, 1), window_size=(1200, 700))
for row, q in enumerate(("0.0", "0.5")):
    grid = pv.read(Path(f"results/grains_{q}/grains.vtu"))
    grid.cell_data["sigma_x"] = grid.cell_data["stress"][:, 0]
    plotter.subplot(row, 0)
    plotter.add_mesh(grid, scalars="sigma_x", show_edges=True, cmap="coolwarm")
    plotter.add_text(f"q_rand = {q}: grains coloured by mean sigma_x", font_size=10)
    plotter.view_xy()
    plotter.camera.zoom(2.2)
plotter.screenshot("docs/img/efmm_grains.png")
