"""Crack state of a triangle mesh: cracked edges and the MLS fits of cracked cells.

Pure numpy and identical on every rank: the driver replicates it, so that the crack
sequence does not depend on the number of ranks. A cell *uses MLS* when it owns a
cracked edge (Edo (2016), §2.3.1) or lies in a forced region (the patch test's core); its field
is the linear fit of :mod:`geofrac.mls.shape` through its visible satellite nodes
(:mod:`geofrac.fracture.visibility`). A cracked cell that sees fewer than 3
non-collinear nodes is *void*: it carries no stiffness, as Edo (2016) does for a fragment
(Fig. 2.4(d)).

:meth:`CrackState.crack` refits the cells of the edge and every MLS cell whose influence
circle the edge crosses, and returns those whose field really changed (a refit that finds
the same satellites and radius keeps its fit object, so caches keyed by it stay valid).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from geofrac.fracture.consistent import consistent_fit, touched_cells
from geofrac.fracture.topology import EdgeMesh, components
from geofrac.fracture.visibility import Bins, PointIndex, blocked, visible_nodes
from geofrac.mls.shape import LinearFit, linear_fit

__all__ = ["CrackState", "Mapper", "MlsSettings", "segment_distance", "serial_map"]

#: ``mapper(f, items) -> [f(i) for i in items]``, in order; the driver passes one that
#: shares the items among MPI ranks (the results do not depend on who computes them).
Mapper = Callable[[Callable[[int], Any], list[int]], list[Any]]


def serial_map(f: Callable[[int], Any], items: list[int]) -> list[Any]:
    """The plain :data:`Mapper`: ``[f(i) for i in items]``."""
    return [f(i) for i in items]


@dataclass(frozen=True)
class MlsSettings:
    """Neighbourhood settings of the MLS fits.

    Attributes:
        neighbours: visible satellite nodes wanted (Edo (2016): about 10).
        margin: h / distance of the ``neighbours``-th node.
        max_radius_factor: largest search radius in units of the cell's longest edge.
        gradient: ``"fit"``, the fit's own gradient (Edo (2016), eq. 2.19), or
            ``"consistent"`` (:mod:`geofrac.fracture.consistent`).
    """

    neighbours: int = 10
    margin: float = 1.1
    max_radius_factor: float = 8.0
    gradient: str = "fit"


def _ranges(starts: np.ndarray, stops: np.ndarray) -> np.ndarray:
    """The concatenated ranges [starts[i], stops[i]), shape=(sum(stops - starts),)."""
    lengths = stops - starts
    if not len(lengths) or not lengths.sum():
        return np.zeros(0, dtype=np.int64)
    offsets = np.repeat(starts - np.concatenate([[0], np.cumsum(lengths)[:-1]]), lengths)
    return np.arange(int(lengths.sum())) + offsets


def segment_distance(points: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Distance from points, shape=(n, 2), to the segment a–b."""
    d = b - a
    t = np.clip(((points - a) @ d) / max(float(d @ d), 1e-300), 0.0, 1.0)
    return np.hypot(*(points - (a + t[:, None] * d)).T)


@dataclass
class CrackState:
    """Cracked edges, frozen cells and MLS fits.

    Args:
        mesh: the triangle mesh with edges.
        frozen: cells that may not crack (touching a Dirichlet node), shape=(num_cells,).
        forced: cells that use MLS from the start, shape=(num_cells,).
        settings: neighbourhood settings.
        mapper: runs the neighbourhood searches of a refit (:data:`Mapper`).
        cut: cells touching a *cut* node (one where two cracked edges meet, or a
            boundary node of a cracked edge) use MLS too, so that no element cell ties
            the two faces of a crack together at its nodes (crack-face contact); and so
            do element cells left hanging on one node (:meth:`hinged_cells`).
    """

    mesh: EdgeMesh
    frozen: np.ndarray
    forced: np.ndarray
    settings: MlsSettings = field(default_factory=MlsSettings)
    mapper: Mapper = serial_map
    cut: bool = False

    def __post_init__(self) -> None:  # noqa: D105
        m = self.mesh
        n_nodes = len(m.coords)
        #: cracked edges at each node, shape=(num_nodes,).
        self.node_cracks = np.zeros(n_nodes, dtype=np.int64)
        self._on_boundary = m.boundary_nodes()
        order = np.argsort(m.cells.ravel(), kind="stable")
        self._star = order // 3  # cells around each node, grouped by node
        self._star_ptr = np.searchsorted(m.cells.ravel()[order], np.arange(n_nodes + 1))
        # interior edges and their two cells, shape=(k,) and (k, 2)
        self._inner_edges = np.flatnonzero((m.edge_cells >= 0).all(axis=1))
        self._inner_cells = m.edge_cells[self._inner_edges]
        self.cracked = np.zeros(len(m.edges), dtype=bool)
        #: each MLS cell's own fit through its satellites (eq. 2.17), None when void; the
        #: faces of a crack take their jump from these.
        self.own_fits: dict[int, LinearFit | None] = {}
        #: the field each MLS cell's stiffness and stress use: its own fit, or with
        #: ``settings.gradient == "consistent"`` the consistent field
        #: (:func:`~geofrac.fracture.consistent.consistent_fit`); the same keys.
        self.fits: dict[int, LinearFit | None] = (
            self.own_fits if self.settings.gradient == "fit" else {}
        )
        self.centroids = m.centroids()
        self.areas = m.areas()
        seg = m.coords[m.edges]  # shape=(ne, 2, 2)
        self.segments = seg
        lengths = np.hypot(*(seg[:, 1] - seg[:, 0]).T)
        self.cell_size = lengths[m.cell_edges].max(axis=1)  # longest edge per cell
        size = 3.0 * float(np.median(lengths))
        self.node_bins = PointIndex(m.coords)
        self.crack_bins = Bins(size)
        #: the boundary edges: no satellite is seen out of the body (a notch, a hole).
        self.boundary_bins = Bins(size)
        for e in np.flatnonzero(m.boundary_edges).tolist():
            a, b = seg[e]
            self.boundary_bins.add(e, np.minimum(a, b), np.maximum(a, b))
        #: edges that may crack: interior edges (two cells; an edge on the boundary has
        #: no second face to open) not of frozen cells, shape=(num_edges,).
        self.crackable = ~m.boundary_edges
        self.crackable[np.unique(m.cell_edges[self.frozen])] = False
        self._h = np.zeros(m.num_cells)

    # -- queries ---------------------------------------------------------------------
    @property
    def mls_cells(self) -> np.ndarray:
        """Ids of the cells that use MLS, sorted, shape=(k,)."""
        return np.array(sorted(self.own_fits), dtype=np.int64)

    def is_mls(self) -> np.ndarray:
        """Whether each cell uses MLS, shape=(num_cells,)."""
        out = np.zeros(self.mesh.num_cells, dtype=bool)
        out[list(self.own_fits)] = True
        return out

    def void_cells(self) -> np.ndarray:
        """Cracked cells without a fit (no stiffness), sorted, shape=(k,)."""
        return np.array(sorted(c for c, f in self.own_fits.items() if f is None), dtype=np.int64)

    # -- updates ---------------------------------------------------------------------
    def start(self, precracked: np.ndarray) -> np.ndarray:
        """Crack ``precracked`` edges and fit every MLS cell; return the MLS cells."""
        for e in np.asarray(precracked, dtype=np.int64):
            self._mark(int(e))
        cells = set(np.flatnonzero(self.forced).tolist())
        for e in np.flatnonzero(self.cracked):
            cells.update(c for c in self.mesh.edge_cells[e] if c >= 0)
        cells.update(self._cut_cells(np.flatnonzero(self.node_cracks)))
        changed = self._refit_hinged(self.refit(np.array(sorted(cells), dtype=np.int64)))
        return self.conform(changed, np.flatnonzero(self.cracked))

    def hinged_cells(self) -> np.ndarray:
        """Element cells that hang on at most one node: they would turn about it freely.

        Element cells joined by uncracked edges form pieces. A piece's node *holds* it
        when an MLS fit uses the node or an element cell of another piece has it. A piece
        of no frozen cell (none touches a Dirichlet node) held by one node or none moves
        rigidly without strain energy, since MLS cells tie a node only through their
        fits' satellites (not their own vertices). Only with ``cut``, where the MLS
        cells around cut nodes can leave such pieces behind. Returns their cells,
        sorted, shape=(k,).
        """
        m = self.mesh
        elem = ~self.is_mls()
        if not self.cut or not elem.any():
            return np.zeros(0, dtype=np.int64)
        inner, ec = self._inner_edges, self._inner_cells
        joined = ~self.cracked[inner] & elem[ec[:, 0]] & elem[ec[:, 1]]
        labels = components(m.num_cells, ec[joined, 0], ec[joined, 1])
        cells = np.flatnonzero(elem)
        anchored = np.zeros(m.num_cells, dtype=bool)
        anchored[labels[cells[self.frozen[cells]]]] = True
        # only pieces without a frozen cell can hang: count the holds of those alone
        loose = cells[~anchored[labels[cells]]]
        if not len(loose):
            return loose
        nodes = np.unique(m.cells[loose].ravel())
        # every element cell around those nodes, with its piece: the distinct
        # (node, piece) pairs tell which nodes an element cell of another piece has
        starts, stops = self._star_ptr[nodes], self._star_ptr[nodes + 1]
        around = self._star[_ranges(starts, stops)]
        owner = np.repeat(nodes, stops - starts)
        keep = elem[around]
        pair = np.unique(owner[keep] * m.num_cells + labels[around[keep]])
        node, piece = np.divmod(pair, m.num_cells)
        used = np.zeros(len(m.coords), dtype=bool)
        nodes_of_fits = [f.nodes for f in self.own_fits.values() if f is not None]
        if nodes_of_fits:
            used[np.concatenate(nodes_of_fits)] = True
        holds = used[node] | (np.bincount(node, minlength=len(m.coords))[node] > 1)
        held_by = np.bincount(piece, weights=holds, minlength=m.num_cells)
        hanging = held_by <= 1
        return loose[hanging[labels[loose]]]

    def _refit_hinged(self, changed: np.ndarray) -> np.ndarray:
        """Give MLS fits to :meth:`hinged_cells` until none is left; all changed cells."""
        hinged = self.hinged_cells()
        while len(hinged):
            changed = np.union1d(changed, self.refit(hinged))
            hinged = self.hinged_cells()
        return changed

    def is_cut(self, nodes: np.ndarray) -> np.ndarray:
        """Whether each node is cut (two cracked edges, or one on the boundary), same shape."""
        k = self.node_cracks[nodes]
        return (k >= 2) | ((k >= 1) & self._on_boundary[nodes])

    def _cut_cells(self, nodes: np.ndarray) -> list[int]:
        """Cells around the cut ones of ``nodes`` (none unless ``cut``)."""
        if not self.cut or not len(nodes):
            return []
        nodes = np.asarray(nodes, dtype=np.int64)
        cut = nodes[self.is_cut(nodes)]
        return self._star[_ranges(self._star_ptr[cut], self._star_ptr[cut + 1])].tolist()

    def crack(self, edge: int) -> np.ndarray:
        """Crack one edge; refit; return the cells whose field changed, sorted, shape=(k,)."""
        return self.crack_many([edge])

    def crack_many(self, edges: list[int]) -> np.ndarray:
        """Crack several edges at once; refit; return the cells whose field changed.

        An MLS cell whose influence circle a new edge crosses keeps its fit without a
        new search when it has ``neighbours`` satellites and the new edges hide none of
        them: a crack only hides nodes, so its nearest visible nodes, h and the visible
        set inside h stay as they are (the same :func:`blocked` test decides both).
        """
        own: set[int] = set()
        near: set[int] = set()
        mls = self.mls_cells
        for e in edges:
            if self.cracked[e]:
                raise ValueError(f"edge {e} is already cracked")
            self._mark(e)
            own.update(int(c) for c in self.mesh.edge_cells[e] if c >= 0)
            if len(mls):
                a, b = self.segments[e]
                d = segment_distance(self.centroids[mls], a, b)
                near.update(mls[d < self._h[mls]].tolist())
        ends = self.mesh.edges[np.asarray(edges, dtype=np.int64)].ravel()
        own.update(c for c in self._cut_cells(ends) if c not in self.own_fits)
        seg = self.segments[np.asarray(edges, dtype=np.int64)]
        coords, target = self.mesh.coords, self.settings.neighbours
        for c in sorted(near - own):
            fit = self.own_fits[c]
            if (
                fit is None
                or len(fit.nodes) < target
                or blocked(self.centroids[c], coords[fit.nodes], a=seg[:, 0], b=seg[:, 1]).any()
            ):
                own.add(c)
        changed = self._refit_hinged(self.refit(np.array(sorted(own), dtype=np.int64)))
        return self.conform(changed, np.asarray(edges, dtype=np.int64))

    def _mark(self, e: int) -> None:
        self.cracked[e] = True
        self.node_cracks[self.mesh.edges[e]] += 1
        a, b = self.segments[e]
        self.crack_bins.add(e, np.minimum(a, b), np.maximum(a, b))

    def refit(self, cells: np.ndarray) -> np.ndarray:
        """(Re)compute the MLS fits of ``cells`` (pure function of the crack state).

        Returns the cells whose fit changed (new, or other satellites or radius), sorted,
        shape=(k,); the others keep their fit object.
        """
        coords = self.mesh.coords
        changed = []
        items = [int(c) for c in np.asarray(cells, dtype=np.int64)]
        for c, (ids, h) in zip(items, self.mapper(self._search, items), strict=True):
            self._h[c] = h
            known = c in self.own_fits
            old = self.own_fits.get(c)
            if known and old is not None and old.h == h and np.array_equal(old.nodes, ids):
                continue
            fit = linear_fit(self.centroids[c], h, ids, coords=coords[ids]) if len(ids) else None
            if known and old is None and fit is None:
                continue
            self.own_fits[c] = fit
            changed.append(c)
        return np.array(changed, dtype=np.int64)

    def conform(self, changed: np.ndarray, edges: np.ndarray) -> np.ndarray:
        """Bring :attr:`fits` up to :attr:`own_fits` after a change; all changed cells.

        Args:
            changed: cells whose own fit changed, shape=(m,).
            edges: edges newly cracked or turned into boundary, shape=(j,).

        Returns:
            ``changed`` and, with consistent gradients, the cells whose consistent field
            changed with them (:func:`~geofrac.fracture.consistent.touched_cells`), sorted.
            A field equal to the old one keeps its object.
        """
        if self.fits is self.own_fits:
            return changed
        out = []
        m = self.mesh
        for c in touched_cells(changed, edges, mesh=m, own=self.own_fits).tolist():
            new = consistent_fit(
                c,
                mesh=m,
                own=self.own_fits,
                cracked=self.cracked,
                node_cracks=self.node_cracks,
                centroid=self.centroids[c],
                area=float(self.areas[c]),
            )
            old = self.fits.get(c, False)
            same = (old is None and new is None) or (
                isinstance(old, LinearFit)
                and new is not None
                and np.array_equal(old.nodes, new.nodes)
                and np.array_equal(old.coefficients, new.coefficients)
            )
            if not same:
                self.fits[c] = new
                out.append(c)
        return np.union1d(changed, np.array(out, dtype=np.int64)).astype(np.int64)

    def _search(self, c: int) -> tuple[np.ndarray, float]:
        """Visible satellites of cell c and its radius h (:func:`visible_nodes`)."""
        s, size = self.settings, self.cell_size[c]
        return visible_nodes(
            self.centroids[c],
            self.mesh.coords,
            self.node_bins,
            crack_bins=self.crack_bins,
            crack_segments=self.segments,
            start=1.5 * size,
            target=s.neighbours,
            max_radius=s.max_radius_factor * size,
            margin=s.margin,
            boundary_bins=self.boundary_bins,
        )
