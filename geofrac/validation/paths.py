"""Where a crack went: measures of a cracking run's path from its ``events.csv``.

Pure numpy. A run's ``events.csv`` has one row per crack event: the cracked edge, its two
nodes and its midpoint (x, y), the load factor and the control reaction
(:data:`geofrac.fracture.output.EVENT_COLUMNS`). The measures here judge a path against
the one the specimen's symmetry dictates: the axis x = 0 of the symmetric notched beam
(jobs/sym_notched_beam.toml), the loaded diameter of the Brazilian disc
(jobs/brazilian_disc.toml).

The *main crack* is the set of cracked edges joined to the first event's edge through
shared nodes (and, with ``gap`` > 0, through midpoints at most ``gap`` apart): cracks that
start elsewhere (under a load pad, at a support) are not part of it.
"""

from __future__ import annotations

import csv
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from geofrac.validation.brazilian import splitting_tensile_strength

__all__ = [
    "PAD_ZONE",
    "AxisDeviation",
    "CrackEvents",
    "DiscSplit",
    "axis_deviation",
    "disc_split",
    "main_crack",
    "read_events",
    "split_through",
    "spread_until",
]


#: The depth below the symmetric beam's top (mm) that the load pad's frozen cells and its
#: compression take: a crack that enters it has reached the load (its 6 mm pad holds the
#: cells touching it, one element deep, which no crack may cross).
PAD_ZONE = 5.0


@dataclass(frozen=True)
class CrackEvents:
    """The events of a run, in order; every array has shape=(n,), n events.

    Attributes:
        event: event numbers (1, 2, ...).
        node_a: first node of the cracked edge.
        node_b: second node of the cracked edge.
        x: abscissa of the cracked edge's midpoint.
        y: ordinate of the cracked edge's midpoint.
        load_factor: r of the event (the unit load's multiplier).
        reaction: the control reaction at the event's load.
    """

    event: np.ndarray
    node_a: np.ndarray
    node_b: np.ndarray
    x: np.ndarray
    y: np.ndarray
    load_factor: np.ndarray
    reaction: np.ndarray

    def __len__(self) -> int:
        """Number of events."""
        return len(self.event)

    @classmethod
    def from_rows(cls, rows: Sequence[Mapping[str, Any]]) -> CrackEvents:
        """From the rows of ``events.csv`` (strings) or of a driver's event log (numbers)."""

        def column(name: str, kind: type) -> np.ndarray:
            return np.array([kind(float(r[name])) for r in rows], dtype=kind)

        return cls(
            event=column("event", int),
            node_a=column("node_a", int),
            node_b=column("node_b", int),
            x=column("x", float),
            y=column("y", float),
            load_factor=column("load_factor", float),
            reaction=column("reaction", float),
        )


def read_events(out: Path) -> CrackEvents:
    """The events of the run whose output directory is ``out`` (its ``events.csv``)."""
    with open(Path(out) / "events.csv", newline="") as f:
        return CrackEvents.from_rows(list(csv.DictReader(f)))


def main_crack(events: CrackEvents, *, gap: float = 0.0, upto: int | None = None) -> np.ndarray:
    """Which events belong to the crack of the first event (see the module docstring).

    Args:
        events: the run's events.
        gap: edges whose midpoints are at most this far apart join too (0: shared nodes
            only).
        upto: consider the first ``upto`` events only (None: all).

    Returns:
        shape=(n,) bool; False beyond ``upto``.
    """
    n = len(events) if upto is None else min(upto, len(events))
    member = np.zeros(len(events), dtype=bool)
    if n == 0:
        return member
    parent = list(range(n))

    def find(i: int) -> int:
        while parent[i] != i:
            parent[i] = parent[parent[i]]
            i = parent[i]
        return i

    first_by_node: dict[int, int] = {}
    for i in range(n):
        for node in (int(events.node_a[i]), int(events.node_b[i])):
            j = first_by_node.setdefault(node, i)
            parent[find(i)] = find(j)
    if gap > 0.0:
        pts = np.c_[events.x[:n], events.y[:n]]
        close = np.hypot(*(pts[:, None, :] - pts[None, :, :]).transpose(2, 0, 1)) <= gap
        for i, j in zip(*np.nonzero(np.triu(close, 1)), strict=True):
            parent[find(int(i))] = find(int(j))
    root = find(0)
    member[:n] = [find(i) == root for i in range(n)]
    return member


@dataclass(frozen=True)
class AxisDeviation:
    """How far a crack strayed from an axis x = ``axis`` (the symmetric beam's).

    Attributes:
        distance: largest |x − axis| of a main-crack edge until the crack reached the
            face (or over the whole run).
        x: abscissa of that edge's midpoint.
        y: ordinate of that edge's midpoint.
        reached_event: the event whose edge brought the main crack to the face, or None.
        face_x: x − axis of that edge (where the crack reaches the face), or None.
        events: the events counted (up to ``reached_event``, else all).
        main_edges: main-crack edges among them (at y <= ``below``).
    """

    distance: float
    x: float
    y: float
    reached_event: int | None
    face_x: float | None
    events: int
    main_edges: int


def axis_deviation(
    events: CrackEvents,
    *,
    face_y: float,
    reach: float,
    axis: float = 0.0,
    gap: float = 0.0,
    below: float = math.inf,
) -> AxisDeviation:
    """Largest distance of the main crack from the axis until it reaches the face y = face_y.

    The main crack (:func:`main_crack`, from the first event's edge) reaches the face at
    its first edge whose midpoint lies within ``reach`` of it (for an edge with a node on
    the face, at most half the edge's length; the bench takes 0.75 h).

    Args:
        events: the run's events (the first at the notch tip).
        face_y: the face's ordinate (the beam's top).
        reach: distance from the face within which a midpoint counts as on it.
        axis: the axis' abscissa.
        gap: see :func:`main_crack`.
        below: only edges with midpoints at y <= ``below`` count for the distance (the
            beam's ligament without the load pad's zone, where the main crack may join
            cracks under the pad); all count for reaching the face.
    """
    member = main_crack(events, gap=gap)
    on_face = member & (np.abs(events.y - face_y) <= reach)
    hits = np.flatnonzero(on_face)
    stop = int(hits[0]) + 1 if len(hits) else len(events)
    counted = member.copy()
    counted[stop:] = False
    counted &= events.y <= below
    if not counted.any():
        return AxisDeviation(math.nan, math.nan, math.nan, None, None, stop, 0)
    dist = np.where(counted, np.abs(events.x - axis), -np.inf)
    k = int(np.argmax(dist))
    reached = int(events.event[hits[0]]) if len(hits) else None
    face_x = float(events.x[hits[0]] - axis) if len(hits) else None
    return AxisDeviation(
        distance=float(dist[k]),
        x=float(events.x[k]),
        y=float(events.y[k]),
        reached_event=reached,
        face_x=face_x,
        events=stop,
        main_edges=int(counted.sum()),
    )


def spread_until(
    events: CrackEvents, *, y_stop: float, axis: float = 0.0
) -> tuple[float, int | None]:
    """Largest distance of *every* cracked edge from the axis until the crack reaches y_stop.

    The count stops at the first event whose edge belongs to the main crack
    (:func:`main_crack`) and lies at y ≥ ``y_stop`` (the beam's load-pad zone): every
    edge cracked up to that event counts, on the main crack or not.

    Args:
        events: the run's events (the first at the notch tip).
        y_stop: the ordinate that ends the count.
        axis: the axis' abscissa.

    Returns:
        (the distance, nan without events; the stopping event, or None when the crack
        never reached y_stop and every event counted).
    """
    if len(events) == 0:
        return math.nan, None
    member = main_crack(events)
    hits = np.flatnonzero(member & (events.y >= y_stop))
    stop = int(hits[0]) + 1 if len(hits) else len(events)
    distance = float(np.abs(events.x[:stop] - axis).max())
    return distance, (int(events.event[hits[0]]) if len(hits) else None)


@dataclass(frozen=True)
class DiscSplit:
    """Where a Brazilian disc split and at what load.

    Attributes:
        first_from_diameter: distance of the first cracked edge from the loaded diameter.
        first_from_centre: distance of the first cracked edge from the centre.
        main_from_diameter: largest distance of a main-crack edge from the loaded diameter.
        any_from_diameter: largest distance of any cracked edge from the loaded diameter.
        peak_load: the largest |reaction| of the events measured (the splitting load P under force
            control, where the reaction is the load factor times the strip's resultant).
        peak_event: the event of ``peak_load``.
        strength_isrm: 2P / (π D t) (ISRM).
        strength_hondros: 2P / (π D t) (sin 2α − α) / sin α (Hondros' strip correction,
            with P the strip's resultant; see
            :func:`~geofrac.validation.brazilian.splitting_tensile_strength`).
    """

    first_from_diameter: float
    first_from_centre: float
    main_from_diameter: float
    any_from_diameter: float
    peak_load: float
    peak_event: int
    strength_isrm: float
    strength_hondros: float


def split_through(
    events: CrackEvents,
    *,
    radius: float,
    reach: float,
    centre: tuple[float, float] = (0.0, 0.0),
    gap: float = 0.0,
) -> int | None:
    """The event at which the main crack has split the disc: it reaches the rim on both sides.

    The main crack (:func:`main_crack`) reaches the rim on a side of the centre (y above
    or below centre[1]) at its first edge there whose midpoint lies within ``reach`` of
    the rim (distance from the centre ≥ radius − reach). The cells at the strips'
    centres hold the supports and never crack, so a split along the loaded diameter
    stops about one element short of the rim: a ``reach`` of 1.5 h counts it.

    Returns:
        the number of the event at which both sides are reached, or None (not split).
    """
    member = main_crack(events, gap=gap)
    dx, dy = events.x - centre[0], events.y - centre[1]
    near = member & (np.hypot(dx, dy) >= radius - reach)
    above, below = np.flatnonzero(near & (dy > 0)), np.flatnonzero(near & (dy < 0))
    if not (len(above) and len(below)):
        return None
    return int(events.event[max(above[0], below[0])])


def disc_split(
    events: CrackEvents,
    *,
    diameter: float,
    thickness: float,
    alpha: float,
    centre: tuple[float, float] = (0.0, 0.0),
    gap: float = 0.0,
    upto: int | None = None,
) -> DiscSplit:
    """The split of a disc loaded along the diameter x = centre[0] (the y direction).

    Args:
        events: the run's events (at least one).
        diameter: D.
        thickness: t.
        alpha: half the strips' angular width, radians.
        centre: the disc's centre.
        gap: see :func:`main_crack`.
        upto: measure the first ``upto`` events only (None: all), e.g. until the split
            (:func:`split_through`).

    Raises:
        ValueError: no events.
    """
    if len(events) == 0:
        raise ValueError("no crack events")
    n = len(events) if upto is None else max(1, min(upto, len(events)))
    off = np.abs(events.x[:n] - centre[0])
    member = main_crack(events, gap=gap, upto=n)[:n]
    k = int(np.argmax(np.abs(events.reaction[:n])))
    peak = float(abs(events.reaction[k]))
    return DiscSplit(
        first_from_diameter=float(off[0]),
        first_from_centre=float(math.hypot(events.x[0] - centre[0], events.y[0] - centre[1])),
        main_from_diameter=float(off[member].max()),
        any_from_diameter=float(off.max()),
        peak_load=peak,
        peak_event=int(events.event[k]),
        strength_isrm=splitting_tensile_strength(peak, diameter=diameter, thickness=thickness),
        strength_hondros=splitting_tensile_strength(
            peak, diameter=diameter, thickness=thickness, alpha=alpha
        ),
    )
