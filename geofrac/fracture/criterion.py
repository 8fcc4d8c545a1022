"""Sequentially linear crack criterion, Edo (2016), eqs. (2.20)-(2.21) (pure numpy).

For a solution under the unit load, each edge's maximum principal stress σ1 is the mean
of the largest principal stresses of its (one or two) cells at the edge midpoint
(§2.3.2: "the mean of the two maximum principal stresses at the middle of the edge"). The
edge with the least r = f_t / σ1 over the uncracked, crackable edges with σ1 > 0 cracks,
and the solution is scaled by r.

Decisions (docs/cracking.md, "Decisions and their scales"):

- *in tension*: σ1 > ``floor``, a stated fraction of the unit solution's stress scale
  (:data:`~geofrac.fracture.scales.TENSION_FLOOR`); a σ1 that is zero in exact arithmetic
  is round-off of either sign and never an event;
- *ties*: r values within a relative :data:`TIE_TOLERANCE` of the minimum are equal, and
  the site that comes first by its position (x, then y; :func:`tie_order`) wins, so the
  choice depends on the geometry only: not on the number of ranks, nor on how the mesh
  file numbers its nodes and cells.
"""

from __future__ import annotations

import numpy as np

from geofrac.fracture.topology import EdgeMesh

__all__ = [
    "TIE_TOLERANCE",
    "edge_means",
    "edge_principal",
    "least",
    "normal_stress",
    "select_edges",
    "tie_order",
]

#: Relative difference of r below which two edges count as tied. The round-off between
#: edges that are equal in exact arithmetic is far below it: σ1 of the 427 crackable edges
#: of the uniform-strain square (tests/fracture/test_robust.py) spreads by 2e-14, on the
#: mesh and on two permuted copies of it; distinct edges differ by far more than 1e-9.
TIE_TOLERANCE = 1e-9


def tie_order(ids: np.ndarray, points: np.ndarray | None) -> np.ndarray:
    """Positions that order sites ``ids`` by their points (x, then y), then by id.

    Args:
        ids: site ids, shape=(k,).
        points: every site's position, shape=(num_sites, 2); None orders by id alone.

    Returns:
        the order, shape=(k,).
    """
    if points is None:
        return np.argsort(ids, kind="stable")
    p = points[ids]
    return np.lexsort((ids, p[:, 1], p[:, 0]))


def edge_principal(mesh: EdgeMesh, s1: np.ndarray) -> np.ndarray:
    """σ1 per edge: mean over its cells of the largest principal stress at the midpoint.

    Args:
        mesh: the triangle mesh with edges.
        s1: largest principal stress of each cell at the midpoint of its local edge j
            (:func:`geofrac.fracture.cells.principal_max`), shape=(num_cells, 3).

    Returns:
        shape=(num_edges,).
    """
    return edge_means(mesh, s1[:, :, None])[:, 0]


def edge_means(mesh: EdgeMesh, values: np.ndarray) -> np.ndarray:
    """Per edge, the mean over its cells of their values at the edge.

    Args:
        mesh: the triangle mesh with edges.
        values: per cell and local edge j, shape=(num_cells, 3, c).

    Returns:
        shape=(num_edges, c).
    """
    ne = len(mesh.edges)
    ids = mesh.cell_edges.ravel()
    count = np.maximum(np.bincount(ids, minlength=ne), 1)
    flat = values.reshape(len(ids), -1)
    return np.stack(
        [np.bincount(ids, weights=flat[:, k], minlength=ne) / count for k in range(flat.shape[1])],
        axis=1,
    )


def least(ids: np.ndarray, r: np.ndarray, points: np.ndarray | None = None) -> tuple[int, float]:
    """The id of least finite r, and r; ties within :data:`TIE_TOLERANCE` by :func:`tie_order`.

    Args:
        ids: site ids, shape=(k,).
        r: their load factors, shape=(k,).
        points: every site's position, shape=(num_sites, 2); None breaks ties by id.

    Returns (-1, inf) when no r is finite.
    """
    ok = np.isfinite(r)
    if not np.any(ok):
        return -1, float("inf")
    ids, r = ids[ok], r[ok]
    r_min = float(r.min())
    tied = ids[r <= r_min * (1.0 + TIE_TOLERANCE)]
    return int(tied[tie_order(tied, points)[0]]), r_min


def normal_stress(stress: np.ndarray, normal: np.ndarray) -> np.ndarray:
    """Normal traction n · σ n on planes of unit normal n.

    Args:
        stress: (σ_xx, σ_yy, σ_xy), shape=(k, 3).
        normal: unit normals, shape=(k, 2).

    Returns:
        shape=(k,).
    """
    nx, ny = normal[:, 0], normal[:, 1]
    return stress[:, 0] * nx * nx + stress[:, 1] * ny * ny + 2.0 * stress[:, 2] * nx * ny


def select_edges(
    sigma1: np.ndarray,
    candidates: np.ndarray,
    tensile_strength: float,
    *,
    batch_tolerance: float = 0.0,
    max_edges: int = 1,
    floor: float = 0.0,
    points: np.ndarray | None = None,
) -> tuple[np.ndarray, float]:
    """Edges that crack in this event and the scale factor r (2.20).

    Args:
        sigma1: σ1 per edge under the unit load, shape=(num_edges,).
        candidates: whether each edge may crack, shape=(num_edges,).
        tensile_strength: f_t.
        batch_tolerance: also crack edges with r ≤ (1 + batch_tolerance) r_min (several
            near-critical edges per event); 0 cracks one edge (plus exact ties only when
            ``max_edges`` > 1).
        max_edges: at most this many edges per event.
        floor: σ1 must exceed it to count as tension (≥ 0; the unit solution's stress
            scale times :data:`~geofrac.fracture.scales.TENSION_FLOOR` in the loop).
        points: every edge's position for the ties (:func:`tie_order`),
            shape=(num_edges, 2); None breaks ties by id.

    Returns:
        (edge ids in order of r then :func:`tie_order`, shape=(k,); r_min). k = 0 (and
        r = inf) when no candidate is in tension.
    """
    ok = candidates & (sigma1 > max(floor, 0.0)) & np.isfinite(sigma1)
    ids = np.flatnonzero(ok)
    if len(ids) == 0:
        return ids, float("inf")
    r = tensile_strength / sigma1[ids]
    r_min = float(r.min())
    limit = r_min * (1.0 + max(batch_tolerance, TIE_TOLERANCE))
    close = r <= limit
    ids, r = ids[close], r[close]
    tied = r <= r_min * (1.0 + TIE_TOLERANCE)  # ties sort by position, the rest by r
    key = np.where(tied, r_min, r)
    rank = np.empty(len(ids), dtype=np.int64)
    rank[tie_order(ids, points)] = np.arange(len(ids))
    order = np.lexsort((rank, key))
    return ids[order][:max_edges], r_min
