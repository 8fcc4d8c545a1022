"""Turn a fracture network into a meshable planar graph, by documented tolerance rules.

Numpy, and scipy's connected components for ``vertex_merge``. The input is a
:class:`~geofrac.dfn.sampling.Network` and the domain polygon; the output is a
:class:`CleanNetwork`: vertices and straight edges that meet only at shared vertices,
each edge belonging to one fracture, no two vertices closer than the tolerance ``tol``
and no vertex closer than ``tol`` to an edge it does not end on. A gmsh builder can
embed such a graph as it is (``geofrac.meshing.dfn``), and every fracture is then a
chain of mesh edges.

Rules, applied in this order (each event is recorded in :class:`CleanReport`):

1. ``clipped``: fractures are clipped to the domain; a fracture entirely outside is
   ``outside``; a fracture leaving and re-entering a non-convex domain becomes several
   pieces.
2. ``short``: a piece shorter than ``tol`` after clipping is dropped.
3. ``on_boundary``: a piece lying within ``tol`` of the domain boundary along its whole
   length is dropped (the boundary already is a mesh line there).
4. ``duplicate``: a piece whose two endpoints both lie within ``tol`` of another piece's
   endpoints is dropped; the piece of the lower fracture number is kept.
5. ``merged``: near-parallel pieces closer than ``tol``: when the shorter piece lies
   within ``tol`` of the longer one's line along its whole length and the two overlap or
   leave a gap below ``tol`` along that line, both are replaced by one piece on the
   longer one's line spanning both (the longer fracture keeps it, the shorter is merged
   into it). Repeated until no such pair is left.
6. Planar arrangement, repeated until nothing changes (at most ``max_passes``):

   - ``boundary_snap``: an endpoint within ``tol`` of the boundary moves onto it (onto a
     corner when within ``tol`` of one), so the fracture touches the boundary;
   - ``tee_snap``: an endpoint within ``tol`` of the interior of another edge moves onto
     that edge (T-junction); the other edge is split there;
   - crossings (X-junctions) split both edges at the intersection point;
   - ``vertex_merge``: vertices closer than ``tol`` (near-coincident endpoints, junctions
     close together) become one vertex, placed at the most constrained of them (domain
     corner, then a boundary vertex, then a crossing, then an endpoint);
   - ``overlap``: an edge shared by two fractures after the moves above is kept once, by
     the lower fracture number.

A fracture that no rule moved keeps its clipped geometry exactly: its edges are the
pieces of its clipped segment split at junctions, so the total length is the clipped
length to round-off. ``CleanNetwork.modified`` says which fractures were moved and by
how much.
"""

from __future__ import annotations

import itertools
from collections import defaultdict
from dataclasses import dataclass, field

import numpy as np

from geofrac.dfn.errors import DfnError
from geofrac.dfn.polygon import clip_segments, nearest_boundary_point, point_segment_distance
from geofrac.dfn.sampling import Network

__all__ = [
    "RULES",
    "CleanNetwork",
    "CleanReport",
    "box_pairs",
    "clean_network",
]

#: Rule names in the order they are applied (docs/dfn.md explains each).
RULES = (
    "outside",
    "clipped",
    "short",
    "on_boundary",
    "duplicate",
    "merged",
    "boundary_snap",
    "tee_snap",
    "vertex_merge",
    "overlap",
)

# Vertex kinds, most constrained first: a merged cluster sits at its lowest kind.
_CORNER, _BOUNDARY, _CROSSING, _ENDPOINT = 0, 1, 2, 3
#: ``moved`` value of a fracture whose extent changed but whose points did not move.
_TOUCHED = 1e-300


@dataclass
class CleanReport:
    """What the cleaning did.

    Attributes:
        events: rule name -> list of (fracture, other fracture or -1, distance moved or
            length dropped). ``other`` is the fracture kept (``duplicate``), merged into
            (``merged``), snapped onto (``tee_snap``) or sharing the edge (``overlap``).
        crossings: number of X-junctions (edges crossing) found.
        tees: number of T-junctions (an endpoint on another edge, snapped or exact).
        passes: arrangement passes until nothing changed.
    """

    events: dict[str, list[tuple[int, int, float]]] = field(
        default_factory=lambda: {r: [] for r in RULES}
    )
    crossings: int = 0
    tees: int = 0
    passes: int = 0

    def add(
        self,
        rule: str,
        fracture: int | np.integer,
        other: int | np.integer = -1,
        *,
        amount: float = 0.0,
    ) -> None:
        """Record one event of ``rule``."""
        self.events[rule].append((int(fracture), int(other), float(amount)))

    def counts(self) -> dict[str, int]:
        """Number of events per rule, plus ``crossings``, ``tees`` and ``passes``."""
        out = {r: len(v) for r, v in self.events.items()}
        return out | {"crossings": self.crossings, "tees": self.tees, "passes": self.passes}

    def summary(self) -> str:
        """One line: the non-zero counts."""
        parts = [f"{k} {v}" for k, v in self.counts().items() if v]
        return ", ".join(parts) if parts else "nothing to clean"


@dataclass(frozen=True)
class CleanNetwork:
    """A fracture network as a planar straight-line graph inside the domain.

    Attributes:
        vertices: vertex coordinates, shape=(num_vertices, 2).
        edges: vertex indices of each edge, shape=(num_edges, 2).
        edge_fracture: fracture number (row of the input network) of each edge,
            shape=(num_edges,).
        on_boundary: whether each vertex lies on the domain boundary, shape=(num_vertices,).
        domain: the domain polygon, counter-clockwise, shape=(num_corners, 2).
        network: the input network (fracture numbers are its rows).
        clipped_length: length of each input fracture inside the domain,
            shape=(num_fractures,).
        moved: largest distance a rule moved a point of each fracture (0 when untouched;
            inf when dropped or merged away; 1e-300 when only its extent changed: it
            absorbed a merged fracture or lost an edge to ``overlap`` or ``on_boundary``),
            shape=(num_fractures,).
        tol: the tolerance used.
        report: the events.
        constraints: fixed lines inside the domain that the cleaning treated like the
            boundary (region outlines, :mod:`geofrac.dfn.regions`); fractures crossing
            them are split there, shape=(num_constraints, 2, 2).
    """

    vertices: np.ndarray
    edges: np.ndarray
    edge_fracture: np.ndarray
    on_boundary: np.ndarray
    domain: np.ndarray
    network: Network
    clipped_length: np.ndarray
    moved: np.ndarray
    tol: float
    report: CleanReport
    constraints: np.ndarray = field(default_factory=lambda: np.zeros((0, 2, 2)))

    @property
    def edge_length(self) -> np.ndarray:
        """Length of each edge, shape=(num_edges,)."""
        d = self.vertices[self.edges[:, 1]] - self.vertices[self.edges[:, 0]]
        return np.hypot(d[:, 0], d[:, 1])

    @property
    def length(self) -> np.ndarray:
        """Total edge length of each input fracture, shape=(num_fractures,)."""
        return np.bincount(
            self.edge_fracture, weights=self.edge_length, minlength=len(self.clipped_length)
        )

    @property
    def modified(self) -> np.ndarray:
        """Whether a rule moved, merged or dropped each fracture, shape=(num_fractures,)."""
        return self.moved > 0.0

    @property
    def segments(self) -> np.ndarray:
        """Edge endpoints, shape=(num_edges, 2, 2)."""
        return self.vertices[self.edges]

    def min_junction_angle(self) -> float:
        """Smallest angle between two lines meeting at a vertex, in degrees.

        Lines are the network edges and, at vertices on the boundary, the two boundary
        directions. A triangle mesh that follows the network has no angle larger than
        this at that vertex, so it bounds the mesh's minimum angle (180 when no two lines
        meet).
        """
        if len(self.edges) == 0:
            return 180.0
        a, b = self.edges[:, 0], self.edges[:, 1]
        d = self.vertices[b] - self.vertices[a]
        vert = np.concatenate([a, b])
        theta = np.concatenate([np.arctan2(d[:, 1], d[:, 0]), np.arctan2(-d[:, 1], -d[:, 0])])
        on = np.flatnonzero(self.on_boundary)
        if len(on):
            _, side, _, _ = nearest_boundary_point(self.vertices[on], self.domain)
            t = self.domain[(side + 1) % len(self.domain)] - self.domain[side]
            along = np.arctan2(t[:, 1], t[:, 0])
            vert = np.concatenate([vert, on, on])
            theta = np.concatenate([theta, along, along + np.pi])
        more_vert, more_theta = self._constraint_directions()
        vert, theta = np.concatenate([vert, more_vert]), np.concatenate([theta, more_theta])
        theta = np.mod(theta, 2 * np.pi)
        order = np.lexsort((theta, vert))
        vert, theta = vert[order], theta[order]
        gap = np.diff(theta)
        same = vert[1:] == vert[:-1]
        gaps = [gap[same]]
        # wrap-around gap of each vertex with at least two lines
        first = np.flatnonzero(np.r_[True, ~same])
        last = np.r_[first[1:] - 1, len(vert) - 1]
        many = last > first
        gaps.append(2 * np.pi - (theta[last[many]] - theta[first[many]]))
        smallest = np.concatenate(gaps)
        return float(np.degrees(smallest.min())) if smallest.size else 180.0

    def _constraint_directions(self) -> tuple[np.ndarray, np.ndarray]:
        """(vertex, direction angle) of the constraint lines leaving each vertex on one.

        A vertex inside a constraint segment sees both of its directions, a vertex at its
        end only the one into it. Shapes (k,) each.
        """
        if len(self.constraints) == 0 or len(self.vertices) == 0:
            return np.zeros(0, dtype=np.int64), np.zeros(0)
        a, b = self.constraints[:, 0], self.constraints[:, 1]
        d, t = point_segment_distance(self.vertices[:, None, :], a[None], b[None])
        eps = 1e-12 * float(np.ptp(self.domain, axis=0).max())
        v, c = np.nonzero(d <= eps)
        length = np.hypot(*(b - a).T)[c]
        t = t[v, c]
        fwd = np.arctan2(*(b - a)[c][:, ::-1].T)
        toward_a = t * length > eps
        toward_b = (1 - t) * length > eps
        vert = np.concatenate([v[toward_b], v[toward_a]])
        theta = np.concatenate([fwd[toward_b], fwd[toward_a] + np.pi])
        return vert, theta


# ----------------------------------------------------------------------------- geometry


def box_pairs(
    boxes_a: np.ndarray, boxes_b: np.ndarray | None = None, pad: float = 0.0
) -> tuple[np.ndarray, np.ndarray]:
    """Pairs of axis-aligned boxes that overlap after growing each by ``pad``.

    Sweep over x, then filter on y; output sorted by (i, j).

    Args:
        boxes_a: (xmin, ymin, xmax, ymax) rows, shape=(n, 4).
        boxes_b: a second set, shape=(m, 4); None pairs ``boxes_a`` with itself (i < j).
        pad: growth of each box on every side.

    Returns:
        (i, j) index arrays, each shape=(num_pairs,).
    """
    self_pairs = boxes_b is None
    b = boxes_a if boxes_b is None else boxes_b
    if len(boxes_a) == 0 or len(b) == 0:
        return np.zeros(0, dtype=np.int64), np.zeros(0, dtype=np.int64)
    order = np.argsort(b[:, 0], kind="stable")
    xs = b[order, 0]
    widest = float((b[:, 2] - b[:, 0]).max())
    lo = np.searchsorted(xs, boxes_a[:, 0] - widest - 2 * pad, side="left")
    hi = np.searchsorted(xs, boxes_a[:, 2] + 2 * pad, side="right")
    counts = hi - lo
    i = np.repeat(np.arange(len(boxes_a)), counts)
    start = np.repeat(np.cumsum(counts) - counts, counts)
    j = order[np.arange(len(i)) - start + np.repeat(lo, counts)]
    keep = (
        (b[j, 2] + 2 * pad >= boxes_a[i, 0])
        & (b[j, 1] <= boxes_a[i, 3] + 2 * pad)
        & (b[j, 3] + 2 * pad >= boxes_a[i, 1])
    )
    if self_pairs:
        keep &= i < j
    i, j = i[keep], j[keep]
    key = np.lexsort((j, i))
    return i[key], j[key]


def _boxes(segments: np.ndarray) -> np.ndarray:
    return np.hstack([segments.min(axis=1), segments.max(axis=1)])


def _cross(u: np.ndarray, v: np.ndarray) -> np.ndarray:
    return u[..., 0] * v[..., 1] - u[..., 1] * v[..., 0]


def _interior_crossings(
    a: np.ndarray, b: np.ndarray, eps: float
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Which segments a[k] and b[k] cross at interior points, and where.

    Args:
        a: the first segment of each pair, shape=(k, 2, 2) (pair, endpoint, xy).
        b: the second segment of each pair, shape=(k, 2, 2).
        eps: the least distance of the crossing from either segment's ends.

    Returns:
        (hit, shape=(k,) bool; t, u: the crossing's parameters along a and b, shape=(k,)).
        Parallel pairs (|a × b| ≤ 1e-14 |a| |b|) never hit.
    """
    a0, b0 = a[:, 0], b[:, 0]
    r, s = a[:, 1] - a0, b[:, 1] - b0
    den = _cross(r, s)
    ok = np.abs(den) > 1e-14 * np.hypot(*r.T) * np.hypot(*s.T)
    den = np.where(ok, den, 1.0)
    t = _cross(b0 - a0, s) / den
    u = _cross(b0 - a0, r) / den
    la, lb = np.hypot(*r.T), np.hypot(*s.T)
    hit = ok & (t * la > eps) & ((1 - t) * la > eps) & (u * lb > eps) & ((1 - u) * lb > eps)
    return hit, t, u


class _Fixed:
    """Lines the cleaning cannot move: the domain's sides, then the constraint segments.

    Attributes:
        domain: the domain polygon, shape=(m, 2).
        a, b: segment ends, each shape=(k, 2); the first ``len(domain)`` are the sides.
        corners: fixed points (the domain's corners, then the constraints' ends),
            shape=(c, 2).
        constraints: the constraint segments, shape=(n, 2, 2).
    """

    def __init__(self, domain: np.ndarray, constraints: np.ndarray) -> None:
        self.domain, self.constraints = domain, constraints
        self.a = np.vstack([domain, constraints[:, 0]])
        self.b = np.vstack([np.roll(domain, -1, axis=0), constraints[:, 1]])
        ends = constraints.reshape(-1, 2)
        if len(ends):
            ends = np.unique(ends, axis=0)
        self.corners = np.vstack([domain, ends])

    def nearest(self, points: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(distance, segment, closest point) of each point, shapes (n,), (n,), (n, 2).

        Without constraints, the same numbers as
        :func:`~geofrac.dfn.polygon.nearest_boundary_point` on the domain.
        """
        d, t = point_segment_distance(points[:, None, :], self.a[None], self.b[None])
        side = np.argmin(d, axis=1)
        rows = np.arange(len(points))
        ts = t[rows, side]
        closest = self.a[side] + ts[:, None] * (self.b[side] - self.a[side])
        return d[rows, side], side, closest


# ----------------------------------------------------------------------- piece rules


def _initial_pieces(
    network: Network, fixed: _Fixed, tol: float, report: CleanReport
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Rules 1-3: clip, drop short pieces and pieces along the boundary (or a constraint)."""
    domain = fixed.domain
    n = len(network)
    pieces, parent = clip_segments(network.segments, domain)
    lengths = np.hypot(*(pieces[:, 1] - pieces[:, 0]).T) if len(pieces) else np.zeros(0)
    clipped = np.bincount(parent, weights=lengths, minlength=n)
    inside_full = np.isclose(clipped, network.lengths, rtol=1e-12, atol=0.0)
    for f in np.flatnonzero(clipped == 0.0):
        report.add("outside", f, amount=float(network.lengths[f]))
    for f in np.flatnonzero((clipped > 0.0) & ~inside_full):
        report.add("clipped", f, amount=float(network.lengths[f] - clipped[f]))
    keep = lengths >= tol
    for k in np.flatnonzero(~keep):
        report.add("short", parent[k], amount=float(lengths[k]))
    pieces, parent = pieces[keep], parent[keep]
    if len(pieces):
        samples = np.linspace(0.0, 1.0, 5)
        pts = (
            pieces[:, 0, None, :]
            + samples[None, :, None] * (pieces[:, 1] - pieces[:, 0])[:, None, :]
        )
        d, side, _ = fixed.nearest(pts.reshape(-1, 2))
        d, side = d.reshape(-1, 5), side.reshape(-1, 5)
        along = (d.max(axis=1) < tol) & (side == side[:, :1]).all(axis=1)
        for k in np.flatnonzero(along):
            report.add("on_boundary", parent[k], amount=float(lengths[keep][k]))
        pieces, parent = pieces[~along], parent[~along]
    return pieces, parent, clipped


def _drop_duplicates(
    pieces: np.ndarray, parent: np.ndarray, tol: float, report: CleanReport
) -> tuple[np.ndarray, np.ndarray]:
    """Rule 4: both endpoints within ``tol`` of another piece's endpoints."""
    i, j = box_pairs(_boxes(pieces), pad=tol)
    same = np.minimum(
        np.maximum(
            np.hypot(*(pieces[i, 0] - pieces[j, 0]).T), np.hypot(*(pieces[i, 1] - pieces[j, 1]).T)
        ),
        np.maximum(
            np.hypot(*(pieces[i, 0] - pieces[j, 1]).T), np.hypot(*(pieces[i, 1] - pieces[j, 0]).T)
        ),
    )
    dropped = np.zeros(len(pieces), dtype=bool)
    for a, b, d in zip(i[same < tol], j[same < tol], same[same < tol], strict=True):
        if dropped[a] or dropped[b]:
            continue
        keep, drop = (a, b) if (parent[a], a) < (parent[b], b) else (b, a)
        dropped[drop] = True
        report.add("duplicate", parent[drop], parent[keep], amount=float(d))
    return pieces[~dropped], parent[~dropped]


def _merge_parallel(
    pieces: np.ndarray, parent: np.ndarray, tol: float, report: CleanReport
) -> tuple[np.ndarray, np.ndarray]:
    """Rule 5: merge near-parallel pieces closer than ``tol`` onto the longer one's line."""
    pieces = pieces.copy()
    alive = np.ones(len(pieces), dtype=bool)
    changed = True
    while changed:
        changed = False
        idx = np.flatnonzero(alive)
        i, j = box_pairs(_boxes(pieces[idx]), pad=tol)
        i, j = idx[i], idx[j]
        hits = _parallel_close(pieces[i], pieces[j], tol)
        for a, b in zip(i[hits], j[hits], strict=True):
            if not (alive[a] and alive[b]) or not _parallel_close(pieces[[a]], pieces[[b]], tol)[0]:
                continue  # an earlier merge in this sweep changed one of them
            la = np.hypot(*(pieces[a, 1] - pieces[a, 0]))
            lb = np.hypot(*(pieces[b, 1] - pieces[b, 0]))
            long, short = (a, b) if (la, -parent[a]) >= (lb, -parent[b]) else (b, a)
            length = max(la, lb)
            p0 = pieces[long, 0]
            direction = (pieces[long, 1] - p0) / length
            rel = pieces[short] - p0
            s = rel @ direction
            lo, hi = min(0.0, s.min()), max(length, s.max())
            pieces[long] = [p0 + lo * direction, p0 + hi * direction]
            alive[short] = False
            report.add(
                "merged",
                parent[short],
                parent[long],
                amount=float(np.abs(_cross(direction, rel)).max()),
            )
            changed = True
    return pieces[alive], parent[alive]


def _parallel_close(a: np.ndarray, b: np.ndarray, tol: float) -> np.ndarray:
    """Rule 5 test for segment pairs ``a``, ``b``, each shape=(n, 2, 2).

    True where the shorter lies within ``tol`` of the longer one's line and their extents
    along it overlap or leave a gap below ``tol``; shape=(n,).
    """
    la = np.hypot(*(a[:, 1] - a[:, 0]).T)
    lb = np.hypot(*(b[:, 1] - b[:, 0]).T)
    swap = lb > la
    long = np.where(swap[:, None, None], b, a)
    short = np.where(swap[:, None, None], a, b)
    length = np.maximum(la, lb)
    direction = (long[:, 1] - long[:, 0]) / length[:, None]
    rel = short - long[:, :1]
    offset = np.abs(_cross(direction[:, None, :], rel)).max(axis=1)
    s = np.einsum("nki,ni->nk", rel, direction)
    return (offset < tol) & (s.min(axis=1) <= length + tol) & (s.max(axis=1) >= -tol)


# ---------------------------------------------------------------------- arrangement


def _cluster(points: np.ndarray, kinds: np.ndarray, tol: float) -> np.ndarray:
    """Representative of each point after merging points closer than ``tol``.

    Clusters are the connected components of the close pairs
    (``scipy.sparse.csgraph.connected_components``; boolean weights, so a repeated pair
    cannot sum to zero); the representative is the cluster member of lowest
    (kind, index). Returns shape=(n,) indices into ``points``.
    """
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    n = len(points)
    i, j = box_pairs(np.hstack([points, points]), pad=tol)
    close = np.hypot(*(points[i] - points[j]).T) < tol
    graph = coo_matrix((np.ones(int(close.sum()), dtype=bool), (i[close], j[close])), (n, n))
    groups = connected_components(graph.tocsr(), directed=False)[1]  # labels in [0, n)
    order = np.lexsort((np.arange(n), kinds, groups))
    first = np.ones(n, dtype=bool)
    first[1:] = groups[order][1:] != groups[order][:-1]
    best = np.empty(n, dtype=np.int64)
    best[groups[order][first]] = order[first]
    return best[groups]


class _Pass:
    """State of one arrangement pass over segments ``segs`` of fractures ``fid``."""

    def __init__(
        self,
        segs: np.ndarray,
        fid: np.ndarray,
        fixed: _Fixed,
        *,
        tol: float,
        report: CleanReport,
        moved: np.ndarray,
        count_junctions: bool,
    ) -> None:
        self.segs, self.fid, self.fixed, self.tol = segs, fid, fixed, tol
        self.report, self.moved, self.count = report, moved, count_junctions
        self.exact = 1e-12 * float(np.ptp(fixed.domain, axis=0).max())
        self.changed = False
        m = len(segs)
        self.ends = segs.reshape(-1, 2).copy()  # endpoint k belongs to segment k // 2
        self.end_kind = np.full(2 * m, _ENDPOINT)
        self.crossings: list[np.ndarray] = []
        self.crossing_kind: list[int] = []  # _CROSSING, or _BOUNDARY on a constraint
        # segment -> vertices on its interior: ("end", k) or ("cross", c)
        self.on_seg: dict[int, list[tuple[str, int]]] = defaultdict(list)
        self.tee_pairs: set[tuple[int, int]] = set()  # (segment of the endpoint, target)

    def run(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, bool]:
        """The pass: returns (vertices, edges, edge fracture, whether anything changed)."""
        self.snap_to_boundary()
        i, j = box_pairs(_boxes(self.segs), pad=self.tol)
        if len(i):
            self.snap_tees(i, j)
        self.snap_tees_on_fixed_corners()
        if len(i):
            self.split_crossings(i, j)
        if len(self.fixed.constraints):
            self.split_constraint_crossings()
        vertices, edges, fids = self.build()
        return vertices, edges, fids, self.changed

    def move(self, f: int, distance: float, rule: str, *, other: int = -1) -> None:
        if distance > self.exact:
            self.report.add(rule, f, other, amount=distance)
            self.moved[f] = max(self.moved[f], distance)
            self.changed = True

    def snap_to_boundary(self) -> None:
        """boundary_snap: endpoints within tol of the boundary move onto it."""
        dist, _, proj = self.fixed.nearest(self.ends)
        corners = self.fixed.corners
        to_corner = np.hypot(*(self.ends[:, None, :] - corners[None]).transpose(2, 0, 1))
        for k in np.flatnonzero(dist < self.tol):
            corner = np.flatnonzero(to_corner[k] < self.tol)
            target = corners[corner[0]] if len(corner) else proj[k]
            self.move(self.fid[k // 2], float(np.hypot(*(target - self.ends[k]))), "boundary_snap")
            self.ends[k] = target
            self.end_kind[k] = _CORNER if len(corner) else _BOUNDARY

    def snap_tees(self, i: np.ndarray, j: np.ndarray) -> None:
        """tee_snap: a vertex within tol of the interior of another segment.

        A free endpoint moves onto the nearest such segment, which is split there. An
        endpoint on the boundary cannot leave it, so the segment is bent through it
        instead (the segment's fracture moves by less than tol).
        """
        segs, tol = self.segs, self.tol
        length = np.hypot(*(segs[:, 1] - segs[:, 0]).T)
        best: dict[int, tuple[float, int, float]] = {}
        for src, dst in ((i, j), (j, i)):
            for e in (0, 1):
                k = 2 * src + e
                d, t = point_segment_distance(self.ends[k], segs[dst, 0], segs[dst, 1])
                hit = (d < tol) & (t * length[dst] > self.exact)
                hit &= (1 - t) * length[dst] > self.exact
                for kk, s, dd, tt in zip(k[hit], dst[hit], d[hit], t[hit], strict=True):
                    if self.end_kind[kk] != _ENDPOINT:
                        self._bend(int(s), ("end", int(kk)), float(dd))
                    elif int(kk) not in best or dd < best[int(kk)][0]:
                        best[int(kk)] = (float(dd), int(s), float(tt))
        for kk, (dd, s, tt) in sorted(best.items()):
            target = segs[s, 0] + tt * (segs[s, 1] - segs[s, 0])
            self.move(self.fid[kk // 2], dd, "tee_snap", other=int(self.fid[s]))
            self.ends[kk] = target
            self.on_seg[s].append(("end", kk))
            self.tee_pairs.add((kk // 2, s))
            if self.count:
                self.report.tees += 1

    def snap_tees_on_fixed_corners(self) -> None:
        """tee_snap: a segment passing within tol of a domain (or constraint) corner bends."""
        segs, tol = self.segs, self.tol
        length = np.hypot(*(segs[:, 1] - segs[:, 0]).T)
        corners = self.fixed.corners
        c, s_idx = box_pairs(np.hstack([corners, corners]), _boxes(segs), pad=tol)
        d, t = point_segment_distance(corners[c], segs[s_idx, 0], segs[s_idx, 1])
        hit = (d < tol) & (t * length[s_idx] > self.exact) & ((1 - t) * length[s_idx] > self.exact)
        for corner, s, dd in zip(c[hit], s_idx[hit], d[hit], strict=True):
            self._bend(int(s), ("corner", int(corner)), float(dd))

    def _bend(self, s: int, ref: tuple[str, int], distance: float) -> None:
        """Split segment ``s`` at a vertex that cannot move (it bends through it)."""
        if ref in self.on_seg[s]:
            return
        self.on_seg[s].append(ref)
        self.move(self.fid[s], distance, "tee_snap")
        if distance <= self.exact:
            self.changed = True  # an exact T on a boundary vertex still splits

    def split_crossings(self, i: np.ndarray, j: np.ndarray) -> None:
        """X-junctions: proper intersections split both segments."""
        segs = self.segs
        # shared endpoints give t = 1 - 1e-16, not a crossing: self.exact
        hit, t, _ = _interior_crossings(segs[i], segs[j], self.exact)
        for a, b, tt in zip(i[hit], j[hit], t[hit], strict=True):
            if (int(a), int(b)) in self.tee_pairs or (int(b), int(a)) in self.tee_pairs:
                continue  # an endpoint overshooting the other edge by < tol: the tee cut it
            c = len(self.crossings)
            self.crossings.append(segs[a, 0] + tt * (segs[a, 1] - segs[a, 0]))
            self.crossing_kind.append(_CROSSING)
            self.on_seg[int(a)].append(("cross", c))
            self.on_seg[int(b)].append(("cross", c))
            self.changed = True
            if self.count:
                self.report.crossings += 1

    def split_constraint_crossings(self) -> None:
        """A segment crossing a constraint line is split there (a boundary vertex).

        Crossings within tol of the constraint's ends are left to the corner bend.
        """
        segs, cons = self.segs, self.fixed.constraints
        i, j = box_pairs(_boxes(segs), _boxes(cons), pad=self.tol)
        hit, _, u = _interior_crossings(segs[i], cons[j], self.exact)
        for a, b, uu in zip(i[hit], j[hit], u[hit], strict=True):
            c = len(self.crossings)
            self.crossings.append(cons[b, 0] + uu * (cons[b, 1] - cons[b, 0]))
            self.crossing_kind.append(_BOUNDARY)
            self.on_seg[int(a)].append(("cross", c))
            self.changed = True

    def build(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Merge close vertices, split segments at their vertices, drop repeated edges."""
        corners = self.fixed.corners
        m, nc, ncr = len(self.segs), len(corners), len(self.crossings)
        points = np.vstack([corners, *self.crossings, self.ends]) if m else corners
        kinds = np.concatenate(
            [np.full(nc, _CORNER), np.array(self.crossing_kind, dtype=np.int64), self.end_kind]
        ).astype(np.int64)
        orig = points.copy()
        if ncr:  # boundary_snap for crossings: a junction within tol of the boundary
            crossing = slice(nc, nc + ncr)
            dist, _, proj = self.fixed.nearest(points[crossing])
            near = dist < self.tol
            points[crossing][near] = proj[near]
            kinds[crossing][near] = _BOUNDARY
        rep = _cluster(points, kinds, self.tol)
        step = np.hypot(*(orig - points[rep]).T)
        base = nc + ncr

        def vid(ref: tuple[str, int]) -> int:
            offset = {"end": base, "cross": nc, "corner": 0}[ref[0]]
            return offset + ref[1]

        for k in range(2 * m):
            self.move(self.fid[k // 2], float(step[base + k]), "vertex_merge")
        for s, refs in self.on_seg.items():
            # a junction that moved off the segment's line bends the segment
            p0, p1 = self.segs[s]
            d = (p1 - p0) / np.hypot(*(p1 - p0))
            off = np.abs(_cross(d[None], points[rep[[vid(r) for r in refs]]] - p0))
            self.move(self.fid[s], float(off.max()), "vertex_merge")
        edges: list[tuple[int, int]] = []
        edge_fid: list[int] = []
        for s in range(m):
            ids = np.array([base + 2 * s, base + 2 * s + 1] + [vid(r) for r in self.on_seg[s]])
            p0, p1 = self.segs[s]
            d = p1 - p0
            par = (orig[ids] - p0) @ d / (d @ d)
            chain = rep[ids[np.argsort(par, kind="stable")]]
            for a, b in itertools.pairwise(chain):
                if a == b:
                    continue
                if kinds[a] <= _BOUNDARY and kinds[b] <= _BOUNDARY:
                    mid = 0.5 * (points[a] + points[b])
                    if self.fixed.nearest(mid[None])[0][0] < self.tol:
                        f = int(self.fid[s])  # on_boundary: the edge runs along the boundary
                        self.report.add(
                            "on_boundary", f, amount=float(np.hypot(*(points[b] - points[a])))
                        )
                        self.moved[f] = max(self.moved[f], _TOUCHED)
                        self.changed = True
                        continue
                edges.append((int(a), int(b)))
                edge_fid.append(int(self.fid[s]))
        seen: dict[tuple[int, int], int] = {}
        for e, (a, b) in enumerate(edges):
            key = (min(a, b), max(a, b))
            if key in seen:
                f, other = edge_fid[e], edge_fid[seen[key]]
                self.report.add("overlap", f, other)
                self.moved[f] = max(self.moved[f], _TOUCHED)
                self.changed = True
            else:
                seen[key] = e
        chosen = np.array(sorted(seen.values()), dtype=np.int64)
        edge_arr = np.array(edges, dtype=np.int64).reshape(-1, 2)[chosen]
        used, inverse = np.unique(edge_arr, return_inverse=True)
        return points[used], inverse.reshape(-1, 2), np.array(edge_fid, dtype=np.int64)[chosen]


def clean_network(
    network: Network,
    domain: np.ndarray,
    tol: float,
    *,
    max_passes: int = 8,
    constraints: np.ndarray | None = None,
) -> CleanNetwork:
    """Apply the rules of this module and return the planar graph.

    Args:
        network: the fractures (any may lie partly or wholly outside ``domain``).
        domain: counter-clockwise simple polygon, shape=(num_corners, 2).
        tol: tolerance (length): pieces shorter than this are dropped, points closer than
            this are merged or snapped.
        max_passes: arrangement passes before giving up.
        constraints: fixed segments inside the domain (region outlines), shape=(k, 2, 2),
            whose ends keep at least ``tol`` apart and from the other segments. The rules
            treat them as the boundary: a fracture crossing one is split at the crossing
            (not moved; it stays a fracture on both sides), endpoints and junctions within
            ``tol`` of one snap onto it (onto its ends when within ``tol`` of them), a
            fracture passing within ``tol`` of an end bends through it, and a piece along
            one is dropped.

    Raises:
        DfnError: ``tol`` is not positive, or the arrangement did not settle.
    """
    if not (np.isfinite(tol) and tol > 0):
        raise DfnError(f"tolerance must be a positive length, got {tol!r}")
    domain = np.asarray(domain, dtype=float)
    cons = np.zeros((0, 2, 2)) if constraints is None else np.asarray(constraints, dtype=float)
    fixed = _Fixed(domain, cons.reshape(-1, 2, 2))
    report = CleanReport()
    n = len(network)
    pieces, parent, clipped = _initial_pieces(network, fixed, tol, report)
    if len(pieces):
        pieces, parent = _drop_duplicates(pieces, parent, tol, report)
        pieces, parent = _merge_parallel(pieces, parent, tol, report)
    moved = np.zeros(n)
    for rule in ("short", "on_boundary", "duplicate", "merged"):
        for f, _, d in report.events[rule]:
            moved[f] = max(moved[f], d if np.any(parent == f) else np.inf)
    moved[clipped == 0.0] = np.inf
    kept = np.bincount(parent, weights=np.hypot(*(pieces[:, 1] - pieces[:, 0]).T), minlength=n)
    grown = kept > clipped * (1 + 1e-12)  # a fracture that absorbed a merged one
    moved[grown] = np.maximum(moved[grown], _TOUCHED)
    vertices = np.zeros((0, 2))
    edges = np.zeros((0, 2), dtype=np.int64)
    fids = np.zeros(0, dtype=np.int64)
    segs, fid = pieces, parent
    changed = len(segs) > 0
    while changed:
        if report.passes == max_passes:
            raise DfnError(
                f"the fracture network did not settle after {max_passes} cleaning passes "
                f"with tolerance {tol:g}; try a larger tolerance"
            )
        vertices, edges, fids, changed = _Pass(
            segs,
            fid,
            fixed,
            tol=tol,
            report=report,
            moved=moved,
            count_junctions=report.passes == 0,
        ).run()
        report.passes += 1
        segs, fid = vertices[edges], fids
    scale = float(np.ptp(domain, axis=0).max())
    on_boundary = (
        nearest_boundary_point(vertices, domain)[0] <= 1e-12 * scale
        if len(vertices)
        else np.zeros(0, dtype=bool)
    )
    return CleanNetwork(
        vertices=vertices,
        edges=edges,
        edge_fracture=fids,
        on_boundary=on_boundary,
        domain=domain,
        network=network,
        clipped_length=clipped,
        moved=moved,
        tol=float(tol),
        report=report,
        constraints=fixed.constraints,
    )
