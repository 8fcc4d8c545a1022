"""Crack growth that follows the stress's direction, not the mesh's (pure numpy).

Edo (2016), §2.3.2, cracks the edge with the highest σ1 at its midpoint. σ1 does not
depend on the edge's direction, and at a crack tip the stress is singular: among the
edges at the tip, the one whose midpoint lies closest to the tip wins whatever its
direction, so the mesh's lattice picks the path. This module separates *which way* a
crack grows from *where* and *when*:

- **Tips.** A tip is an interior node with exactly one cracked edge
  (:func:`tip_nodes`), or the corner of a notch (:func:`notch_corners`) while no crack
  lies within R of it, with the corner's bisector as its last direction. Its
  direction of growth is perpendicular to the largest principal direction of the
  stress averaged over a disc about the tip (:func:`averaged_stress`: Gaussian
  weights of radius R, cells within :data:`CUTOFF` R), which does not depend on which
  edge lies closest to the tip. R is ``cracking.averaging_radius``
  or, by default, :data:`RADIUS_FACTOR` times the mean length of the tip's edges.
- **Path tracking.** Each tip carries an *ideal point* p on the continuous path the
  directions describe. The tip grows along the uncracked edge (a, b) whose far node b
  lies closest to the ideal line p + s d (s > 0; :func:`choose_edge`), and b's ideal
  point is the projection of b onto that line. The discrete crack therefore stays
  within about half an element of the continuous path, and its zigzag across a
  lattice does not accumulate into a drift along one of the lattice's directions.
- **Where and when.** A tip and the uncracked edges at it or within R of it form
  the tip's *zone*: the zone cracks when the largest σ1 of its edges (at their
  midpoints, the thesis's measure: the singular value at the tip) reaches f_t, and
  then along the tip's chosen edge only. Away from tips a new crack starts where σ1
  of an edge first reaches f_t (the thesis's measure, blind to the edge's direction,
  so that the place is the stress's), along the edge there (itself or one sharing a
  node with it) whose normal lies nearest to σ1's direction. The traction n·σ·n would
  pick the best-aligned edge anywhere in a region of near-uniform stress instead: on a
  Brazilian disc whose central 20 mm carry σ_xx within 1 %, an edge 7° off the
  diameter 3.7 mm from the centre, at a load 14 % too high. The stress is averaged for
  the direction only: an average over R mixes a tip's small tensile lobe with the
  compression around it (a wing crack), which would delay the event.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy.spatial import cKDTree

from geofrac.fracture.topology import EdgeMesh

__all__ = [
    "CUTOFF",
    "FORWARD",
    "ISOTROPIC",
    "NOTCH_ANGLE",
    "RADIUS_FACTOR",
    "Tip",
    "TipTracker",
    "averaged_stress",
    "choose_edge",
    "growth_direction",
    "notch_corners",
    "nucleation_tips",
    "principal_direction",
    "tip_nodes",
]

#: The default radius R, in mean lengths of the tip's edges.
RADIUS_FACTOR = 2.0

#: Cells farther than this many R from the point get no weight (exp(−4) = 0.018 there).
CUTOFF = 2.0

#: An edge counts as growing forward when it advances along the direction by at least
#: this fraction of its length (an angle below about 84° to the direction).
FORWARD = 0.1

#: A boundary node is a notch's corner (a tip before any crack) when the body's angle
#: there exceeds this (radians: 240°; a V notch of 90° leaves 270°, the V's shoulders
#: on a slot's faces 225°).
NOTCH_ANGLE = np.radians(240.0)

#: The averaged stress is *isotropic* (no direction of its own) when σ1 − σ2 is below
#: this fraction of max(|σ1|, |σ2|); the tip then keeps its previous direction.
ISOTROPIC = 1e-6


@dataclass
class Tip:
    """A crack tip's ideal point and its last direction of growth.

    Attributes:
        point: the ideal point p on the continuous path, shape=(2,).
        direction: the last unit direction of growth, shape=(2,).
    """

    point: np.ndarray
    direction: np.ndarray


def tip_nodes(mesh: EdgeMesh, cracked: np.ndarray, on_boundary: np.ndarray) -> np.ndarray:
    """Interior nodes with exactly one cracked edge, sorted, shape=(k,).

    Args:
        mesh: the triangle mesh with edges.
        cracked: whether each edge is cracked, shape=(num_edges,).
        on_boundary: whether each node lies on the boundary, shape=(num_nodes,).
    """
    count = np.bincount(mesh.edges[cracked].ravel(), minlength=len(mesh.coords))
    return np.flatnonzero((count == 1) & ~on_boundary)


def notch_corners(mesh: EdgeMesh) -> tuple[np.ndarray, np.ndarray]:
    """Boundary nodes at re-entrant corners, and the bisector into the body at each.

    A corner is re-entrant when the body's angle there (the sum of its cells' angles)
    exceeds :data:`NOTCH_ANGLE`: the tip of a V notch (270° for a 90° V), the corners
    of a slot's end; not the nodes of a polygon approximating a hole (180° plus 360°
    over the number of segments).

    Returns:
        (nodes, sorted, shape=(k,); unit bisectors pointing into the body, shape=(k, 2)).
    """
    x = mesh.coords[mesh.cells]  # shape=(num_cells, 3, 2)
    angle = np.zeros(len(mesh.coords))
    for j in range(3):
        a, b = x[:, (j + 1) % 3] - x[:, j], x[:, (j + 2) % 3] - x[:, j]
        cos = np.sum(a * b, axis=1) / (np.hypot(*a.T) * np.hypot(*b.T))
        np.add.at(angle, mesh.cells[:, j], np.arccos(np.clip(cos, -1.0, 1.0)))
    bnd = mesh.edges[mesh.boundary_edges]
    nodes = np.flatnonzero(mesh.boundary_nodes() & (angle > NOTCH_ANGLE))
    out = np.zeros((len(nodes), 2))
    for i, v in enumerate(nodes.tolist()):
        ends = bnd[(bnd == v).any(axis=1)]
        others = np.where(ends[:, 0] == v, ends[:, 1], ends[:, 0])
        u = mesh.coords[others] - mesh.coords[v]
        u /= np.hypot(*u.T)[:, None]
        d = -u.sum(axis=0)  # the opening lies between the two boundary edges
        out[i] = d / np.hypot(*d)
    return nodes, out


def principal_direction(stress: np.ndarray) -> tuple[float, float, np.ndarray]:
    """(σ1, σ2, unit direction of σ1) of one plane stress (σ_xx, σ_yy, σ_xy), shape=(3,)."""
    sxx, syy, sxy = (float(v) for v in stress)
    centre, radius = 0.5 * (sxx + syy), float(np.hypot(0.5 * (sxx - syy), sxy))
    angle = 0.5 * np.arctan2(2.0 * sxy, sxx - syy)
    return centre + radius, centre - radius, np.array([np.cos(angle), np.sin(angle)])


def averaged_stress(
    stress: np.ndarray, areas: np.ndarray, distance: np.ndarray, *, radius: float
) -> np.ndarray:
    """The Gaussian-weighted mean of cell stresses about a point, shape=(3,).

    Args:
        stress: (σ_xx, σ_yy, σ_xy) of each cell, shape=(k, 3).
        areas: the cells' areas, shape=(k,).
        distance: the cells' centroids' distances from the point, shape=(k,).
        radius: R; the weight of a cell is its area times exp(−(d / R)²).
    """
    w = areas * np.exp(-((distance / radius) ** 2))
    return (w @ stress) / w.sum()


def growth_direction(stress: np.ndarray, previous: np.ndarray) -> tuple[float, np.ndarray]:
    """(σ1, the unit direction a tip grows in) under an averaged stress, shape=(3,).

    The direction is perpendicular to σ1's, on the side of ``previous`` (shape=(2,)).
    An isotropic stress (:data:`ISOTROPIC`) keeps ``previous``.
    """
    s1, s2, v = principal_direction(stress)
    if s1 - s2 <= ISOTROPIC * max(abs(s1), abs(s2)):
        return s1, previous
    d = np.array([-v[1], v[0]])
    return s1, d if d @ previous >= 0.0 else -d


def choose_edge(
    coords: np.ndarray,
    tip: int,
    ideal: Tip,
    *,
    direction: np.ndarray,
    edges: np.ndarray,
    others: np.ndarray,
) -> tuple[int, np.ndarray] | None:
    """The edge a tip grows along, and the ideal point of its far node.

    Among the edges at the tip that advance along ``direction`` (:data:`FORWARD`), the
    one whose far node lies closest to the ideal line p + s d; ties (within 1e-9 of
    the edge length) go to the far node that comes first by position (x, then y).

    Args:
        coords: node coordinates, shape=(num_nodes, 2).
        tip: the tip node.
        ideal: the tip's ideal point p.
        direction: the unit direction d, shape=(2,).
        edges: candidate edge ids at the tip, shape=(k,).
        others: their far nodes, shape=(k,).

    Returns:
        (edge id, ideal point of its far node, shape=(2,)), or None when no edge
        advances.
    """
    if not len(edges):
        return None
    xb = coords[others]
    step = xb - coords[tip]
    length = np.hypot(step[:, 0], step[:, 1])
    ahead = step @ direction > FORWARD * length
    rel = xb - ideal.point
    along = rel @ direction
    ok = ahead & (along > 0.0)
    if not np.any(ok):
        return None
    lateral = np.abs(rel[:, 0] * direction[1] - rel[:, 1] * direction[0])
    best = lateral[ok].min()
    tied = np.flatnonzero(ok & (lateral <= best + 1e-9 * length))
    pick = tied[np.lexsort((others[tied], xb[tied, 1], xb[tied, 0]))[0]]
    return int(edges[pick]), ideal.point + along[pick] * direction


def nucleation_tips(
    ends: np.ndarray, stress: np.ndarray, *, through: np.ndarray | None = None
) -> list[tuple[int, Tip]]:
    """The tips a new crack on one edge starts at its two nodes.

    The ideal line runs through ``through`` (default: the edge's midpoint) perpendicular
    to σ1's direction there (not along the edge: the lattice's direction is not the
    crack's); each node's ideal point is its projection onto that line, its direction
    the line's, pointing away from the line's point. An isotropic stress
    (:data:`ISOTROPIC`) takes the edge's own direction.

    Args:
        ends: the two nodes' coordinates, shape=(2, 2).
        stress: (σ_xx, σ_yy, σ_xy) where the crack starts, shape=(3,).
        through: the point the ideal line runs through, shape=(2,).

    Returns:
        [(0, tip of the first node), (1, tip of the second)] (local node indices).
    """
    mid = ends.mean(axis=0) if through is None else np.asarray(through, dtype=float)
    along = ends[1] - ends[0]
    _, d = growth_direction(stress, along / np.hypot(*along))
    out = []
    for i, x in enumerate(ends):
        s = float((x - mid) @ d)
        if s == 0.0:  # a node on the normal through the point: away from the other node
            s = float((x - ends[1 - i]) @ d)
        di = d if s >= 0.0 else -d
        out.append((i, Tip(mid + float((x - mid) @ d) * d, di.copy())))
    return out


@dataclass
class TipTracker:
    """The tips of the cracks, their ideal points and their neighbourhoods.

    Args:
        mesh: the triangle mesh with edges.
        on_boundary: whether each node lies on the boundary, shape=(num_nodes,).
        radius: the averaging radius R, or None for :data:`RADIUS_FACTOR` times the
            mean length of each tip's edges.
    """

    mesh: EdgeMesh
    on_boundary: np.ndarray
    radius: float | None = None
    #: tip node -> its ideal point and last direction.
    tips: dict[int, Tip] = field(default_factory=dict)
    #: notch corner node -> its bisector into the body (:func:`notch_corners`).
    notches: dict[int, np.ndarray] = field(default_factory=dict)

    def __post_init__(self) -> None:  # noqa: D105
        m = self.mesh
        #: edges at each node as CSR: offsets, shape=(num_nodes + 1,); edge ids.
        self._ptr, self._node_edges = m.node_edges()
        seg = m.coords[m.edges]
        self.lengths = np.hypot(*(seg[:, 1] - seg[:, 0]).T)
        self._centroids = m.centroids()
        self._cells = cKDTree(self._centroids)
        self._mids = cKDTree(m.midpoints())
        self.areas = m.areas()
        #: per tip node: (cells within CUTOFF R, their distances), (edges within R).
        self._near: dict[int, tuple[np.ndarray, np.ndarray, np.ndarray]] = {}
        #: per tip node: its zone's edges (:meth:`zone`).
        self._zones: dict[int, np.ndarray] = {}

    def edges_at(self, node: int) -> np.ndarray:
        """The edges at a node, shape=(k,)."""
        return self._node_edges[self._ptr[node] : self._ptr[node + 1]]

    def tip_radius(self, node: int) -> float:
        """R at a tip node."""
        if self.radius is not None:
            return self.radius
        return RADIUS_FACTOR * float(self.lengths[self.edges_at(node)].mean())

    def near(self, node: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(cells within CUTOFF R, shape=(k,); their distances, shape=(k,); edges within R)."""
        hit = self._near.get(node)
        if hit is None:
            x, r = self.mesh.coords[node], self.tip_radius(node)
            cells = np.array(sorted(self._cells.query_ball_point(x, CUTOFF * r)), dtype=np.int64)
            dist = np.hypot(*(self._centroids[cells] - x).T) if len(cells) else cells
            edges = np.array(sorted(self._mids.query_ball_point(x, r)), dtype=np.int64)
            hit = self._near[node] = (cells, np.asarray(dist, dtype=float), edges)
        return hit

    def zone(self, node: int) -> np.ndarray:
        """The edges at a tip node or within R of it (open or not), sorted, shape=(k,)."""
        zone = self._zones.get(node)
        if zone is None:
            zone = self._zones[node] = np.union1d(self.near(node)[2], self.edges_at(node))
        return zone

    def tip(self, node: int, cracked: np.ndarray) -> Tip:
        """The tracked tip at ``node``, or a new one there (its crack's own direction)."""
        known = self.tips.get(node)
        if known is not None:
            return known
        if node in self.notches:
            return Tip(self.mesh.coords[node].copy(), self.notches[node].copy())
        e = self.edges_at(node)
        e = e[cracked[e]][0]
        a, b = self.mesh.edges[e]
        other = b if a == node else a
        d = self.mesh.coords[node] - self.mesh.coords[other]
        return Tip(self.mesh.coords[node].copy(), d / np.hypot(*d))

    def cracked(self, edges: np.ndarray, grown: dict[int, list[tuple[int, Tip]]]) -> None:
        """Update the tips after ``edges`` cracked (shape=(k,)).

        ``grown`` maps a cracked edge to the (node, tip) pairs it starts: the far node
        of an edge grown from a tip, the two nodes of a nucleated edge. The nodes of any
        other cracked edge start with their crack's own direction (:meth:`tip`). Nodes
        that are no longer tips are dropped by :meth:`prune`.
        """
        for e in np.asarray(edges, dtype=np.int64):
            for node, tip in grown.get(int(e), []):
                self.tips[node] = tip

    def prune(self, tips: np.ndarray) -> None:
        """Keep the tracked tips that are still tips (``tips``, shape=(k,))."""
        keep = set(tips.tolist())
        self.tips = {n: t for n, t in self.tips.items() if n in keep}

    def snapshot(self) -> dict[str, list[float]]:
        """The tracked tips as JSON: node -> [px, py, dx, dy]."""
        return {str(n): [float(v) for v in (*t.point, *t.direction)] for n, t in self.tips.items()}

    def restore(self, data: dict[str, list[float]]) -> None:
        """Set the tracked tips from :meth:`snapshot`."""
        self.tips = {
            int(n): Tip(np.array(v[:2], dtype=float), np.array(v[2:], dtype=float))
            for n, v in data.items()
        }
