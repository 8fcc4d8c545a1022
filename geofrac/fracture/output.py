"""What the event loop writes: ``events.csv``, the XDMF series, the pictures.

The loop talks to an :class:`OutputWriter`; :class:`EventOutput` is the one writer: the
event log streamed row by row, the series ``cracks.xdmf`` (crack sites) and
``damage.xdmf`` (cells), ``load_displacement.png`` and ``cracks.png``. What the series
and the crack picture show of the sites comes from a :class:`SiteDrawing`
(:class:`EdgeDrawing` for element edges; the grain variant draws interfaces, fills
fragment grains and adds the grain file through it). Files are written on rank 0.
The checkpoints are :mod:`geofrac.fracture.replay`'s.
"""

from __future__ import annotations

import csv
import os
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import IO, TYPE_CHECKING, Protocol

import numpy as np

from geofrac.fracture.contact import NO_PAIR, OPEN, SLIP, STATES, STICK
from geofrac.fracture.context import CrackContext, Sites
from geofrac.fracture.control import RELEASE, Control
from geofrac.fracture.units import SiteState
from geofrac.io.series import XdmfSeries
from geofrac.model.scene import Units as SceneUnits

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

__all__ = [
    "CHANGE_COLUMNS",
    "CONTACT_COLUMNS",
    "EVENT_COLUMNS",
    "SOFTENING_COLUMNS",
    "EdgeDrawing",
    "EventLog",
    "EventOutput",
    "FrameData",
    "OutputWriter",
    "Row",
    "SiteDrawing",
    "load_displacement_figure",
]

#: Columns of ``events.csv``.
EVENT_COLUMNS = (
    "event",
    "edge",
    "node_a",
    "node_b",
    "x",
    "y",
    "r",
    "load_factor",
    "control_displacement",
    "reaction",
    "strain_energy",
    "edges_cracked",
    "iterations",
    "mode",
)

#: Column of ``events.csv`` added with a fracture energy: the energy dissipated by the
#: cohesive faces' teeth up to and including the event (times the thickness).
SOFTENING_COLUMNS = ("dissipated_energy",)

#: Columns of ``events.csv`` added with crack-face contact: pairs per state, the most
#: negative gap of a closed pair at the event's load, state changes in the event.
CONTACT_COLUMNS = ("open", "stick", "slip", "min_gap", "contact_changes")

#: Columns of ``contact.csv``: each state change of a face pair.
CHANGE_COLUMNS = ("event", "edge", "x", "y", "from", "to", "gap", "slip")

#: Colours of new cracks in ``cracks.png`` by mode (tension, shear), of slipping faces.
MODE_COLOURS = ("tab:red", "tab:blue")
SLIP_COLOUR = "tab:orange"
#: Colour of open joints in ``cracks.png`` (with contact).
OPEN_COLOUR = "tab:purple"

#: One event's row of ``events.csv`` (keys :data:`EVENT_COLUMNS`).
Row = dict[str, int | float]

#: A frame of the series: (cracks.xdmf cell data, damage.xdmf point data, damage.xdmf
#: cell data), name -> values.
FrameData = tuple[dict[str, np.ndarray], dict[str, np.ndarray], dict[str, np.ndarray]]

#: Seconds between two ``fsync`` of the streamed event log (it is flushed every event).
FSYNC_S = 1.0


@dataclass
class EventLog:
    """``events.csv`` open for appending rows (rank 0).

    Each row is flushed to the operating system as its event completes, which a killed
    process (SIGKILL) cannot undo; ``fsync`` (against a crash of the machine) costs about
    0.3 ms on the development machine, up to 1 % of a small model's event, so it runs at
    most once per :data:`FSYNC_S` seconds, at checkpoints and on closing.
    """

    handle: IO[str]
    writer: csv.DictWriter[str]
    synced: float = field(default_factory=time.monotonic)

    def writerow(self, row: Row) -> None:
        """Append one event's row and flush it."""
        self.writer.writerow(row)
        self.handle.flush()
        if time.monotonic() - self.synced >= FSYNC_S:
            self.sync()

    def sync(self) -> None:
        """Flush and ``fsync`` the file."""
        self.handle.flush()
        os.fsync(self.handle.fileno())
        self.synced = time.monotonic()

    def close(self) -> None:
        """Sync and close."""
        try:
            self.sync()
        finally:
            self.handle.close()


class SiteDrawing(Protocol):
    """How the crack sites of a variant appear in the series and pictures."""

    def crack_geometry(self) -> tuple[np.ndarray, np.ndarray]:
        """(points, shape=(p, 2); line cells, shape=(c, 2)) of ``cracks.xdmf``."""
        ...

    def frame(self, disp: np.ndarray) -> FrameData:
        """The frame of the current state; ``disp`` per node, shape=(num_nodes, 2)."""
        ...

    def segments(self, sites: np.ndarray) -> np.ndarray:
        """Line segments drawing the sites selected by a mask, shape=(k, 2, 2)."""
        ...

    def draw_extra(self, ax: Axes) -> None:
        """Draw anything else into ``cracks.png`` below the cracks."""
        ...

    def write_extra(self, out_dir: Path) -> None:
        """Write the variant's own files of the final state (rank 0)."""
        ...


class EdgeDrawing:
    """Element edges: cracked edges as lines, damage and MLS cells per cell.

    Args:
        state: the edge crack state.
    """

    def __init__(self, state: SiteState) -> None:
        self.state = state

    def crack_geometry(self) -> tuple[np.ndarray, np.ndarray]:
        """The mesh nodes and edges."""
        return self.state.mesh.coords, self.state.mesh.edges

    def frame(self, disp: np.ndarray) -> FrameData:
        """``crack`` per edge; ``displacement``; ``damage`` (cracked edges / 3), ``mls``."""
        state = self.state
        crack = state.cracked.astype(float)
        dmg = crack[state.mesh.cell_edges].mean(axis=1)
        return (
            {"crack": crack},
            {"displacement": disp},
            {"damage": dmg, "mls": state.is_mls().astype(float)},
        )

    def segments(self, sites: np.ndarray) -> np.ndarray:
        """The selected edges, shape=(k, 2, 2)."""
        m = self.state.mesh
        return m.coords[m.edges[sites]]

    def draw_extra(self, ax: Axes) -> None:
        """Nothing."""

    def write_extra(self, out_dir: Path) -> None:
        """Nothing."""


class OutputWriter(Protocol):
    """What the event loop writes as it goes (every method collective-safe: rank 0 writes)."""

    def open(self, rows: list[Row], keep_until: float | None) -> None:
        """Start ``events.csv`` with ``rows`` and the series (continued up to ``keep_until``)."""
        ...

    def row(self, row: Row) -> None:
        """Append one event's row (flushed)."""
        ...

    def frame(
        self, event: int, u: np.ndarray, edge_data: dict[str, np.ndarray] | None = None
    ) -> None:
        """A frame of the series at ``event`` with the solution u, shape=(n_global,).

        ``edge_data``: more per-site fields of the crack series (mode, contact state).
        """
        ...

    def contact_changes(
        self, event: int, changes: list[tuple[int, int, int, float, float]]
    ) -> None:
        """Log the face pairs' state changes (edge, old, new, gap, slip) of an event."""
        ...

    def sync(self) -> None:
        """Put the event log on disk (before a checkpoint)."""
        ...

    def close(self) -> None:
        """Close the event log."""
        ...

    def finish(self, rows: list[Row], modes: np.ndarray, faces: np.ndarray | None) -> None:
        """The pictures and the variant's files of the final state.

        ``modes``: per site, 0 or 1 + the index of its crack mode in
        :data:`~geofrac.fracture.loop.MODES`; ``faces``: per site, its face pair's
        contact state (:data:`~geofrac.fracture.contact.NO_PAIR`, OPEN, STICK, SLIP),
        shape=(num_sites,), or None without crack-face contact.
        """
        ...


class EventOutput:
    """The crack driver's files in ``output.dir`` (rank 0; nothing when not ``write``).

    Args:
        ctx: the shared set-up data.
        state: the crack state.
        drawing: the variant's drawing of its sites.
        sites: the sites cracked before loading.
        write: write anything at all.
        contact: write the crack faces' contact (``cracking.contact``).
        softening: write the cohesive faces' dissipation (a fracture energy is given).
    """

    def __init__(
        self,
        ctx: CrackContext,
        state: SiteState,
        drawing: SiteDrawing,
        *,
        sites: Sites,
        write: bool,
        contact: bool,
        softening: bool,
    ) -> None:
        self.ctx, self.state, self.drawing, self.sites = ctx, state, drawing, sites
        self.on = write and ctx.comm.rank == 0
        self.out_dir = ctx.scene.output.dir
        self._log: EventLog | None = None
        self._series: tuple[XdmfSeries, XdmfSeries] | None = None
        self._changes: tuple[IO[str], csv.writer] | None = None  # type: ignore[valid-type]
        self._contact, self._softening = contact, softening

    def _open_series(
        self, name: str, coords: np.ndarray, cells: np.ndarray, keep: float | None
    ) -> XdmfSeries:
        series = XdmfSeries(self.out_dir / name, coords, cells, keep_until=keep)
        if series.note is not None:
            self.ctx.say(f"cracking: {series.note}")
        return series

    def open(self, rows: list[Row], keep_until: float | None) -> None:
        """The series (when ``output.xdmf``) and ``events.csv`` with ``rows`` written."""
        if not self.on:
            return
        gm = self.ctx.gm
        if self.ctx.scene.output.xdmf:
            points, lines = self.drawing.crack_geometry()
            self._series = (
                self._open_series("cracks.xdmf", points, lines, keep_until),
                self._open_series("damage.xdmf", gm.coords, gm.cells, keep_until),
            )
        handle = open(self.out_dir / "events.csv", "w", newline="")  # noqa: SIM115
        columns = (
            EVENT_COLUMNS
            + (SOFTENING_COLUMNS if self._softening else ())
            + (CONTACT_COLUMNS if self._contact else ())
        )
        writer = csv.DictWriter(handle, fieldnames=columns)
        writer.writeheader()
        writer.writerows(rows)
        handle.flush()
        self._log = EventLog(handle, writer)
        if self._contact:
            path = self.out_dir / "contact.csv"
            kept = _changes_until(path, keep_until) if keep_until is not None else []
            log = open(path, "w", newline="")  # noqa: SIM115
            changes = csv.writer(log)
            changes.writerow(CHANGE_COLUMNS)
            changes.writerows(kept)
            log.flush()
            self._changes = (log, changes)

    def contact_changes(
        self, event: int, changes: list[tuple[int, int, int, float, float]]
    ) -> None:
        """Append the state changes of ``event`` to ``contact.csv`` (flushed).

        ``changes``: (edge, old state, new state, gap, slip at the event's load).
        """
        if self._changes is None or not changes:
            return
        log, writer = self._changes
        m = self.state.mesh
        for e, old, new, g, sl in changes:
            x, y = m.coords[m.edges[e]].mean(axis=0)
            writer.writerow(
                [
                    event,
                    e,
                    f"{x:.6g}",
                    f"{y:.6g}",
                    STATES[old],
                    STATES[new],
                    f"{g:.6e}",
                    f"{sl:.6e}",
                ]
            )
        log.flush()

    def row(self, row: Row) -> None:
        """Append one event's row (flushed: a killed run keeps every completed event)."""
        if self._log is not None:
            self._log.writerow(row)

    def frame(
        self, event: int, u: np.ndarray, edge_data: dict[str, np.ndarray] | None = None
    ) -> None:
        """Write (or replace) the frame of ``event``."""
        if self._series is None:
            return
        ctx = self.ctx
        disp = u[(ctx.gm.node_block[:, None] * ctx.bs + np.arange(2))]
        crack_data, point_data, cell_data = self.drawing.frame(disp)
        n_lines = len(crack_data["crack"])
        for name, values in (edge_data or {}).items():
            if len(values) == n_lines:  # the series draws one line per site
                crack_data[name] = values
        cracks, damage = self._series
        cracks.write(float(event), cell_data=crack_data)
        damage.write(float(event), point_data=point_data, cell_data=cell_data)

    def sync(self) -> None:
        """``fsync`` the event log (and ``contact.csv``)."""
        if self._log is not None:
            self._log.sync()
        if self._changes is not None:
            self._changes[0].flush()
            os.fsync(self._changes[0].fileno())

    def close(self) -> None:
        """Close the event log (and ``contact.csv``)."""
        if self._log is not None:
            self._log.close()
        self._log = None
        if self._changes is not None:
            self._changes[0].close()
        self._changes = None

    def finish(self, rows: list[Row], modes: np.ndarray, faces: np.ndarray | None) -> None:
        """``load_displacement.png``, ``cracks.png`` and the drawing's own files."""
        if not self.on or not rows:
            return
        import matplotlib

        matplotlib.use("Agg")
        from geofrac.io.pictures import save

        scene = self.ctx.scene
        fig = load_displacement_figure(rows, self.ctx.control, name=scene.name, units=scene.units)
        save(fig, self.out_dir / "load_displacement.png", dpi=90)
        self._plot_cracks(modes, faces, rows)
        self.drawing.write_extra(self.out_dir)

    def _plot_cracks(self, modes: np.ndarray, faces: np.ndarray | None, rows: list[Row]) -> None:
        """``cracks.png``: the outline, pre-existing cracks and joints, new cracks by mode.

        New cracks are red (tension) or blue (shear). Without contact, pre-existing
        cracks are grey; with contact, joints (pre-existing cracks) are drawn by the
        state of their faces at the end: stuck grey, open purple, slipping orange (thicker),
        and new cracks whose faces slip are drawn orange over their mode's colour. Cells a
        stage removed are filled grey, other void cells (fragments) sand; cracks inside
        the excavation (both cells removed) are not drawn. When the excavation spans less
        than a quarter of the specimen, a second panel shows it enlarged (its frame is
        drawn on the first). The axes keep a margin around the specimen so that its
        outline is drawn whole; the legend sits below.
        """
        import matplotlib.pyplot as plt

        state = self.state
        m = state.mesh
        x0, y0 = m.coords.min(axis=0)
        x1, y1 = m.coords.max(axis=0)
        span = max(x1 - x0, y1 - y0)
        pad = 0.02 * span
        removed = getattr(state, "removed", np.zeros(m.num_cells, dtype=bool))
        zoom = None
        if removed.any():
            pts = m.coords[m.cells[removed]].reshape(-1, 2)
            lo, hi = pts.min(axis=0), pts.max(axis=0)
            if (hi - lo).max() < 0.25 * span:
                centre, half = 0.5 * (lo + hi), (hi - lo).max()
                zoom = (centre - half, centre + half)
        aspect = (y1 - y0 + 2 * pad) / (x1 - x0 + 2 * pad)
        size = 7.0  # inches of the longer side of the specimen's box
        box = (size, size * aspect) if aspect <= 1.0 else (size / aspect, size)
        width, height = max(box[0], 3.5) + 0.8, max(box[1], 2.0) + 1.2
        if zoom is None:
            fig, ax = plt.subplots(figsize=(width, height))
            axes = [ax]
        else:
            fig, axes = plt.subplots(1, 2, figsize=(width + height - 1.2, height))
        units = self.ctx.scene.units
        for i, ax in enumerate(axes):
            self._draw_cracks(ax, modes, faces, legend=i == 0)
            _mark_slips(ax, rows, legend=i == 0)
            if i == 0:
                ax.set_xlim(x0 - pad, x1 + pad)
                ax.set_ylim(y0 - pad, y1 + pad)
            else:
                assert zoom is not None
                ax.set_xlim(zoom[0][0], zoom[1][0])
                ax.set_ylim(zoom[0][1], zoom[1][1])
                ax.set_title("around the excavation", fontsize=10)
                (a, b), (c, d) = zoom
                axes[0].plot([a, c, c, a, a], [b, b, d, d, b], color="k", lw=0.8, ls="--")
            ax.set_aspect("equal")
            ax.set_xlabel(units.label("x", "length"))
            ax.set_ylabel(units.label("y", "length"))
        new = int((state.cracked & ~self._precracked()).sum())
        axes[0].set_title(
            f"{self.ctx.scene.name}: {new} new cracked edges after {len(rows)} events"
            + _pair_counts(faces),
            fontsize=10,
        )
        handles, labels = axes[0].get_legend_handles_labels()
        if handles:  # below the axes: it hides nothing
            fig.legend(handles, labels, loc="lower center", ncol=2, fontsize=8, frameon=False)
        rows = (len(handles) + 1) // 2  # legend rows below the axes
        below = (0.15 + 0.17 * rows) / height if handles else 0.0  # inches -> figure share
        fig.tight_layout(rect=(0.0, below, 1.0, 1.0))
        # "tight": a long two-line title or the legend is never cut at the figure's edge
        fig.savefig(self.out_dir / "cracks.png", dpi=110, bbox_inches="tight", pad_inches=0.1)
        plt.close(fig)

    def _precracked(self) -> np.ndarray:
        """Whether each edge was cracked before loading, shape=(num_edges,)."""
        pre = np.zeros(len(self.state.mesh.edges), dtype=bool)
        pre[self.sites.precracked] = True
        return pre

    def _draw_cracks(
        self, ax: Axes, modes: np.ndarray, faces: np.ndarray | None, *, legend: bool
    ) -> None:
        """Draw void cells, the outline and the crack layers of ``cracks.png`` on ``ax``."""
        from matplotlib.collections import LineCollection, PolyCollection

        state = self.state
        m = state.mesh
        pre = self._precracked()
        new = state.cracked & ~pre
        void = state.void_cells()
        removed = getattr(state, "removed", np.zeros(m.num_cells, dtype=bool))
        ec = m.edge_cells
        inside = (ec >= 0).all(axis=1) & removed[np.maximum(ec, 0)].all(axis=1)
        for cells, colour, label in (
            (void[removed[void]], "0.75", "excavated"),
            (void[~removed[void]], "#f3d9a4", "fragment (void)"),
        ):
            if len(cells):
                ax.add_collection(
                    PolyCollection(
                        m.coords[m.cells[cells]],
                        facecolors=colour,
                        edgecolors="none",
                        label=label if legend else None,
                    )
                )
        outline = m.coords[m.edges[m.boundary_edges]]
        ax.add_collection(LineCollection(outline, colors="k", linewidths=0.6))
        self.drawing.draw_extra(ax)
        shear = new & (modes == 2) if len(modes) == len(new) else np.zeros_like(new)
        layers: list[tuple[np.ndarray, str, float, str]] = []
        if faces is None:
            layers.append((pre, "0.6", 0.5, "pre-existing crack"))
        else:
            for code, colour, width_, label in (
                (STICK, "0.55", 0.5, "joint, stuck"),
                (OPEN, OPEN_COLOUR, 1.0, "joint, open"),
            ):
                layers.append((pre & (faces == code), colour, width_, label))
            layers.append((pre & (faces == NO_PAIR), "0.6", 0.5, "joint"))
        layers += [
            (new & ~shear, MODE_COLOURS[0], 1.0, "new crack, tension"),
            (shear, MODE_COLOURS[1], 1.0, "new crack, shear"),
        ]
        if faces is not None:
            layers.append((pre & (faces == SLIP), SLIP_COLOUR, 1.8, "joint, slipping"))
            layers.append((new & (faces == SLIP), SLIP_COLOUR, 1.8, "new crack, slipping"))
        for layer, colour, width_, label in layers:
            mask = layer & ~inside
            if mask.any():
                segments = self.drawing.segments(mask)
                ax.add_collection(
                    LineCollection(
                        segments, colors=colour, linewidths=width_, label=label if legend else None
                    )
                )


def _mark_slips(ax: Axes, rows: list[Row], *, legend: bool) -> None:
    """Circle the sites of the slip events (a face pair starting to slip), numbered if few."""
    slips = [r for r in rows if r.get("mode") == "slip"]
    if not slips:
        return
    at = np.array([(r["x"], r["y"]) for r in slips], dtype=float)
    label = f"slip event ({len(at)})" if legend else None
    ax.plot(at[:, 0], at[:, 1], "o", mfc="none", mec="k", ms=8, mew=0.9, label=label, zorder=5)
    if len(slips) <= 10:
        for r, (x, y) in zip(slips, at, strict=True):
            ax.annotate(f"{int(r['event'])}", (x, y), xytext=(5, -9), textcoords="offset points",
                        fontsize=7)  # fmt: skip


def _pair_counts(faces: np.ndarray | None) -> str:
    """A second title line with contact: the cracked edges' face states at the end; else ``""``.

    Counted per cracked edge (as drawn), not per node pair of the summary's ``contact``.
    """
    if faces is None:
        return ""
    counts = [f"{int((faces == code).sum())} {name}" for code, name in
              ((STICK, "stuck"), (SLIP, "slipping"), (OPEN, "open"))]  # fmt: skip
    return "\ncracked edges' faces at the end: " + ", ".join(counts)


def load_displacement_figure(
    rows: list[Row], control: Control, *, name: str, units: SceneUnits
) -> Figure:
    """``load_displacement.png``: the control's force against its displacement, by event.

    Displacement control: the mean prescribed displacement of the control group's DOFs
    against the reaction on them; force control: the displacement work-conjugate to the
    load (or the ``control_point`` node's along it) against its force; a staged release:
    the load factor λ of the stage's release against the event.
    """
    from matplotlib.ticker import MaxNLocator

    from geofrac.io.pictures import new_figure

    fig = new_figure(6.0, 4.0)
    ax = fig.subplots()
    group = control.group
    if control.kind == RELEASE:
        ax.plot([r["event"] for r in rows], [r["load_factor"] for r in rows], lw=0.8,
                marker=".", ms=2)  # fmt: skip
        ax.set_xlabel("event")
        ax.set_ylabel("load factor λ of the stage's release")
    else:
        d = [0.0] + [r["control_displacement"] for r in rows]  # from the unloaded state
        ax.plot(d, [0.0] + [r["reaction"] for r in rows], lw=0.8, marker=".", ms=2,
                label="event")  # fmt: skip
        slips = [r for r in rows if r.get("mode") == "slip"]
        if slips:  # a joint's face pair starting to slip (Jaeger's σ1 is the first)
            ax.plot([r["control_displacement"] for r in slips], [r["reaction"] for r in slips],
                    "o", mfc="none", mec="k", ms=6, label="slip event")  # fmt: skip
            ax.legend(fontsize=8)
        if control.kind == "force":
            along = "work-conjugate" if control.node is None else "at the control point"
            ax.set_xlabel(units.label(f"displacement of the load on '{group}', {along}", "length"))
            ax.set_ylabel(units.label(f"force of the load on '{group}'", "force"))
        else:
            ax.set_xlabel(units.label(f"prescribed displacement of '{group}'", "length"))
            ax.set_ylabel(units.label(f"reaction on '{group}'", "force"))
    release = control.kind == RELEASE
    ax.xaxis.set_major_locator(MaxNLocator(6, integer=release))
    ax.grid(True, alpha=0.3)
    what = "the stages' release by event" if release else "load against displacement"
    events = f"{len(rows)} event{'s' if len(rows) != 1 else ''}"
    ax.set_title(f"{name}: {what}, {events}", fontsize=10)
    return fig


def _changes_until(path: Path, event: float) -> list[list[str]]:
    """The rows of an earlier ``contact.csv`` up to ``event`` (a resumed run keeps them)."""
    if not path.is_file():
        return []
    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    if not rows or tuple(rows[0]) != CHANGE_COLUMNS:
        return []
    out = []
    for row in rows[1:]:
        try:
            if int(row[0]) <= event:
                out.append(row)
        except (ValueError, IndexError):
            break  # a line cut by the interruption: nothing after it was written whole
    return out
