"""Draw a 3D DFN run's fractures: coloured by set and by contact state (pyvista off-screen).

    python docs/dfn3d_pictures.py RUN_DIR --out docs/img/dfn3d_NAME.png [--view iso|side]

RUN_DIR is the output directory of a ``dfn3d`` scene with joints (``fracture_faces.vtu``:
one triangle per joint face with its ``set`` and ``state``; ``summary.json``: the scene's
name, box, ``[units]``, the joint groups and the last load step). The picture has two
panels side by side: the fractures coloured by set (the joint tables' names, in
``results.plasticity.joints.groups``; a scene with one joint table on ``fractures`` has a
single colour) and by contact state (closed, slip, open: each face the most frequent
state of its pairs, ``fracture_faces.vtu``), each with a legend that counts the faces,
the box as a faint outline and axes in the scene's length unit. The title names the scene
and the load state (the last converged load factor, the steps, the pairs slipping and
open).
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path
from typing import Any

import numpy as np
import pyvista as pv

#: Colours of the sets (matplotlib's tab10, in the joint tables' order).
SET_COLOURS = (
    "#1f77b4",
    "#ff7f0e",
    "#2ca02c",
    "#d62728",
    "#9467bd",
    "#8c564b",
    "#e377c2",
    "#7f7f7f",
    "#bcbd22",
    "#17becf",
)
#: The contact states of ``fracture_faces.vtu`` (0, 1, 2): name and colour.
STATES = (("closed (stick)", "#b0b0b0"), ("slip", "#d62728"), ("open", "#1f77b4"))
#: Camera directions (from the focal point towards the camera) and view-up vectors.
VIEWS = {
    "iso": ((1.0, -1.6, 1.0), (0.0, 0.0, 1.0)),  # from the +x, -y side: x = xmax in view
    "side": ((0.35, -1.6, 0.5), (0.0, 0.0, 1.0)),  # nearly along +y: x to the right, z up
}


def _label(text: str, unit: str) -> str:
    return f"{text} ({unit})" if unit else text


def _summary(run: Path) -> dict[str, Any]:
    summary: dict[str, Any] = json.loads((run / "summary.json").read_text())
    return summary


def load_state(summary: dict[str, Any]) -> str:
    """The load state for the title: the last converged factor, steps, pairs slipping/open."""
    plastic = summary["results"].get("plasticity", {})
    steps = [s for s in plastic.get("steps", []) if s.get("accepted")]
    factor = plastic.get("factor", steps[-1]["factor"] if steps else 0.0)
    text = f"load factor {factor:.3g} after {len(steps)} steps"
    if not plastic.get("converged", False):
        text += f" (NOT converged: {plastic.get('end_reason', '?')})"
    joints = plastic.get("joints")
    if joints:
        text += (
            f"; {joints['pairs']:,} joint node pairs, {joints['slipping']:,} slipping, "
            f"{joints['open']:,} opened"
        )
    return text


def _ticks(length: float) -> int:
    """Labels on an axis of this length: every 5 units when that makes 3 to 6, else 3."""
    steps = length / 5.0
    return round(steps) + 1 if abs(steps - round(steps)) < 1e-9 and 2 <= steps <= 5 else 3


def _frame(plotter: pv.Plotter, box: np.ndarray, unit: str, view: str) -> None:
    """The faint box outline, a ruler in metres along three edges (off the box), the camera.

    Rulers rather than VTK's cube axes: those drop the labels where two axes meet a
    corner (the last x label, the first y label), these keep every one.
    """
    lo, hi = box[:3], box[3:]
    bounds = (lo[0], hi[0], lo[1], hi[1], lo[2], hi[2])
    plotter.add_mesh(pv.Box(bounds=bounds).outline(), color="#808080", line_width=1, opacity=0.6)
    off = 0.05 * float(np.linalg.norm(hi - lo))  # the rulers stand off the box's edges
    mid = 0.5 * (lo + hi)
    rulers = (  # (start, end, axis, where its title goes: beyond the labels)
        ((lo[0], lo[1] - off, lo[2]), (hi[0], lo[1] - off, lo[2]), "x",
         (mid[0], lo[1] - 3.0 * off, lo[2] - off)),
        ((hi[0] + off, lo[1], lo[2]), (hi[0] + off, hi[1], lo[2]), "y",
         (hi[0] + 3.0 * off, mid[1], lo[2] - off)),
        ((lo[0] - off, lo[1] - off, lo[2]), (lo[0] - off, lo[1] - off, hi[2]), "z",
         (lo[0] - 3.0 * off, lo[1] - 3.0 * off, mid[2])),
    )  # fmt: skip
    for start, end, axis, title in rulers:
        length = float(np.linalg.norm(np.subtract(end, start)))
        plotter.add_ruler(
            start,
            end,
            title=" ",  # the title is a label of its own below: VTK's sits on a tick label
            number_labels=_ticks(length),
            label_format="%.3g",
            font_size_factor=0.8,
            label_size_factor=0.9,
            tick_length=6,
            label_color="black",
            tick_color="black",
        )
        plotter.add_point_labels(
            [title],
            [_label(axis, unit)],
            show_points=False,
            shape=None,
            font_size=18,
            text_color="black",
            justification_horizontal="center",
            justification_vertical="center",
            always_visible=True,
        )
    direction, up = VIEWS[view]
    centre = 0.5 * (lo + hi)
    extent = float(np.linalg.norm(hi - lo))
    d = np.asarray(direction) / np.linalg.norm(direction)
    plotter.camera_position = [tuple(centre + 2.2 * extent * d), tuple(centre), up]
    reach = 3.0 * off  # the box with its rulers and their titles in view
    plotter.reset_camera(
        bounds=(lo[0] - reach, hi[0] + reach, lo[1] - reach, hi[1], lo[2] - off, hi[2])
    )
    plotter.camera.zoom(1.1)


def _panel(
    faces: pv.UnstructuredGrid,
    layers: list[tuple[np.ndarray, str, float]],
    box: np.ndarray,
    unit: str,
    view: str,
    size: tuple[int, int],
) -> np.ndarray:
    """One rendered panel: each (cells, colour, opacity) layer of ``faces``, the box, axes."""
    plotter = pv.Plotter(off_screen=True, window_size=size)
    plotter.set_background("white")
    for cells, colour, opacity in layers:
        if cells.size:
            plotter.add_mesh(
                faces.extract_cells(cells),
                color=colour,
                opacity=opacity,
                ambient=0.45,  # lit from any side: a face seen from behind keeps its colour
                diffuse=0.6,
                specular=0.0,
            )
    _frame(plotter, box, unit, view)
    image: np.ndarray = plotter.screenshot(return_img=True)
    plotter.close()
    return image


def render(run: Path, out: Path, *, view: str = "iso", size: tuple[int, int] = (900, 820)) -> None:
    """Write the two-panel picture of ``run`` to ``out``."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.patches import Patch

    pv.OFF_SCREEN = True
    summary = _summary(run)
    scene = summary["scene"]
    unit = scene["input"].get("units", {}).get("length", "")
    box = np.asarray(scene["input"]["dfn3d"]["box"], dtype=float)
    groups = summary["results"]["plasticity"]["joints"]["groups"]
    faces = pv.read(run / "fracture_faces.vtu")
    set_index = np.asarray(faces.cell_data["set"])
    state = np.asarray(faces.cell_data["state"])

    by_set, set_entries = [], []
    for k, group in enumerate(groups):
        cells = np.flatnonzero(set_index == k)
        colour = SET_COLOURS[k % len(SET_COLOURS)]
        by_set.append((cells, colour, 0.8))
        set_entries.append(Patch(color=colour, label=f"{group}: {cells.size:,} faces"))
    by_state, state_entries = [], []
    for k, (label, colour) in enumerate(STATES):
        cells = np.flatnonzero(state == k)
        by_state.append((cells, colour, 0.4 if k == 0 else 0.95))  # closed dimmed
        state_entries.append(Patch(color=colour, label=f"{label}: {cells.size:,} faces"))

    panels = [
        (_panel(faces, by_set, box, unit, view, size), "fractures by set", set_entries),
        (
            _panel(faces, by_state, box, unit, view, size),
            "contact state (of each face: its node pairs' most frequent)",
            state_entries,
        ),
    ]
    panels = _trimmed(panels)
    height, width = panels[0][0].shape[:2]
    dpi = 100
    fig, axes = plt.subplots(
        1, 2, figsize=(2 * width / dpi, (height + 110) / dpi), dpi=dpi, layout="constrained"
    )
    for ax, (image, title, entries) in zip(axes, panels, strict=True):
        ax.imshow(image)
        ax.set_axis_off()
        ax.set_title(title, fontsize=14)
        ax.legend(
            handles=entries,
            loc="upper center",
            bbox_to_anchor=(0.5, 0.0),  # below the picture: nothing drawn is covered
            ncol=len(entries),
            fontsize=12,
            frameon=False,
        )
    fig.suptitle(f"{scene['name']}: {load_state(summary)}", fontsize=15)
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out, dpi=dpi, facecolor="white")
    plt.close(fig)


def _trimmed(panels: list[tuple[np.ndarray, str, list[Any]]]) -> list[Any]:
    """The panels cropped alike to what is drawn on them, with a margin of 12 pixels."""
    drawn = np.zeros(panels[0][0].shape[:2], dtype=bool)
    for image, _, _ in panels:
        drawn |= np.any(image[:, :, :3] < 250, axis=2)
    rows, cols = np.flatnonzero(drawn.any(axis=1)), np.flatnonzero(drawn.any(axis=0))
    if rows.size == 0:
        return panels
    margin = 12
    r0, r1 = max(rows[0] - margin, 0), min(rows[-1] + margin + 1, drawn.shape[0])
    c0, c1 = max(cols[0] - margin, 0), min(cols[-1] + margin + 1, drawn.shape[1])
    return [(image[r0:r1, c0:c1], title, entries) for image, title, entries in panels]


def main(argv: list[str] | None = None) -> None:
    """``RUN_DIR --out PNG [--view iso|side]``."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("run", type=Path, help="the output directory of a dfn3d run")
    parser.add_argument("--out", type=Path, required=True, help="the PNG to write")
    parser.add_argument("--view", choices=sorted(VIEWS), default="iso", help="camera (iso)")
    args = parser.parse_args(argv)
    render(args.run, args.out, view=args.view)
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
