"""Cleaning rules: each degenerate case is merged, snapped or dropped, and reported.

Every test also checks the planar-graph invariants that gmsh relies on (no crossing
edges, vertices at least ``tol`` apart and from edges they do not end on).
"""

import numpy as np
import pytest

from geofrac.dfn.check import covered_length, match_facets
from geofrac.dfn.clean import box_pairs, clean_network
from geofrac.dfn.errors import DfnError
from geofrac.dfn.polygon import as_polygon, point_segment_distance, rectangle
from geofrac.dfn.sampling import FractureSet, Network, generate_network

TOL = 0.1
BOX = rectangle((0.0, 0.0), (10.0, 10.0))


def _network(*segments):
    segs = np.array(segments, dtype=float).reshape(-1, 2, 2)
    return Network(segs, np.zeros(len(segs), dtype=np.int64), ("s",))


def _events(clean, rule):
    return clean.report.events[rule]


def _check_invariants(clean):
    """The graph gmsh gets: no crossings, no vertex near another or near a foreign edge."""
    v, e, tol = clean.vertices, clean.edges, clean.tol
    assert len(np.unique(np.sort(e, axis=1), axis=0)) == len(e), "repeated edge"
    assert np.all(e[:, 0] != e[:, 1])
    if len(v) > 1:
        d = np.hypot(*(v[:, None, :] - v[None, :, :]).transpose(2, 0, 1))
        np.fill_diagonal(d, np.inf)
        assert d.min() >= tol
    segs = clean.segments
    for k, p in enumerate(v):
        dist, _ = point_segment_distance(p[None], segs[:, 0], segs[:, 1])
        foreign = ~np.any(e == k, axis=1)
        assert np.all(dist[foreign] >= tol * (1 - 1e-12)), f"vertex {k} near an edge"
    a0, a1 = segs[:, None, 0], segs[:, None, 1]
    b0, b1 = segs[None, :, 0], segs[None, :, 1]
    r, s = a1 - a0, b1 - b0
    den = r[..., 0] * s[..., 1] - r[..., 1] * s[..., 0]
    with np.errstate(divide="ignore", invalid="ignore"):
        t = ((b0 - a0)[..., 0] * s[..., 1] - (b0 - a0)[..., 1] * s[..., 0]) / den
        u = ((b0 - a0)[..., 0] * r[..., 1] - (b0 - a0)[..., 1] * r[..., 0]) / den
    inner = (t > 1e-9) & (t < 1 - 1e-9) & (u > 1e-9) & (u < 1 - 1e-9) & (np.abs(den) > 0)
    assert not inner.any(), "edges cross"
    assert np.all(clean.edge_length >= tol)


def _unmodified_keep_their_length(clean):
    keep = ~clean.modified
    np.testing.assert_allclose(clean.length[keep], clean.clipped_length[keep], rtol=1e-12)


def test_x_junction_splits_both_fractures_without_moving_them():
    c = clean_network(_network([[2, 2], [8, 8]], [[2, 8], [8, 2]]), BOX, TOL)
    assert c.report.crossings == 1 and len(c.edges) == 4 and len(c.vertices) == 5
    assert not c.modified.any()
    assert np.any(np.all(np.isclose(c.vertices, [5.0, 5.0]), axis=1))
    _unmodified_keep_their_length(c)
    _check_invariants(c)
    assert c.min_junction_angle() == pytest.approx(90.0)


def test_exact_t_junction_splits_the_through_fracture():
    c = clean_network(_network([[2, 5], [8, 5]], [[5, 5], [5, 8]]), BOX, TOL)
    assert c.report.tees == 1 and len(c.edges) == 3
    assert not c.modified.any() and not _events(c, "tee_snap")
    _unmodified_keep_their_length(c)
    _check_invariants(c)


def test_t_junction_that_misses_by_less_than_tol_is_snapped():
    c = clean_network(_network([[2, 5], [8, 5]], [[5, 5.06], [5, 8]]), BOX, TOL)
    ((f, other, moved),) = _events(c, "tee_snap")
    assert (f, other) == (1, 0) and moved == pytest.approx(0.06)
    assert len(c.edges) == 3
    degree = np.bincount(c.edges.ravel())
    np.testing.assert_allclose(c.vertices[degree == 3], [[5.0, 5.0]])
    assert c.modified.tolist() == [False, True]
    _check_invariants(c)


def test_t_junction_that_overshoots_by_less_than_tol_leaves_no_stub():
    c = clean_network(_network([[2, 5], [8, 5]], [[5, 4.94], [5, 8]]), BOX, TOL)
    assert len(_events(c, "tee_snap")) == 1 and c.report.crossings == 0
    assert len(c.edges) == 3  # no 0.06-long piece below the horizontal fracture
    assert c.length[1] == pytest.approx(3.0)
    _check_invariants(c)


def test_t_junction_farther_than_tol_is_left_alone():
    c = clean_network(_network([[2, 5], [8, 5]], [[5, 5.3], [5, 8]]), BOX, TOL)
    assert not c.modified.any() and len(c.edges) == 2
    _check_invariants(c)


def test_fracture_crossing_the_boundary_is_clipped_and_ends_on_it():
    c = clean_network(_network([[5, 5], [15, 5]]), BOX, TOL)
    assert _events(c, "clipped") == [(0, -1, pytest.approx(5.0))]
    assert c.clipped_length[0] == pytest.approx(5.0) and c.length[0] == pytest.approx(5.0)
    assert c.on_boundary.tolist().count(True) == 1
    np.testing.assert_allclose(c.vertices[c.on_boundary], [[10.0, 5.0]])
    assert not c.modified.any()
    _check_invariants(c)


def test_fracture_ending_just_short_of_the_boundary_is_snapped_onto_it():
    c = clean_network(_network([[5, 5], [9.95, 5]]), BOX, TOL)
    ((f, _, moved),) = _events(c, "boundary_snap")
    assert f == 0 and moved == pytest.approx(0.05)
    np.testing.assert_allclose(c.vertices[c.on_boundary], [[10.0, 5.0]])
    _check_invariants(c)


def test_fracture_ending_near_a_corner_is_snapped_onto_the_corner():
    c = clean_network(_network([[5, 5], [9.95, 9.96]]), BOX, TOL)
    assert len(_events(c, "boundary_snap")) == 1
    np.testing.assert_allclose(c.vertices[c.on_boundary], [[10.0, 10.0]])


def test_fracture_passing_near_a_corner_is_bent_through_it():
    c = clean_network(_network([[8, 8.5], [10.0, 10.05]]), BOX, TOL)
    corner = np.all(np.isclose(c.vertices, [10.0, 10.0]), axis=1)
    assert corner.any()
    _check_invariants(c)


def test_near_parallel_fractures_closer_than_tol_are_merged():
    c = clean_network(_network([[2, 5], [8, 5]], [[3, 5.05], [9, 5.05]]), BOX, TOL)
    ((f, into, offset),) = _events(c, "merged")
    assert (f, into) == (1, 0) and offset == pytest.approx(0.05)
    assert c.length[0] == pytest.approx(7.0) and c.length[1] == 0.0
    assert np.isinf(c.moved[1]) and c.modified[0]
    _check_invariants(c)


def test_collinear_fractures_with_a_gap_below_tol_become_one():
    c = clean_network(_network([[2, 5], [5, 5]], [[5.05, 5], [8, 5]]), BOX, TOL)
    assert len(_events(c, "merged")) == 1
    assert len(c.edges) == 1 and c.length.sum() == pytest.approx(6.0)


def test_near_parallel_fractures_farther_apart_are_kept():
    c = clean_network(_network([[2, 5], [8, 5]], [[3, 5.3], [9, 5.3]]), BOX, TOL)
    assert not any(c.report.counts()[r] for r in ("merged", "duplicate", "overlap"))
    assert not c.modified.any()
    _check_invariants(c)


def test_near_coincident_endpoints_become_one_vertex():
    c = clean_network(_network([[2, 2], [5, 5]], [[5.05, 5.0], [8, 2]]), BOX, TOL)
    assert len(_events(c, "vertex_merge")) == 1
    assert len(c.vertices) == 3 and len(c.edges) == 2
    _check_invariants(c)


def test_junctions_closer_than_tol_merge():
    # three fractures nearly concurrent: the two crossings are 0.05 apart
    net = _network([[2, 5], [8, 5]], [[2, 2], [8, 8]], [[2.05, 8], [8.05, 2]])
    c = clean_network(net, BOX, TOL)
    assert c.report.counts()["vertex_merge"] >= 1
    assert np.bincount(c.edges.ravel()).max() == 6  # one vertex where all three meet
    _check_invariants(c)


def test_piece_shorter_than_tol_after_clipping_is_dropped():
    c = clean_network(_network([[2, 5], [8, 5]], [[9.95, 2], [12, 2]]), BOX, TOL)
    ((f, _, length),) = _events(c, "short")
    assert f == 1 and length == pytest.approx(0.05)
    assert set(c.edge_fracture.tolist()) == {0} and np.isinf(c.moved[1])


def test_fracture_outside_the_domain_is_reported():
    c = clean_network(_network([[2, 5], [8, 5]], [[11, 11], [12, 12]]), BOX, TOL)
    assert [f for f, _, _ in _events(c, "outside")] == [1]
    assert c.clipped_length[1] == 0.0 and c.length[1] == 0.0


def test_duplicate_fractures_keep_the_first():
    c = clean_network(_network([[2, 5], [8, 5]], [[8.02, 5.01], [2.01, 4.99]]), BOX, TOL)
    assert [(f, other) for f, other, _ in _events(c, "duplicate")] == [(1, 0)]
    assert len(c.edges) == 1 and c.edge_fracture.tolist() == [0]


def test_fracture_along_the_boundary_is_dropped():
    c = clean_network(_network([[2, 0.05], [8, 0.05]], [[5, 5], [5, 8]]), BOX, TOL)
    assert [f for f, _, _ in _events(c, "on_boundary")] == [0]
    assert set(c.edge_fracture.tolist()) == {1}


def test_non_convex_domain_splits_a_fracture_into_pieces():
    ell = as_polygon([[0, 0], [10, 0], [10, 4], [4, 4], [4, 10], [0, 10]])
    c = clean_network(_network([[2, 6], [8, 2]]), ell, TOL)
    on_line = c.clipped_length[0]
    assert 0 < on_line < np.hypot(6, 4)
    assert len(c.edges) == 2 and c.on_boundary.sum() == 2
    assert c.length[0] == pytest.approx(on_line, rel=1e-12)
    _check_invariants(c)


def test_tolerance_must_be_positive():
    with pytest.raises(DfnError, match="tolerance"):
        clean_network(_network([[2, 5], [8, 5]]), BOX, 0.0)


def _table_2_1(count):
    return [
        FractureSet("set1", 47.473, 60.74**0.5, 10.0, 50.0, 3.1, count=count),
        FractureSet("set2", 102.753, 57.16**0.5, 10.0, 50.0, 3.1, count=count),
        FractureSet("set3", 162.830, 57.48**0.5, 10.0, 50.0, 3.1, count=count),
    ]


@pytest.mark.parametrize("seed", range(4))
def test_dense_random_networks_satisfy_the_invariants(seed):
    domain = rectangle((0.0, 0.0), (200.0, 100.0))
    net = generate_network(_table_2_1(120), domain, seed)
    c = clean_network(net, domain, 0.25)
    _check_invariants(c)
    _unmodified_keep_their_length(c)
    moved = c.moved[np.isfinite(c.moved)]
    assert moved.max() < 3 * c.tol  # rules move geometry by about tol at most
    # P21 ≈ 0.26/mm here: an endpoint lies within tol of another fracture with probability
    # about 2·tol·P21 ≈ 0.13, so roughly a quarter of the fractures get a snapped end
    assert np.count_nonzero(~c.modified) > 0.6 * len(net)
    assert c.report.crossings > 50
    inside = np.all((c.vertices >= 0) & (c.vertices <= [200, 100]), axis=1)
    assert inside.all()


def test_box_pairs_matches_brute_force():
    rng = np.random.default_rng(3)
    lo = rng.uniform(0, 10, (200, 2))
    boxes = np.hstack([lo, lo + rng.uniform(0, 2, (200, 2))])
    i, j = box_pairs(boxes, pad=0.1)
    a, b = boxes[:, None], boxes[None, :]
    overlap = (
        (a[..., 0] <= b[..., 2] + 0.2)
        & (b[..., 0] <= a[..., 2] + 0.2)
        & (a[..., 1] <= b[..., 3] + 0.2)
        & (b[..., 1] <= a[..., 3] + 0.2)
    )
    bi, bj = np.nonzero(np.triu(overlap, 1))
    assert sorted(zip(i.tolist(), j.tolist(), strict=True)) == sorted(
        zip(bi.tolist(), bj.tolist(), strict=True)
    )
    others = boxes[:50] + 5.0
    i, j = box_pairs(boxes, others)
    expected = np.nonzero(
        (boxes[:, None, 0] <= others[None, :, 2])
        & (others[None, :, 0] <= boxes[:, None, 2])
        & (boxes[:, None, 1] <= others[None, :, 3])
        & (others[None, :, 1] <= boxes[:, None, 3])
    )
    assert sorted(zip(i.tolist(), j.tolist(), strict=True)) == sorted(
        zip(*(e.tolist() for e in expected), strict=True)
    )


def test_facets_on_the_network_are_matched_and_summed():
    c = clean_network(_network([[2, 2], [8, 8]], [[2, 8], [8, 2]]), BOX, TOL)
    t = np.linspace(0.0, 1.0, 7)
    line = np.array([2.0, 2.0]) + t[:, None] * 6.0
    facets = np.stack([line[:-1], line[1:]], axis=1)  # fracture 0 in 6 pieces
    stray = np.array([[[1.0, 1.0], [1.5, 1.0]]])
    edge = match_facets(np.concatenate([facets, stray]), c)
    assert np.all(edge[:-1] >= 0) and edge[-1] == -1
    assert set(c.edge_fracture[edge[:-1]].tolist()) == {0}
    np.testing.assert_allclose(covered_length(facets, c), [6 * 2**0.5, 0.0], rtol=1e-14)
