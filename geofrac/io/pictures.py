"""The run pictures: ``network.png`` (DFN), ``particles.png`` (MPM), ``section.png`` (blocks).

Pure numpy and matplotlib (Agg, through :class:`~matplotlib.figure.Figure`: no pyplot
state, so a picture can be built and checked without being written). Each function
returns the figure; :func:`save` writes and releases it. The callers draw on rank 0.

Every picture has labelled axes with the units of the scene's ``[units]`` (no unit where
the scene declares none: :meth:`geofrac.model.scene.Units.label`), a title naming the
scene, a legend where it shows more than one kind of thing and a colour bar with its unit.
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np

from geofrac.model.scene import Units

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.cm import ScalarMappable
    from matplotlib.figure import Figure

__all__ = [
    "network_figure",
    "new_figure",
    "particles_figure",
    "save",
    "section_figure",
    "section_polygons",
    "section_segments",
]

#: Longer side of a picture's axes (inches).
SIZE = 7.0


def new_figure(width: float, height: float) -> Figure:
    """An Agg figure of ``width`` x ``height`` inches with a constrained layout."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(width, height), layout="constrained")
    FigureCanvasAgg(fig)
    return fig


def save(fig: Figure, path: str | os.PathLike[str], dpi: int = 110) -> None:
    """Write ``fig`` to ``path`` and release it."""
    fig.savefig(path, dpi=dpi)
    fig.clear()


def _box(lo: np.ndarray, hi: np.ndarray, extra: float = 1.2) -> tuple[float, float]:
    """A figure size whose axes keep the aspect of the box ``lo``-``hi``.

    ``extra``: inches beside the axes (a colour bar, a legend); a wide box
    (:func:`_wide`) gets them below instead (its colour bar goes there).
    """
    span = np.maximum(hi - lo, 1e-300)
    aspect = float(np.clip(span[1] / span[0], 0.1, 2.0))
    if _wide(lo, hi):
        return SIZE + 1.0, max(SIZE * aspect, 1.2) + 1.2 + 0.6 * extra
    if aspect <= 1.0:
        return SIZE + extra, max(SIZE * aspect, 2.5) + 1.0
    return max(SIZE / aspect, 3.0) + extra, SIZE + 1.0


def _wide(lo: np.ndarray, hi: np.ndarray) -> bool:
    """Whether the box ``lo``-``hi`` is less than half as high as wide."""
    span = np.maximum(hi - lo, 1e-300)
    return bool(span[1] < 0.5 * span[0])


def _colour_bar(fig: Figure, art: ScalarMappable, ax: Axes, label: str, wide: bool) -> None:
    """A colour bar beside ``ax``, or below it when the picture is ``wide``."""
    fig.colorbar(art, ax=ax, label=label, location="bottom" if wide else "right",
                 shrink=0.6 if wide else 1.0, aspect=40 if wide else 20)  # fmt: skip


def _axes_labels(ax: Axes, units: Units, names: tuple[str, str] = ("x", "y")) -> None:
    ax.set_xlabel(units.label(names[0], "length"))
    ax.set_ylabel(units.label(names[1], "length"))
    ax.set_aspect("equal")


def network_figure(
    *,
    domain: np.ndarray,
    fractures: np.ndarray,
    sets: np.ndarray,
    set_names: Sequence[str],
    mesh_edges: np.ndarray | None,
    regions: np.ndarray | None = None,
    title: str,
    units: Units,
) -> Figure:
    """The fractures coloured by set over the domain, the mesh's edges faint.

    Args:
        domain: the domain polygon, shape=(num_corners, 2).
        fractures: the fracture edges, shape=(num_edges, 2, 2).
        sets: each edge's set (0-based), shape=(num_edges,).
        set_names: the sets' names.
        mesh_edges: the mesh's edges, shape=(num_mesh_edges, 2, 2), or None.
        regions: the outlines of the scene's regions (openings, stages),
            shape=(num_segments, 2, 2), or None.
        title: the picture's title (it names the scene).
        units: the scene's units.
    """
    from matplotlib.collections import LineCollection

    lo, hi = domain.min(axis=0), domain.max(axis=0)
    fig = new_figure(*_box(lo, hi, extra=2.2))
    ax = fig.subplots()
    if mesh_edges is not None and len(mesh_edges):
        ax.add_collection(LineCollection(mesh_edges, colors="0.6", linewidths=0.2, alpha=0.5))
    ring = np.vstack([domain, domain[:1]])
    ax.plot(ring[:, 0], ring[:, 1], color="k", lw=1.0, label="domain")
    if regions is not None and len(regions):
        ax.add_collection(LineCollection(regions, colors="k", linewidths=1.4, linestyles="--",
                                         label="region outlines"))  # fmt: skip
    colours = _set_colours(len(set_names))
    for k, name in enumerate(set_names):
        mine = fractures[sets == k]
        if len(mine):
            ax.add_collection(
                LineCollection(mine, colors=colours[k], linewidths=1.2, label=_set_label(name))
            )
    if mesh_edges is not None and len(mesh_edges):
        ax.plot([], [], color="0.6", lw=0.5, label=f"mesh ({len(mesh_edges)} edges)")
    pad = 0.02 * float(np.max(hi - lo))
    ax.set_xlim(lo[0] - pad, hi[0] + pad)
    ax.set_ylim(lo[1] - pad, hi[1] + pad)
    _axes_labels(ax, units)
    ax.set_title(title, fontsize=10)
    fig.legend(*ax.get_legend_handles_labels(), loc="outside right upper", fontsize=8)
    return fig


def _set_label(name: str) -> str:
    """``"set J1"`` for a set named J1; a name that already says set stays as it is."""
    return name if name.lower().startswith("set") else f"set {name}"


def _set_colours(n: int) -> list[tuple[float, ...]]:
    from matplotlib import colormaps

    cmap = colormaps["tab10" if n <= 10 else "tab20"]
    return [tuple(cmap(k % cmap.N)) for k in range(n)]


def particles_figure(
    *,
    x0: np.ndarray,
    x: np.ndarray,
    cell: float,
    title: str,
    units: Units,
) -> Figure:
    """The particles at the end coloured by |displacement|, the initial outline over them.

    3D particles are drawn in the x-z plane (the last coordinate up); 1D particles on
    two rows, the initial positions (grey, their extent dashed) above the final ones.

    Args:
        x0: initial positions, shape=(n, dim).
        x: final positions, shape=(n, dim).
        cell: the grid's cell size: the initial outline is traced on cells of this size.
        title: the picture's title (it names the scene).
        units: the scene's units.
    """
    if x.shape[1] == 1:
        return _particles_1d(x0[:, 0], x[:, 0], title=title, units=units)
    up = x.shape[1] - 1
    a0, a = x0[:, [0, up]], x[:, [0, up]]
    u = np.linalg.norm(x - x0, axis=1)
    both = np.vstack([a0, a])
    lo, hi = both.min(axis=0) - cell, both.max(axis=0) + cell
    fig = new_figure(*_box(lo, hi, extra=1.8))
    ax = fig.subplots()
    spacing = _spacing(a0, cell)
    # a marker about one particle spacing wide (in points), so the body reads as filled
    width_in = fig.get_size_inches()[0] - (1.0 if _wide(lo, hi) else 1.8)
    size = (72.0 * width_in * spacing / float(np.max(hi - lo))) ** 2
    art = ax.scatter(a[:, 0], a[:, 1], c=u, s=float(np.clip(size, 0.05, 30.0)), cmap="viridis",
                     linewidths=0, rasterized=True)  # fmt: skip
    _outline(ax, a0, spacing)
    label = units.label("displacement magnitude |u|", "length")
    _colour_bar(fig, art, ax, label, _wide(lo, hi))
    ax.set_xlim(lo[0], hi[0])
    ax.set_ylim(lo[1], hi[1])
    _axes_labels(ax, units, ("x", "z" if up == 2 else "y"))
    ax.set_title(title, fontsize=10)
    ax.legend(loc="upper right", fontsize=8)
    return fig


def _spacing(points: np.ndarray, cell: float) -> float:
    """The median distance of a particle to its nearest neighbour (``cell`` for one)."""
    if len(points) < 2:
        return cell
    from scipy.spatial import cKDTree

    distance, _ = cKDTree(points).query(points, k=2)
    return float(np.median(distance[:, 1])) or cell


def _particles_1d(x0: np.ndarray, x: np.ndarray, *, title: str, units: Units) -> Figure:
    """:func:`particles_figure` of a 1D run: initial and final rows, coloured by |u|."""
    fig = new_figure(SIZE + 1.8, 2.6)
    ax = fig.subplots()
    h = float(np.ptp(x0)) / max(len(x0) - 1, 1)  # the particle spacing
    ax.plot([x0.min() - 0.5 * h, x0.max() + 0.5 * h], [1.0, 1.0], "k--", lw=0.9,
            label="initial outline")  # fmt: skip
    ax.scatter(x0, np.ones_like(x0), s=6, color="0.6", label="initial positions")
    art = ax.scatter(x, np.zeros_like(x), c=np.abs(x - x0), s=10, cmap="viridis")
    fig.colorbar(art, ax=ax, label=units.label("displacement magnitude |u|", "length"))
    ax.set_yticks([0.0, 1.0], ["final", "initial"])
    ax.set_ylim(-0.6, 1.6)
    ax.set_xlabel(units.label("x", "length"))
    ax.set_title(title, fontsize=10)
    ax.legend(loc="upper right", fontsize=8, ncol=2)
    return fig


def _outline(ax: Axes, points: np.ndarray, spacing: float) -> None:
    """The outline of the body ``points`` fill, dashed.

    The particles are binned on squares of side ``spacing``; gaps of one square between
    particles (an irregular seeding) are closed and holes filled, so that the outline is
    the body's, not its particles'.
    """
    from scipy import ndimage

    lo = points.min(axis=0) - 2.5 * spacing  # empty squares around the body
    n = np.floor((points.max(axis=0) - lo) / spacing).astype(int) + 3
    counts, ex, ey = np.histogram2d(
        points[:, 0], points[:, 1], bins=tuple(n.tolist()),
        range=((lo[0], lo[0] + n[0] * spacing), (lo[1], lo[1] + n[1] * spacing)),
    )  # fmt: skip
    body = ndimage.binary_fill_holes(ndimage.binary_closing(counts > 0, np.ones((3, 3))))
    cx, cy = 0.5 * (ex[1:] + ex[:-1]), 0.5 * (ey[1:] + ey[:-1])
    ax.contour(cx, cy, body.T.astype(float), levels=[0.5], colors="k",
               linewidths=0.9, linestyles="--")  # fmt: skip
    ax.plot([], [], color="k", lw=0.9, ls="--", label="initial outline")


def section_polygons(
    points: np.ndarray,
    pieces: np.ndarray,
    *,
    axis: int,
    at: float,
) -> tuple[list[np.ndarray], np.ndarray]:
    """The cut of convex hexahedra by the plane ``x[axis] = at``.

    Args:
        points: coordinates, shape=(num_points, 3).
        pieces: convex hexahedra in VTK order (bottom quad, top quad), shape=(n, 8).
        axis: the plane's normal axis.
        at: the plane's coordinate.

    Returns:
        ``(polygons, which)``: each cut polygon in the plane's other two coordinates
        (in axis order), shape=(k, 2) with 3 <= k <= 6, and the piece it cuts,
        shape=(num_polygons,).
    """
    edges = np.array(
        [[0, 1], [1, 2], [2, 3], [3, 0], [4, 5], [5, 6], [6, 7], [7, 4],
         [0, 4], [1, 5], [2, 6], [3, 7]]
    )  # fmt: skip
    h = points[:, axis] - at
    which = np.flatnonzero(_crossed(h, pieces))
    hp = h[pieces[which]]
    if not len(which):
        return [], which
    keep = [k for k in range(3) if k != axis]
    p = points[pieces[which]][:, :, keep]  # (m, 8, 2)
    a, b = hp[:, edges[:, 0]], hp[:, edges[:, 1]]  # (m, 12)
    crosses = (a < 0.0) != (b < 0.0)
    t = np.where(crosses, a / np.where(crosses, a - b, 1.0), np.nan)
    pa, pb = p[:, edges[:, 0]], p[:, edges[:, 1]]  # (m, 12, 2)
    q = pa + t[:, :, None] * (pb - pa)
    centre = np.nanmean(q, axis=1)
    angle = np.arctan2(q[:, :, 1] - centre[:, 1:2], q[:, :, 0] - centre[:, 0:1])
    order = np.argsort(np.where(crosses, angle, np.inf), axis=1)
    q = np.take_along_axis(q, order[:, :, None], axis=1)
    counts = crosses.sum(axis=1)
    return [q[i, : counts[i]] for i in range(len(which))], which


def _crossed(h: np.ndarray, cells: np.ndarray) -> np.ndarray:
    """Whether each row of ``cells`` has points on both sides (h < 0 and h >= 0).

    Column by column: a reduction along a short row axis is slow on millions of rows.
    """
    below = np.zeros(len(cells), dtype=np.int8)
    for k in range(cells.shape[1]):
        below += h[cells[:, k]] < 0.0
    return (below > 0) & (below < cells.shape[1])


def section_segments(
    points: np.ndarray,
    faces: np.ndarray,
    *,
    axis: int,
    at: float,
) -> np.ndarray:
    """The cut of planar quadrilateral faces by the plane ``x[axis] = at``: the blocks' outlines.

    Args:
        points: coordinates, shape=(num_points, 3).
        faces: quadrilaterals' point indices, shape=(num_faces, 4).
        axis: the plane's normal axis.
        at: the plane's coordinate.

    Returns:
        One segment per face the plane crosses twice, in the plane's other two
        coordinates, shape=(num_segments, 2, 2).
    """
    h = points[:, axis] - at
    f = faces[_crossed(h, faces)]
    if not len(f):
        return np.zeros((0, 2, 2))
    keep = [k for k in range(3) if k != axis]
    a = h[f]
    b = np.roll(a, -1, axis=1)
    crosses = (a < 0.0) != (b < 0.0)
    two = crosses.sum(axis=1) == 2
    t = np.where(crosses, a / np.where(crosses, a - b, 1.0), 0.0)
    pa = points[f][:, :, keep]
    q = pa + t[:, :, None] * (np.roll(pa, -1, axis=1) - pa)
    order = np.argsort(~crosses, axis=1, kind="stable")[:, :2]  # the two crossing edges
    return np.take_along_axis(q, order[:, :, None], axis=1)[two]


def section_figure(
    *,
    polygons: Sequence[np.ndarray],
    values: np.ndarray,
    background: Sequence[np.ndarray] = (),
    background_lines: np.ndarray | None = None,
    outlines: np.ndarray | None = None,
    axes_names: tuple[str, str],
    quantity: str,
    title: str,
    units: Units,
) -> Figure:
    """Block polygons coloured by their blocks' volume; ``background`` (immobile) grey.

    Args:
        polygons: the moving blocks' polygons (2D blocks, or their cut by a plane),
            each shape=(k, 2).
        values: the volume (area in 2D) of each polygon's block, shape=(num_polygons,).
        background: the immobile blocks' polygons, drawn grey.
        background_lines: the immobile blocks' outlines, shape=(n, 2, 2), drawn grey
            (a non-convex block's cut, for which no polygon is at hand).
        outlines: the blocks' outlines, shape=(n, 2, 2), drawn black (None: each
            polygon's own edges are the outlines).
        axes_names: the names of the picture's axes, e.g. ``("x", "z")``.
        quantity: ``"volume"`` (3D blocks) or ``"area"`` (2D): what ``values`` are.
        title: the picture's title (it names the scene and the plane).
        units: the scene's units.
    """
    from matplotlib.collections import PolyCollection
    from matplotlib.colors import LogNorm, Normalize

    every = list(polygons) or [
        *background,
        *(background_lines if background_lines is not None else []),
    ]
    if every:  # the moving blocks fill the picture; the immobile part is the frame
        pts = np.vstack(every)
        lo, hi = pts.min(axis=0), pts.max(axis=0)
    else:
        lo, hi = np.zeros(2), np.ones(2)
    fig = new_figure(*_box(lo, hi, extra=1.8))
    ax = fig.subplots()
    if len(background):
        ax.add_collection(PolyCollection(list(background), facecolors="0.85", edgecolors="0.6",
                                         linewidths=0.3, label="immobile block"))  # fmt: skip
    elif background_lines is not None and len(background_lines):
        from matplotlib.collections import LineCollection

        ax.add_collection(LineCollection(background_lines, colors="0.5", linewidths=1.2,
                                         label="immobile block's outline"))  # fmt: skip
    immobile = len(background) > 0 or (background_lines is not None and len(background_lines) > 0)
    if len(polygons):
        v = np.asarray(values, dtype=float)
        vmin, vmax = float(v.min()), float(v.max())
        log = vmin > 0 and vmax > 20.0 * vmin
        norm = LogNorm(vmin, vmax) if log else Normalize(vmin, vmax)
        polys = PolyCollection(list(polygons), array=v, cmap="viridis", norm=norm,
                               edgecolors="face" if outlines is not None else "k",
                               linewidths=0.15)  # fmt: skip
        ax.add_collection(polys)
        name = "block volume" if quantity == "volume" else "block area"
        label = units.label(name + (", log scale" if log else ""), quantity)
        _colour_bar(fig, polys, ax, label, _wide(lo, hi))
    if outlines is not None and len(outlines):
        from matplotlib.collections import LineCollection

        ax.add_collection(LineCollection(outlines, colors="k", linewidths=0.3))
    pad = 0.02 * float(np.max(hi - lo))
    ax.set_xlim(lo[0] - pad, hi[0] + pad)
    ax.set_ylim(lo[1] - pad, hi[1] + pad)
    _axes_labels(ax, units, axes_names)
    ax.set_title(title, fontsize=10)
    if immobile:
        ax.legend(loc="upper right", fontsize=8)
    return fig
