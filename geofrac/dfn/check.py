"""Geometric check that mesh edges cover the fracture network (pure numpy).

Given the endpoints of mesh facets (e.g. the facets a distributed mesh tags as
fractures, on one rank), find for each facet the network edge it lies on. Summed per
fracture, the facet lengths must equal the fracture's length in the cleaned network
(and, for fractures no cleaning rule moved, its clipped length).
"""

from __future__ import annotations

import numpy as np

from geofrac.dfn.clean import CleanNetwork, box_pairs
from geofrac.dfn.polygon import point_segment_distance

__all__ = ["covered_length", "match_facets"]


def match_facets(facets: np.ndarray, clean: CleanNetwork, rtol: float = 1e-9) -> np.ndarray:
    """Network edge on which each facet lies, or -1.

    A facet lies on an edge when both its endpoints are within ``rtol`` times the domain
    size of that edge.

    Args:
        facets: facet endpoints, shape=(num_facets, 2, 2) (extra coordinates ignored).
        clean: the network.
        rtol: distance tolerance relative to the domain size.

    Returns:
        Edge index per facet, shape=(num_facets,); -1 where no edge holds the facet.
    """
    facets = np.asarray(facets, dtype=float)[:, :, :2]
    out = np.full(len(facets), -1, dtype=np.int64)
    if len(facets) == 0 or len(clean.edges) == 0:
        return out
    eps = rtol * float(np.ptp(clean.domain, axis=0).max())
    segs = clean.segments
    boxes_e = np.hstack([segs.min(axis=1), segs.max(axis=1)])
    boxes_f = np.hstack([facets.min(axis=1), facets.max(axis=1)])
    e, f = box_pairs(boxes_e, boxes_f, pad=eps)
    d0, _ = point_segment_distance(facets[f, 0], segs[e, 0], segs[e, 1])
    d1, _ = point_segment_distance(facets[f, 1], segs[e, 0], segs[e, 1])
    hit = (d0 <= eps) & (d1 <= eps)
    out[f[hit]] = e[hit]
    return out


def covered_length(facets: np.ndarray, clean: CleanNetwork, rtol: float = 1e-9) -> np.ndarray:
    """Length of facets lying on each fracture, shape=(num_fractures,).

    Facets on no network edge are ignored (see :func:`match_facets` to find them).
    """
    facets = np.asarray(facets, dtype=float)[:, :, :2]
    edge = match_facets(facets, clean, rtol)
    on = edge >= 0
    length = np.hypot(*(facets[on, 1] - facets[on, 0]).T)
    return np.bincount(
        clean.edge_fracture[edge[on]], weights=length, minlength=len(clean.clipped_length)
    )
