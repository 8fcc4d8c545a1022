"""Crack state of a grain mosaic: cracked grain interfaces and C-MultiMLSM node fields.

Edo (2016), §3.3 (Fig. 3.4-3.8). The grains are EFMM's integration domains
(:func:`geofrac.elements.efmm_numpy.integration_domains`): node i's grain is the union of
its quadrilaterals (i, X_ij, p_T, X_ik) in the triangles T around it. Each mesh edge ij
owns one *interface*, the boundary between the grains of i and j: the polyline
p_T1 – X_ij – p_T2 through the inner points of the edge's two triangles (one segment
p_T – X_ij on a boundary edge, where X_ij is the edge midpoint). Crack sites are
therefore numbered like the edges (:class:`~geofrac.fracture.topology.EdgeMesh`), so the
chapter-2 event loop, criterion and tie-break serve both.

A node with a cracked interface (§3.3.2) drops its EFMM field and takes the
C-MultiMLSM field of :mod:`geofrac.mls.cmulti` through its *visible* satellites: a node j
is visible from node i when the segment x_i – x_j touches no cracked interface
(:mod:`geofrac.fracture.visibility`, the same closed-segment test as chapter 2) and runs
inside the body: it crosses no boundary edge, and when both nodes lie on the boundary its
midpoint lies in the mesh (so a node does not see across a notch slot or a hole). The
influence radius is set per node and per crack state (3.3.2(d)): the search grows from
1.5 x the node's longest edge until ``neighbours`` satellites are visible or
``max_radius_factor`` x that edge is reached, and h = ``margin`` x the distance of the
``neighbours``-th satellite; the field's order then follows the number of satellites
inside h (>= 10 quadratic, 4-9 linear, 1-3 rotation only, none: a fragment).

Which nodes switch (``switch``): Edo (2016) switches "the nodes that have a cracked
interface" because EFMM's displacement is continuous over the node's patch and cannot
represent the crack (3.3.2). An interface also crosses the two triangles of its edge, and
so the patches of their third vertices: with ``"grain"`` (the literal rule) those nodes
keep EFMM, their CST strains tie the two faces of the crack together and a crack never
opens (docs/granular.md shows the beam cracking diffusely that way). ``"patch"`` (the
default) also switches the vertices of the triangles a cracked interface crosses, so that
no EFMM patch contains a crack.

Pure numpy and identical on every rank (the driver replicates it).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from geofrac.elements.efmm_numpy import Domains
from geofrac.fracture.state import Mapper, MlsSettings, segment_distance, serial_map
from geofrac.fracture.topology import EdgeMesh, components
from geofrac.fracture.visibility import Bins, PointIndex, blocked, orient, visible_nodes
from geofrac.mls.cmulti import NodeFit, node_fit

__all__ = ["GrainState", "Interfaces", "connected_cracks", "interfaces", "side_sites"]


@dataclass(frozen=True)
class Interfaces:
    """The grain interfaces of a triangle mesh, one per edge.

    Attributes:
        centre: the interface's centre X_ij (on edge ij), shape=(num_edges, 2).
        point: where its σ1 is evaluated (Edo (2016), §3.3.1, "the central part of the grain
            interface"): X_ij for an interior interface p_T1–X–p_T2, the middle of
            p_T–X for a boundary one (X lies on the boundary), shape=(num_edges, 2).
        segments: its two segments p_T1–X and X–p_T2 (a boundary edge repeats p_T–X),
            shape=(num_edges, 2, 2, 2): [edge, segment, end, xy].
        normal: unit normal of the interface's chord p_T1 → p_T2 (p_T → X on a boundary
            edge), the direction in which the interface opens, shape=(num_edges, 2).
        grain_offsets: CSR offsets of each node's sub-triangles, shape=(num_nodes + 1,).
        grain_order: the domains' sub-triangles grouped by node (indices into the
            :class:`~geofrac.elements.efmm_numpy.Domains`), shape=(num_sub,).
        grain_subs: sub-triangle corners grouped by node, shape=(num_sub, 3, 2).
    """

    centre: np.ndarray
    point: np.ndarray
    segments: np.ndarray
    normal: np.ndarray
    grain_offsets: np.ndarray
    grain_order: np.ndarray
    grain_subs: np.ndarray

    def grain(self, node: int) -> np.ndarray:
        """The sub-triangles of a node's grain, shape=(s, 3, 2)."""
        return self.grain_subs[self.grain_offsets[node] : self.grain_offsets[node + 1]]

    def polylines(self, edges: np.ndarray) -> np.ndarray:
        """Segments of the interfaces of ``edges``, shape=(2 len(edges), 2, 2)."""
        return self.segments[np.asarray(edges, dtype=np.int64)].reshape(-1, 2, 2)


def interfaces(mesh: EdgeMesh, domains: Domains) -> Interfaces:
    """The interfaces of the domains of :func:`integration_domains` on the same mesh.

    Args:
        mesh: the triangle mesh with edges (the same node and cell numbering).
        domains: the integration domains.
    """
    n = len(mesh.coords)
    tri = domains.triangles
    a, b = tri.ravel(), np.roll(tri, -1, axis=1).ravel()
    key = np.minimum(a, b) * n + np.maximum(a, b)
    edge_keys = mesh.edges[:, 0] * n + mesh.edges[:, 1]
    eid = np.searchsorted(edge_keys, key)
    centre = np.zeros((len(mesh.edges), 2))
    centre[eid] = domains.crossings.reshape(-1, 2)
    inner = domains.inner
    c0, c1 = mesh.edge_cells[:, 0], mesh.edge_cells[:, 1]
    p0 = inner[c0]
    p1 = np.where((c1 >= 0)[:, None], inner[np.maximum(c1, 0)], p0)
    segments = np.stack([np.stack([p0, centre], 1), np.stack([centre, p1], 1)], 1)
    point = np.where((c1 >= 0)[:, None], centre, 0.5 * (p0 + centre))
    chord = np.where((c1 >= 0)[:, None], p1 - p0, centre - p0)
    normal = np.stack([-chord[:, 1], chord[:, 0]], axis=1) / np.hypot(*chord.T)[:, None]
    order = np.argsort(domains.node, kind="stable")
    offsets = np.searchsorted(domains.node[order], np.arange(n + 1))
    return Interfaces(centre, point, segments, normal, offsets, order, domains.corners[order])


def connected_cracks(mesh: EdgeMesh, cracked: np.ndarray, seeds: np.ndarray) -> np.ndarray:
    """Cracked interfaces joined to ``seeds`` by a path of cracked interfaces.

    The interfaces of a triangle's three edges meet at its inner point p_T, so two
    cracked interfaces are joined when their edges share a triangle. Pure numpy
    (:func:`~geofrac.fracture.topology.components` over the cracked interfaces).

    Args:
        mesh: the triangle mesh with edges.
        cracked: whether each interface is cracked, shape=(num_edges,).
        seeds: cracked interfaces to start from, shape=(k,).

    Returns:
        whether each interface belongs to a seed's crack, shape=(num_edges,).
    """
    cracked = np.asarray(cracked, dtype=bool)
    seeds = np.asarray(seeds, dtype=np.int64)
    if len(seeds) and not cracked[seeds].all():
        raise ValueError("connected_cracks: every seed must be a cracked interface")
    ce = mesh.cell_edges
    on = cracked[ce]  # shape=(num_cells, 3)
    pairs = [ce[on[:, a] & on[:, b]][:, [a, b]] for a, b in ((0, 1), (1, 2), (0, 2))]
    a, b = np.concatenate(pairs).T
    labels = components(len(cracked), a, b)
    return cracked & np.isin(labels, labels[seeds])


def side_sites(mesh: EdgeMesh, pairs: np.ndarray) -> np.ndarray:
    """Interfaces that separate a straight line of edges from the nodes on its left.

    An embedded notch (a tagged line of mesh edges) has nodes on it, shared by both
    faces; in the grain model the notch is the chain of interfaces between the line's
    nodes and their neighbours on one side (the left of the line's direction, the
    principal axis of its nodes, pointing to increasing x, then y). Those interfaces
    join through the inner points of the triangles along the line into one polyline
    from end to end.

    Args:
        mesh: the triangle mesh with edges.
        pairs: the line's edges as node pairs, shape=(k, 2).

    Returns:
        edge ids of the interfaces, sorted, shape=(m,).
    """
    line = np.unique(pairs)
    x = mesh.coords[line]
    c = x - x.mean(axis=0)
    direction = np.linalg.svd(c, full_matrices=False)[2][0]
    if direction[0] < 0 or (direction[0] == 0 and direction[1] < 0):
        direction = -direction
    e = mesh.edges
    on = np.isin(e, line)
    one = on[:, 0] ^ on[:, 1]
    node = np.where(on[:, 0], e[:, 0], e[:, 1])
    other = np.where(on[:, 0], e[:, 1], e[:, 0])
    d = mesh.coords[other] - mesh.coords[node]
    left = direction[0] * d[:, 1] - direction[1] * d[:, 0] > 0
    return np.flatnonzero(one & left).astype(np.int64)


@dataclass
class GrainState:
    """Cracked interfaces, frozen interfaces and the C-MultiMLSM fits of cracked grains.

    The driver's units are the nodes (grains): ``fits`` maps each node with a cracked
    interface (or in the forced region) to its :class:`~geofrac.mls.cmulti.NodeFit`.

    Args:
        mesh: the triangle mesh with edges.
        faces: the grain interfaces.
        frozen: nodes whose interfaces may not crack (Dirichlet nodes), shape=(num_nodes,).
        forced: nodes that use C-MultiMLSM from the start, shape=(num_nodes,).
        settings: neighbourhood settings.
        mapper: runs the neighbourhood searches of a refit.
        switch: ``"patch"`` or ``"grain"``: which nodes a cracked interface switches to
            C-MultiMLSM (module docstring).
    """

    mesh: EdgeMesh
    faces: Interfaces
    frozen: np.ndarray
    forced: np.ndarray
    settings: MlsSettings = field(default_factory=MlsSettings)
    mapper: Mapper = serial_map
    switch: str = "patch"

    def __post_init__(self) -> None:  # noqa: D105
        m = self.mesh
        n = len(m.coords)
        self.cracked = np.zeros(len(m.edges), dtype=bool)
        self.fits: dict[int, NodeFit] = {}
        seg = m.coords[m.edges]
        lengths = np.hypot(*(seg[:, 1] - seg[:, 0]).T)
        size = np.zeros(n)
        np.maximum.at(size, m.edges[:, 0], lengths)
        np.maximum.at(size, m.edges[:, 1], lengths)
        self.node_size = size  # longest edge at each node
        #: the cracked interfaces' segments: ids 2e and 2e + 1 for edge e.
        self.crack_segments = self.faces.segments.reshape(-1, 2, 2)
        bin_size = 3.0 * float(np.median(lengths))
        self.node_bins = PointIndex(m.coords)
        self.crack_bins = Bins(bin_size)
        self.crackable = ~(self.frozen[m.edges[:, 0]] | self.frozen[m.edges[:, 1]])
        #: incident edges of each node as CSR (offsets, edge ids).
        self.node_edge_offsets, self.node_edge_ids = m.node_edges()
        self._h = np.zeros(n)
        b = m.boundary_edges
        self._bnd = m.coords[m.edges[b]]  # boundary edges, shape=(nb, 2, 2)
        self._bnd_bins = Bins(bin_size)
        for k, (a, c) in enumerate(self._bnd):
            self._bnd_bins.add(k, np.minimum(a, c), np.maximum(a, c))
        self._on_boundary = m.boundary_nodes()
        self._cell_bins = Bins(bin_size)
        x = m.coords[m.cells]
        for k in range(len(x)):
            self._cell_bins.add(k, x[k].min(axis=0), x[k].max(axis=0))

    # -- queries ---------------------------------------------------------------------
    def is_mls(self) -> np.ndarray:
        """Whether each node uses its C-MultiMLSM field, shape=(num_nodes,)."""
        out = np.zeros(len(self.mesh.coords), dtype=bool)
        out[list(self.fits)] = True
        return out

    def void_cells(self) -> np.ndarray:
        """Nodes whose field has no stiffness (rotation only or fragment), sorted."""
        return np.array(sorted(i for i, f in self.fits.items() if f.order <= 0), dtype=np.int64)

    def fragments(self) -> np.ndarray:
        """Nodes whose grain sees no satellite (a fragment, Edo (2016), Fig. 3.5(b)), sorted."""
        return np.array(sorted(i for i, f in self.fits.items() if f.order < 0), dtype=np.int64)

    def orders(self) -> np.ndarray:
        """Field order per node: 3 EFMM, else the C-MultiMLSM order, shape=(num_nodes,)."""
        out = np.full(len(self.mesh.coords), 3, dtype=np.int64)
        for i, f in self.fits.items():
            out[i] = f.order
        return out

    def edges_of_node(self, node: int) -> np.ndarray:
        """The edges (interfaces) of a node's grain, shape=(k,)."""
        lo, hi = self.node_edge_offsets[node], self.node_edge_offsets[node + 1]
        return self.node_edge_ids[lo:hi]

    def switched(self, edges: np.ndarray) -> np.ndarray:
        """Nodes that cracked interfaces ``edges`` switch to C-MultiMLSM, sorted."""
        m = self.mesh
        edges = np.asarray(edges, dtype=np.int64)
        if self.switch == "grain":
            return np.unique(m.edges[edges])
        cells = m.edge_cells[edges].ravel()
        return np.unique(
            np.concatenate([m.edges[edges].ravel(), m.cells[cells[cells >= 0]].ravel()])
        )

    # -- updates ---------------------------------------------------------------------
    def start(self, precracked: np.ndarray) -> np.ndarray:
        """Crack ``precracked`` interfaces and fit every affected node; return them."""
        for e in np.asarray(precracked, dtype=np.int64):
            self._mark(int(e))
        nodes = set(np.flatnonzero(self.forced).tolist())
        nodes.update(self.switched(np.flatnonzero(self.cracked)).tolist())
        return self.refit(np.array(sorted(nodes), dtype=np.int64))

    def crack_many(self, edges: list[int]) -> np.ndarray:
        """Crack interfaces; refit; return the nodes whose field changed, sorted.

        The two grains of each interface are refitted, and every C-MultiMLSM node whose
        influence circle the new interface crosses, unless it has ``neighbours``
        satellites and the new interfaces hide none of them (then its nearest visible
        nodes, h and satellites stay, as in chapter 2).
        """
        own: set[int] = set()
        near: set[int] = set()
        mls = np.array(sorted(self.fits), dtype=np.int64)
        for e in edges:
            if self.cracked[e]:
                raise ValueError(f"interface {e} is already cracked")
            self._mark(e)
            own.update(self.switched(np.array([e])).tolist())
            if len(mls):
                for a, b in self.faces.segments[e]:
                    d = segment_distance(self.mesh.coords[mls], a, b)
                    near.update(mls[d < self._h[mls]].tolist())
        seg = self.faces.polylines(np.asarray(edges, dtype=np.int64))
        coords, target = self.mesh.coords, self.settings.neighbours
        for i in sorted(near - own):
            fit = self.fits[i]
            sats = fit.nodes[1:]
            if (
                len(sats) < target
                or blocked(coords[i], coords[sats], a=seg[:, 0], b=seg[:, 1]).any()
            ):
                own.add(i)
        return self.refit(np.array(sorted(own), dtype=np.int64))

    def _mark(self, e: int) -> None:
        self.cracked[e] = True
        for k, (a, b) in enumerate(self.faces.segments[e]):
            self.crack_bins.add(2 * e + k, np.minimum(a, b), np.maximum(a, b))

    def refit(self, nodes: np.ndarray) -> np.ndarray:
        """(Re)compute the fits of ``nodes``; return those that changed, sorted."""
        coords = self.mesh.coords
        changed = []
        items = [int(i) for i in np.asarray(nodes, dtype=np.int64)]
        for i, (ids, h) in zip(items, self.mapper(self._search, items), strict=True):
            self._h[i] = h
            old = self.fits.get(i)
            if old is not None and old.h == h and np.array_equal(old.nodes[1:], ids):
                continue
            self.fits[i] = node_fit(coords[i], h, i, ids=ids, xy=coords[ids])
            changed.append(i)
        return np.array(changed, dtype=np.int64)

    def inside(self, points: np.ndarray) -> np.ndarray:
        """Whether points lie in a triangle of the mesh (closed, 1e-9 relative), shape=(k,)."""
        out = np.zeros(len(points), dtype=bool)
        coords, cells = self.mesh.coords, self.mesh.cells
        for k, p in enumerate(points):
            cand = self._cell_bins.query(p, 0.0)
            if not len(cand):
                continue
            x = coords[cells[cand]]  # shape=(c, 3, 2)
            d1, d2, q = x[:, 1] - x[:, 0], x[:, 2] - x[:, 0], p - x[:, 0]
            det = d1[:, 0] * d2[:, 1] - d1[:, 1] * d2[:, 0]
            s = (q[:, 0] * d2[:, 1] - q[:, 1] * d2[:, 0]) / det
            t = (d1[:, 0] * q[:, 1] - d1[:, 1] * q[:, 0]) / det
            tol = 1e-9
            out[k] = bool(np.any((s >= -tol) & (t >= -tol) & (s + t <= 1 + tol)))
        return out

    def through_body(self, i: int, ids: np.ndarray) -> np.ndarray:
        """Whether each segment x_i – x_j runs inside the body, shape=(len(ids),).

        False when it properly crosses a boundary edge (an interior point of both), or
        when both ends are boundary nodes and its midpoint lies outside the mesh.
        """
        coords = self.mesh.coords
        ok = np.ones(len(ids), dtype=bool)
        if not len(ids):
            return ok
        p, q = coords[i], coords[ids]
        reach = float(np.hypot(*(q - p).T).max())
        near = self._bnd_bins.query(p, reach)
        if len(near):
            a, b = self._bnd[near, 0][None], self._bnd[near, 1][None]
            P, Q = p[None, None], q[:, None]
            scale = reach * reach * 1e-9
            o1, o2 = orient(P, Q, a), orient(P, Q, b)
            o3, o4 = orient(a, b, P), orient(a, b, Q)
            cross = (o1 * o2 < -scale * scale) & (o3 * o4 < -scale * scale)
            ok &= ~cross.any(axis=1)
        both = ok & self._on_boundary[i] & self._on_boundary[ids]
        if both.any():
            ok[both] = self.inside(0.5 * (p + q[both]))
        return ok

    def _search(self, i: int) -> tuple[np.ndarray, float]:
        """Visible satellites of node i (itself excluded) and its radius h."""
        s, size = self.settings, self.node_size[i]
        ids, h = visible_nodes(
            self.mesh.coords[i],
            self.mesh.coords,
            self.node_bins,
            crack_bins=self.crack_bins,
            crack_segments=self.crack_segments,
            start=1.5 * size,
            target=s.neighbours + 1,  # the node itself is found at distance 0
            max_radius=s.max_radius_factor * size,
            margin=s.margin,
        )
        ids = ids[ids != i]
        # a grain that sees nothing is a fragment; its radius only has to be positive
        return ids[self.through_body(i, ids)], h if h > 0 else float(size)
