"""The event criterion: which crack sites crack next, and the load factor of the event.

An :class:`EventCriterion` turns the units' stresses under the unit load into one drive
per crack site and picks the sites with least r = f_t / drive (Edo (2016), eq. 2.20;
3.8 for grains). The edge criteria, by ``cracking.criterion`` (:data:`CRITERIA`):

- ``"direction"`` (:class:`DirectionCriterion`, the default): a crack tip grows, when
  the largest σ1 about it reaches f_t, along the edge that follows the direction of
  the stress averaged about the tip; new cracks start where an edge's σ1 reaches f_t,
  on the edge there most nearly across σ1 (:mod:`~geofrac.fracture.direction`);
- ``"traction"`` (:class:`TractionCriterion`): the traction across each edge, n·σ·n;
- ``"principal"`` (:class:`EdgeCriterion`): Edo (2016), §2.3.2: σ1 at the edge's
  midpoint, the mean of its two cells'.

The grain variant (:class:`~geofrac.fracture.grain_driver.GrainCriterion`) takes the
larger of the two grains at the interface centre. A new criterion is one more class with
these methods and one line in :data:`CRITERIA`; the loop calls :meth:`~EventCriterion.cracked`
after each event and keeps :meth:`~EventCriterion.snapshot` in its checkpoints.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Protocol

import numpy as np

from geofrac.fracture.config import CrackingConfig
from geofrac.fracture.contact import edge_frames
from geofrac.fracture.criterion import (
    edge_means,
    edge_principal,
    normal_stress,
    select_edges,
    tie_order,
)
from geofrac.fracture.direction import (
    Tip,
    TipTracker,
    averaged_stress,
    choose_edge,
    growth_direction,
    notch_corners,
    nucleation_tips,
    principal_direction,
    tip_nodes,
)
from geofrac.fracture.units import SiteState

if TYPE_CHECKING:
    from geofrac.fracture.context import JsonValue
    from geofrac.fracture.units import EdgeUnits

__all__ = [
    "CRITERIA",
    "DirectionCriterion",
    "EdgeCriterion",
    "EventCriterion",
    "StatelessCriterion",
    "TractionCriterion",
    "next_sites",
]


class EventCriterion(Protocol):
    """Which sites crack in an event, and r.

    Attributes:
        points: where each site lies (ties go by position), shape=(num_sites, 2).
    """

    points: np.ndarray

    def site_stress(self, unit_s1: np.ndarray) -> np.ndarray:
        """The drive per crack site from the units' σ1 values, shape=(num_sites,)."""
        ...

    def select(self, sigma1: np.ndarray, *, floor: float) -> tuple[np.ndarray, float]:
        """(sites that crack, shape=(k,), k ≥ 1 unless none has a drive > ``floor``; r)."""
        ...

    def cracked(self, sites: np.ndarray) -> None:
        """``sites`` (shape=(k,)) cracked in the event just recorded."""
        ...

    def snapshot(self) -> dict[str, JsonValue]:
        """What a checkpoint must keep of the criterion's own state (JSON)."""
        ...

    def restore(self, data: dict[str, JsonValue]) -> None:
        """Set the criterion's own state from :meth:`snapshot`."""
        ...


def next_sites(
    state: SiteState,
    config: CrackingConfig,
    sigma1: np.ndarray,
    *,
    floor: float,
    points: np.ndarray,
) -> tuple[np.ndarray, float]:
    """The uncracked, crackable sites of least r = f_t / σ1, with the batch settings.

    ``edges_per_event`` sites with r ≤ (1 + ``batch_tolerance``) r_min at most
    (:func:`~geofrac.fracture.criterion.select_edges`); none when no site has
    σ1 > ``floor``. Ties go by ``points``, shape=(num_sites, 2).
    """
    candidates = ~state.cracked & state.crackable
    return select_edges(
        sigma1,
        candidates,
        config.tensile_strength,
        batch_tolerance=config.batch_tolerance,
        max_edges=config.edges_per_event,
        floor=floor,
        points=points,
    )


def state_crackable_at(state: SiteState, nodes: np.ndarray) -> np.ndarray:
    """Whether any edge at each node may crack, shape=(k,)."""
    ends = state.mesh.edges[state.crackable]
    has = np.zeros(len(state.mesh.coords), dtype=bool)
    has[ends.ravel()] = True
    return has[nodes]


class StatelessCriterion:
    """The criterion keeps no state of its own between events."""

    def cracked(self, sites: np.ndarray) -> None:
        """Nothing to update."""

    def snapshot(self) -> dict[str, JsonValue]:
        """Nothing to keep."""
        return {}

    def restore(self, data: dict[str, JsonValue]) -> None:
        """Nothing to restore."""


class EdgeCriterion(StatelessCriterion):
    """Edo (2016), §2.3.2: σ1 of an edge is the mean of its cells' values at its midpoint.

    Args:
        units: the edge units.
        config: the ``[cracking]`` settings.
    """

    needs_stress = False

    def __init__(self, units: EdgeUnits, config: CrackingConfig) -> None:
        self.state, self.config = units.state, config
        #: the edge midpoints, shape=(num_edges, 2).
        self.points = self.state.mesh.midpoints()

    def site_stress(self, unit_s1: np.ndarray) -> np.ndarray:
        """σ1 per edge from σ1 per cell at its local edges, shape=(num_cells, 3)."""
        return edge_principal(self.state.mesh, unit_s1)

    def select(self, sigma1: np.ndarray, *, floor: float) -> tuple[np.ndarray, float]:
        """The edges of least r (:func:`next_sites`)."""
        return next_sites(self.state, self.config, sigma1, floor=floor, points=self.points)

    def set_drive(self, drive: np.ndarray, cell_stress: np.ndarray) -> None:
        """Take ``drive`` per edge as :meth:`site_stress` would have given it (constant loads).

        ``drive``: the equivalent drive f_t/λ per edge (:mod:`~geofrac.fracture.nonprop`),
        shape=(num_edges,); ``cell_stress``: the cells' stress at the event, per local
        edge midpoint, shape=(num_cells, 3, 3).
        """


class TractionCriterion(EdgeCriterion):
    """The traction across each edge, n·σ·n, with σ the mean of its cells' at the midpoint.

    Args:
        units: the edge units (their stress tensors: ``keep_stress``).
        config: the ``[cracking]`` settings.
    """

    needs_stress = True

    def __init__(self, units: EdgeUnits, config: CrackingConfig) -> None:
        super().__init__(units, config)
        self.units = units
        #: unit normals of the edges, shape=(num_edges, 2).
        self.normals = edge_frames(self.state.mesh)[1]
        #: the edges' mean stress of the last :meth:`site_stress`, shape=(num_edges, 3).
        self.edge_stress = np.zeros((0, 3))

    def site_stress(self, unit_s1: np.ndarray) -> np.ndarray:
        """n·σ·n per edge, shape=(num_edges,)."""
        self.edge_stress = edge_means(self.state.mesh, self.units.midpoint_stress)
        return normal_stress(self.edge_stress, self.normals)

    def set_drive(self, drive: np.ndarray, cell_stress: np.ndarray) -> None:
        """Keep the edges' mean of ``cell_stress`` (see :meth:`EdgeCriterion.set_drive`)."""
        self.edge_stress = edge_means(self.state.mesh, cell_stress)


class DirectionCriterion(TractionCriterion):
    """Tips grow along the averaged stress's direction; new cracks start across σ1.

    See :mod:`geofrac.fracture.direction`. A tip's zone (the open edges at it or within
    R of it) offers one edge, chosen by :func:`choose_edge` along the direction of the
    stress averaged about the tip, driven by the largest σ1 of the zone's edges. Every
    other edge is driven by its σ1 (where a new crack starts), and the new crack takes
    the edge there most nearly across σ1's direction (:meth:`_aligned`).

    Args:
        units: the edge units (their stress tensors: ``keep_stress``).
        config: the ``[cracking]`` settings (``averaging_radius``).
    """

    def __init__(self, units: EdgeUnits, config: CrackingConfig) -> None:
        super().__init__(units, config)
        mesh = self.state.mesh
        self.on_boundary = mesh.boundary_nodes()
        self.tracker = TipTracker(mesh, self.on_boundary, config.averaging_radius)
        corners, bisectors = notch_corners(mesh)
        keep = state_crackable_at(self.state, corners)
        self.tracker.notches = {
            int(v): d for v, d, k in zip(corners, bisectors, keep, strict=True) if k
        }
        self._s1 = np.zeros(0)
        #: what each selected edge starts: edge -> [(node, tip)].
        self._grown: dict[int, list[tuple[int, Tip]]] = {}

    def site_stress(self, unit_s1: np.ndarray) -> np.ndarray:
        """σ1 per edge (where a crack starts), shape=(num_edges,); tips: :meth:`select`."""
        self._s1 = edge_principal(self.state.mesh, unit_s1)
        self.edge_stress = edge_means(self.state.mesh, self.units.midpoint_stress)
        return self._s1

    def set_drive(self, drive: np.ndarray, cell_stress: np.ndarray) -> None:
        """The drive of new cracks and tips' zones, the stress of their directions."""
        super().set_drive(drive, cell_stress)
        self._s1 = drive
        self._grown = {}

    def select(self, sigma1: np.ndarray, *, floor: float) -> tuple[np.ndarray, float]:
        """The edges of least r once the tips' zones have chosen their edges.

        A tip's zone is driven by its largest σ1, whichever edge it grows along, so the
        sites of least r are found first (each active zone stands in by its peak edge)
        and only the tips that win look for their direction and edge. A winning tip
        with no edge leading on drops out, its zone's edges become sites of their own,
        and the search is made again.
        """
        state, mesh = self.state, self.state.mesh
        cracked = state.cracked
        open_ = ~cracked & state.crackable
        tips = tip_nodes(mesh, cracked, self.on_boundary)
        notches = [v for v in self.tracker.notches if not cracked[self.tracker.near(v)[2]].any()]
        tips = np.union1d(tips, np.array(notches, dtype=np.int64))
        self.tracker.prune(tips)
        owner = self._zone_owner(tips, open_)  # shape=(num_edges,), index into tips or -1
        in_zone = owner >= 0
        peak = np.full(len(tips), -np.inf)
        np.maximum.at(peak, owner[in_zone], self._s1[in_zone])
        active = peak > floor
        # the peak edge of each zone stands for it (ties: the edge first by position)
        rep = np.full(len(tips), -1, dtype=np.int64)
        zone_edges = np.flatnonzero(in_zone)
        order = tie_order(zone_edges, self.points)
        ranked = zone_edges[order][np.lexsort((-self._s1[zone_edges[order]],))]
        for e in ranked[::-1].tolist():  # the last write per tip is its best edge
            rep[owner[e]] = e
        while True:
            blocked = in_zone.copy()
            blocked[in_zone] = active[owner[in_zone]]
            drive = sigma1.copy()
            drive[blocked] = -np.inf
            drive[rep[active]] = peak[active]
            edges, r = next_sites(state, self.config, drive, floor=floor, points=self.points)
            stand_in = {int(rep[i]): i for i in np.flatnonzero(active)}
            grown: dict[int, list[tuple[int, Tip]]] = {}
            out: list[int] = []
            retry = False
            for e in edges.tolist():
                if e in stand_in:
                    i = stand_in[e]
                    pick = self._grow(int(tips[i]), open_)
                    if pick is None:  # no edge leads on: its zone's edges are sites
                        active[i] = False
                        retry = True
                        break
                    site, starts = pick
                else:  # a new crack at e's σ1, along the edge there that follows the stress
                    site = self._aligned(e, open_ & ~blocked)
                    a, b = mesh.edges[site]
                    made = nucleation_tips(
                        mesh.coords[[a, b]], self.edge_stress[e], through=self.points[e]
                    )
                    starts = [(int((a, b)[i]), t) for i, t in made]
                if site not in out:
                    out.append(site)
                    grown[site] = starts
            if not retry:
                self._grown = grown
                return np.array(out, dtype=np.int64), r

    def _grow(self, a: int, open_: np.ndarray) -> tuple[int, list[tuple[int, Tip]]] | None:
        """The edge tip ``a`` grows along and the tip it leaves at its far node, or None.

        The direction is perpendicular to σ1 of the stress averaged about the tip
        (:func:`averaged_stress`), the edge the one nearest to the ideal line
        (:func:`choose_edge`). ``open_``: the edges that may crack, shape=(num_edges,).
        """
        tracker, mesh = self.tracker, self.state.mesh
        cells, dist, _ = tracker.near(a)
        tip = tracker.tip(a, self.state.cracked)
        if not len(cells):
            return None
        cell_stress = self.units.midpoint_stress[cells].mean(axis=1)
        s_bar = averaged_stress(
            cell_stress, tracker.areas[cells], dist, radius=tracker.tip_radius(a)
        )
        _, d = growth_direction(s_bar, tip.direction)
        at = tracker.edges_at(a)
        cand = at[open_[at]]
        ends = mesh.edges[cand]
        others = np.where(ends[:, 0] == a, ends[:, 1], ends[:, 0])
        pick = choose_edge(mesh.coords, a, tip, direction=d, edges=cand, others=others)
        if pick is None:
            return None
        e, p = pick
        b = int(others[cand == e][0])
        return e, [(b, Tip(p, d.copy()))]

    def _aligned(self, edge: int, free: np.ndarray) -> int:
        """The edge at ``edge`` (itself or one sharing a node) most nearly across σ1 there.

        The normal of the chosen edge is the nearest to σ1's direction at ``edge``'s
        midpoint (:func:`~geofrac.fracture.direction.principal_direction` of the edge's
        mean stress); ties (within 1e-9) go to the edge that comes first by position.
        ``free``: the edges that may crack, shape=(num_edges,).
        """
        tracker = self.tracker
        a, b = self.state.mesh.edges[edge]
        near = np.union1d(tracker.edges_at(int(a)), tracker.edges_at(int(b)))
        near = near[free[near] | (near == edge)]
        _, _, v = principal_direction(self.edge_stress[edge])
        fit = np.abs(self.normals[near] @ v)
        best = near[fit >= fit.max() - 1e-9]
        return int(best[tie_order(best, self.points)[0]])

    def _zone_owner(self, tips: np.ndarray, open_: np.ndarray) -> np.ndarray:
        """The tip whose zone each edge is in: an index into ``tips``, or -1.

        A tip's zone is the open edges at it or within R of it. An edge in the zones of
        several tips (a V notch's corners, two tips about to meet) belongs to the one
        whose node is nearest to its midpoint (ties: the node that comes first by
        position, x then y), so that one stress peak drives one tip.

        Args:
            tips: tip nodes, shape=(k,).
            open_: the edges that may crack, shape=(num_edges,).

        Returns:
            shape=(num_edges,).
        """
        tracker, mesh = self.tracker, self.state.mesh
        owner = np.full(len(mesh.edges), -1, dtype=np.int64)
        if not len(tips):
            return owner
        parts = [tracker.zone(int(a)) for a in tips]
        edges = np.concatenate(parts)
        which = np.repeat(np.arange(len(tips)), [len(z) for z in parts])
        keep = open_[edges]
        edges, which = edges[keep], which[keep]
        xy = mesh.coords[tips[which], :2]
        dist = np.hypot(*(self.points[edges] - xy).T)
        order = np.lexsort((tips[which], xy[:, 1], xy[:, 0], dist, edges))
        first = np.ones(len(order), dtype=bool)
        first[1:] = edges[order][1:] != edges[order][:-1]
        owner[edges[order][first]] = which[order][first]
        return owner

    def cracked(self, sites: np.ndarray) -> None:
        """Track the tips the cracked edges start (shear cracks: their own direction)."""
        self.tracker.cracked(sites, self._grown)
        self._grown = {}

    def snapshot(self) -> dict[str, JsonValue]:
        """The tracked tips (:meth:`~geofrac.fracture.direction.TipTracker.snapshot`)."""
        return {"tips": self.tracker.snapshot()}  # type: ignore[dict-item]

    def restore(self, data: dict[str, JsonValue]) -> None:
        """Set the tracked tips."""
        self.tracker.restore(data.get("tips", {}))  # type: ignore[arg-type]


#: Edge criteria by ``cracking.criterion``.
CRITERIA: dict[str, type[EdgeCriterion]] = {
    "direction": DirectionCriterion,
    "traction": TractionCriterion,
    "principal": EdgeCriterion,
}
