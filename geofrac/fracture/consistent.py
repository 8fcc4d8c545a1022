"""Integration-consistent MLS cells: each cell's gradient from the divergence theorem.

The linear MLS field of a cracked cell (Edo (2016), eqs. 2.13-2.19) is fitted to its
own visible satellites. Neighbouring MLS cells' fields do not conform to each other or
to the element cells, and the one-point stiffness t A Bᵀ D B of eq. (2.19) is not
integration-consistent: Σ_c A_c ∇φ_I over the cells around an interior node does not
vanish, so a uniform stress is not in equilibrium at the nodes of a band of MLS cells
(the patch test fails in stress; docs/cracking.md, "Joint slip").

``cracking.mls_gradient = "consistent"`` gives each MLS cell the gradient of the
divergence theorem instead,

    ∇u_c = (1/A_c) Σ_edges L_e n_e u_e(m_e),

with one *trace* u_e per edge, evaluated at its midpoint m_e and shared by the two cells
of the edge:

- on a cracked edge: the cell's own fit (its face of the crack);
- on an uncracked edge whose two vertices lie on no crack: the nodal interpolation
  ½ (u_a + u_b), as an element cell has it (whatever the cells on its two sides, and on
  the boundary, where the scene's loads are integrated the same way);
- on an uncracked edge with a vertex on a crack: beside an element cell its nodal
  interpolation; beside another (non-void) MLS cell the mean of the two cells' own
  fits; on the boundary and beside a void (or removed) cell the cell's own fit. A
  node on a crack is not used by cracked cells (it would tie the crack's faces:
  :mod:`geofrac.fracture.visibility`), so these edges need the fits.

The traces of an interior edge enter its two cells with opposite normals, so a uniform
stress gives no nodal force there: the cells pass the patch test by construction. The
cell's field is the linear one through its three midpoint traces (for a triangle the
centroid is the mean of the edge midpoints), i.e. a Crouzeix-Raviart interpolant of the
traces; a linear nodal field is reproduced exactly, since every trace reproduces it.
The faces of a crack keep their own fits for the jump [u], so the contact pairs' forces
and the cells' boundary terms use the same trace.

A *void* cell (a cracked cell that sees too few nodes for a fit: Edo (2016), Fig.
2.4(d)) has no stiffness. Under an initial stress it keeps σ0 (:func:`void_sides`): its
sides carry σ0·n on the traces its live neighbours use for them, so that a void cell
inside stressed rock is not a hole whose neighbours' σ0 is out of balance. A removed
cell (an excavation) does not keep it.

Pure numpy; :class:`~geofrac.fracture.state.CrackState` calls it after every refit.
"""

from __future__ import annotations

import numpy as np

from geofrac.fracture.topology import EdgeMesh
from geofrac.mls.shape import LinearFit

__all__ = ["GRADIENTS", "consistent_fit", "touched_cells", "void_sides"]

#: ``cracking.mls_gradient`` values: the fit's own gradient (Edo (2016), eq. 2.19) or
#: the divergence-consistent one of this module.
GRADIENTS = ("fit", "consistent")


def _side(mesh: EdgeMesh, e: int, centroid: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(midpoint, outward normal times length) of edge e of the cell at ``centroid``."""
    p, q = mesh.coords[mesh.edges[e]]
    mid, d = 0.5 * (p + q), q - p
    n = np.array([d[1], -d[0]])
    return mid, (n if n @ (mid - centroid) >= 0.0 else -n)


def _trace(fit: LinearFit, point: np.ndarray) -> dict[int, float]:
    """{node: φ_I(point)} of one fit."""
    values = fit.shape_functions(point[None])[0]
    return dict(zip(fit.nodes.tolist(), values.tolist(), strict=True))


def _edge_trace(
    c: int,
    e: int,
    point: np.ndarray,
    *,
    mesh: EdgeMesh,
    own: dict[int, LinearFit | None],
    cracked: np.ndarray,
    node_cracks: np.ndarray,
) -> dict[int, float]:
    """The one trace of edge e seen from MLS cell c (module docstring), {node: weight}."""
    fit = own[c]
    assert fit is not None
    if cracked[e]:
        return _trace(fit, point)
    n0, n1 = mesh.edges[e].tolist()
    nodal = {int(n0): 0.5, int(n1): 0.5}
    if node_cracks[n0] == 0 and node_cracks[n1] == 0:
        return nodal
    a, b = mesh.edge_cells[e]
    o = int(a if b == c else b)
    if o < 0 or (o in own and own[o] is None):
        return _trace(fit, point)
    other = own.get(o, False)
    if other is False:  # an element cell
        return nodal
    assert isinstance(other, LinearFit)
    mine, theirs = _trace(fit, point), _trace(other, point)
    return {k: 0.5 * (mine.get(k, 0.0) + theirs.get(k, 0.0)) for k in mine.keys() | theirs.keys()}


def consistent_fit(
    c: int,
    *,
    mesh: EdgeMesh,
    own: dict[int, LinearFit | None],
    cracked: np.ndarray,
    node_cracks: np.ndarray,
    centroid: np.ndarray,
    area: float,
) -> LinearFit | None:
    """The integration-consistent field of MLS cell c; None when its own fit is None.

    Args:
        c: the cell.
        mesh: the triangle mesh with edges.
        own: every MLS cell's own fit (eq. 2.17), None for void cells.
        cracked: whether each edge is cracked, shape=(num_edges,).
        node_cracks: cracked edges at each node, shape=(num_nodes,).
        centroid: the cell's centroid, shape=(2,).
        area: the cell's area.

    Returns:
        a :class:`LinearFit` centred at the centroid whose nodes are the union of the
        three traces' nodes (sorted), value row the mean of the midpoint traces and
        gradient rows (1/A) Σ L n u_e(m).
    """
    fit = own[c]
    if fit is None:
        return None
    value: dict[int, float] = {}
    grad: dict[int, np.ndarray] = {}
    for e in mesh.cell_edges[c].tolist():
        mid, n = _side(mesh, e, centroid)
        for k, w in _edge_trace(
            c, e, mid, mesh=mesh, own=own, cracked=cracked, node_cracks=node_cracks
        ).items():
            value[k] = value.get(k, 0.0) + w / 3.0
            grad[k] = grad.get(k, np.zeros(2)) + n * (w / area)
    nodes = np.array(sorted(value), dtype=np.int64)
    coef = np.empty((3, len(nodes)))
    coef[0] = [value[k] for k in nodes.tolist()]
    coef[1:] = np.array([grad[k] for k in nodes.tolist()]).T
    return LinearFit(np.asarray(centroid, dtype=float), fit.h, nodes, coef)


def touched_cells(
    changed: np.ndarray, edges: np.ndarray, *, mesh: EdgeMesh, own: dict[int, LinearFit | None]
) -> np.ndarray:
    """MLS cells whose consistent field may differ after a change, sorted, shape=(k,).

    Args:
        changed: cells whose own fit changed (new, refitted, void or removed), shape=(m,).
        edges: edges newly cracked or turned into boundary, shape=(j,).
        mesh: the triangle mesh with edges.
        own: every MLS cell's own fit.

    Returns:
        the MLS cells among ``changed``, their neighbours across an edge and the cells
        touching a vertex of ``edges``: a trace changes only where one of its cells' fits,
        the edge's state or its vertices' state changed.
    """
    ec = mesh.edge_cells
    changed = np.asarray(changed, dtype=np.int64)
    cells = set(changed.tolist())
    cells.update(ec[mesh.cell_edges[changed].ravel()].ravel().tolist())
    ends = np.unique(mesh.edges[np.asarray(edges, dtype=np.int64)])
    if len(ends):
        cells.update(np.flatnonzero(np.isin(mesh.cells, ends).any(axis=1)).tolist())
    return np.array(sorted(c for c in cells if c >= 0 and c in own), dtype=np.int64)


def void_sides(
    c: int,
    *,
    mesh: EdgeMesh,
    own: dict[int, LinearFit | None],
    cracked: np.ndarray,
    node_cracks: np.ndarray,
    dead: np.ndarray | None = None,
) -> list[tuple[np.ndarray, np.ndarray, np.ndarray]]:
    """The sides of void cell c through which it carries its initial stress.

    Args:
        c: a void cell (its own fit None).
        mesh: the triangle mesh with edges.
        own: every MLS cell's own fit.
        cracked: whether each edge is cracked, shape=(num_edges,).
        node_cracks: cracked edges at each node, shape=(num_nodes,).
        dead: cells that carry nothing at all (removed), shape=(num_cells,), or None.

    Returns:
        per side shared with a live cell (an element cell or a fitted MLS cell):
        (nodes, shape=(q,); weights, shape=(q,); L n, the side's outward normal of c
        times its length, shape=(2,)), the weights those of the trace the live cell
        uses for the side (:func:`consistent_fit`). Its force is t (σ0 L n) wᵢ on node i.
    """
    centroid = mesh.coords[mesh.cells[c]].mean(axis=0)
    out = []
    for e in mesh.cell_edges[c].tolist():
        a, b = mesh.edge_cells[e]
        o = int(a if b == c else b)
        if o < 0 or (dead is not None and dead[o]):
            continue
        mid, n = _side(mesh, e, centroid)
        if o in own:
            if own[o] is None:
                continue
            trace = _edge_trace(
                o, e, mid, mesh=mesh, own=own, cracked=cracked, node_cracks=node_cracks
            )
        else:
            n0, n1 = mesh.edges[e].tolist()
            trace = {int(n0): 0.5, int(n1): 0.5}
        nodes = np.array(sorted(trace), dtype=np.int64)
        out.append((nodes, np.array([trace[k] for k in nodes.tolist()]), n))
    return out
