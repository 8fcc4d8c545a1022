"""Polygon checks, point location and segment clipping (geofrac.dfn.polygon)."""

import numpy as np
import pytest

from geofrac.dfn.errors import DfnError
from geofrac.dfn.polygon import (
    as_polygon,
    clip_segments,
    points_in_polygon,
    polygon_area,
    rectangle,
)

RECT = rectangle((0.0, 0.0), (2.0, 1.0))
# L shape: the square [0, 2]² without its upper right quarter; reflex vertex at (1, 1)
ELL = np.array([[0, 0], [2, 0], [2, 1], [1, 1], [1, 2], [0, 2]], dtype=float)


def clip_one(a, b, poly):
    pieces, parent = clip_segments(np.array([[a, b]], dtype=float), poly)
    assert np.all(parent == 0)
    return pieces


def test_rectangle_is_ccw_from_the_first_corner():
    r = rectangle((1.0, 2.0), (4.0, 3.0))
    assert r.tolist() == [[1, 2], [4, 2], [4, 3], [1, 3]]
    assert polygon_area(r) == pytest.approx(3.0)


@pytest.mark.parametrize(
    ("args", "match"),
    [((0, 0, 0, 1), "x1 = 0 must be greater than x0 = 0"), ((0, 1, 2, 0), "y1 = 0")],
)
def test_rectangle_rejects_empty(args, match):
    with pytest.raises(DfnError, match=match):
        rectangle(args[:2], args[2:])


def test_as_polygon_returns_ccw():
    cw = RECT[::-1]
    out = as_polygon(cw)
    assert polygon_area(out) == pytest.approx(2.0)
    # counter-clockwise: positive shoelace sum
    x, y = out[:, 0], out[:, 1]
    assert np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y) > 0
    assert sorted(map(tuple, out)) == sorted(map(tuple, RECT))


def test_polygon_area_of_the_l_shape():
    assert polygon_area(ELL) == pytest.approx(3.0)


@pytest.mark.parametrize(
    ("points", "match"),
    [
        ([[0, 0], [1, 0]], "at least 3 vertices"),
        ([[0, 0, 0], [1, 0, 0], [0, 1, 0]], r"shape \(m, 2\)"),
        ([[0, 0], [1, np.nan], [0, 1]], "vertex 1 is not finite"),
        ([[0, 0], [1, 0], [1, 0], [0, 1]], "vertices 1 and 2 are the same point"),
        ([[0, 0], [1, 0], [0, 1], [0, 0]], "do not repeat the first vertex"),
        ([[0, 0], [1, 1], [2, 2]], "zero area"),
        ([[0, 0], [3, 2], [3, 0], [0, 1]], "not simple"),  # bow tie
        ([[0, 0], [2, 0], [2, 2], [1, 0], [0, 2]], "not simple"),  # touches its own edge
        ([[0, 0], [4, 0], [4, 2], [0, 2], [0, 1], [-1, 1], [0, 1.5]], "not simple"),
        ([[0, 0], [2, 0], [3, 0], [1, 0], [1, 1]], "folds back|not simple"),  # spike
    ],
)
def test_as_polygon_rejects(points, match):
    with pytest.raises(DfnError, match=match):
        as_polygon(points)


def test_points_in_polygon_even_odd_and_boundary():
    pts = np.array(
        [
            [0.5, 0.5],  # lower arm
            [0.5, 1.5],  # upper arm
            [1.5, 1.5],  # notch: outside
            [2.5, 0.5],  # right of everything
            [1.5, 1.0],  # on the notch edge: boundary counts as inside
            [1.0, 1.0],  # reflex vertex
            [0.0, 2.0],  # corner
            [-1e-9, 1.0],  # just outside the left edge
        ]
    )
    got = points_in_polygon(pts, ELL)
    assert got.tolist() == [True, True, False, False, True, True, True, False]


def test_points_in_polygon_matches_the_rectangle_test():
    rng = np.random.default_rng(4)
    pts = rng.uniform(-0.5, 2.5, size=(2000, 2))
    expected = (pts[:, 0] >= 0) & (pts[:, 0] <= 2) & (pts[:, 1] >= 0) & (pts[:, 1] <= 1)
    assert np.array_equal(points_in_polygon(pts, RECT), expected)


def test_clip_segment_crossing_the_rectangle():
    pieces = clip_one([-1.0, 0.5], [3.0, 0.5], RECT)
    assert pieces.tolist() == [[[0.0, 0.5], [2.0, 0.5]]]
    # an oblique one: enters through the bottom, leaves through the right side
    pieces = clip_one([0.5, -0.5], [2.5, 0.5], RECT)
    np.testing.assert_allclose(pieces, [[[1.5, 0.0], [2.0, 0.25]]], atol=1e-15)


def test_clip_keeps_an_inside_segment_exactly_and_its_direction():
    a, b = [0.1234567, 0.7654321], [1.9, 0.1]
    assert clip_one(b, a, RECT).tolist() == [[b, a]]


def test_clip_drops_a_segment_outside():
    assert clip_one([-1.0, 2.0], [3.0, 2.0], RECT).shape == (0, 2, 2)
    assert clip_one([3.0, 0.0], [4.0, 1.0], RECT).shape == (0, 2, 2)


def test_clip_segment_along_an_edge_counts_as_inside():
    assert clip_one([-1.0, 0.0], [3.0, 0.0], RECT).tolist() == [[[0.0, 0.0], [2.0, 0.0]]]
    assert clip_one([2.0, 0.25], [2.0, 0.75], RECT).tolist() == [[[2.0, 0.25], [2.0, 0.75]]]


def test_clip_non_convex_gives_two_pieces():
    # through the upper arm, across the notch, into the lower arm
    pieces = clip_one([0.0, 1.8], [2.2, 0.2], ELL)
    assert pieces.shape == (2, 2, 2)
    np.testing.assert_allclose(pieces[0], [[0.0, 1.8], [1.0, 1.8 - 1.6 / 2.2]], atol=1e-14)
    np.testing.assert_allclose(pieces[1], [[1.1, 1.0], [2.0, 1.8 - 1.6 * 2.0 / 2.2]], atol=1e-14)


def test_clip_through_the_reflex_vertex_is_one_piece():
    # the diagonal touches the boundary only at (1, 1), from inside
    assert clip_one([0.0, 2.0], [2.0, 0.0], ELL).tolist() == [[[0.0, 2.0], [2.0, 0.0]]]


def test_clip_touching_a_corner_from_outside_gives_nothing():
    assert clip_one([-1.0, 1.0], [1.0, -1.0], RECT).shape == (0, 2, 2)
    # the line x + y = 3 touches the L shape at its vertices (1, 2) and (2, 1) only
    assert clip_one([0.5, 2.5], [2.5, 0.5], ELL).shape == (0, 2, 2)


def test_clip_many_segments_keeps_parents_and_total_length():
    rng = np.random.default_rng(11)
    n = 4000
    c = rng.uniform(-0.5, 2.5, size=(n, 2))
    th = rng.uniform(0, np.pi, n)
    h = 0.4 * np.stack([np.cos(th), np.sin(th)], axis=1)
    segs = np.stack([c - h, c + h], axis=1)
    pieces, parent = clip_segments(segs, ELL)
    assert np.all(np.diff(parent) >= 0)
    assert np.all(points_in_polygon(0.5 * (pieces[:, 0] + pieces[:, 1]), ELL))
    # every piece lies on its parent's line, between the parent's endpoints
    d = segs[parent, 1] - segs[parent, 0]
    for end in (0, 1):
        w = pieces[:, end] - segs[parent, 0]
        assert np.max(np.abs(d[:, 0] * w[:, 1] - d[:, 1] * w[:, 0])) < 1e-12
    # total inside length agrees with a fine sampling of each segment
    t = (np.arange(400) + 0.5) / 400
    pts = segs[:, None, 0] + t[None, :, None] * (segs[:, None, 1] - segs[:, None, 0])
    frac = points_in_polygon(pts.reshape(-1, 2), ELL).reshape(n, -1).mean(axis=1)
    clipped = np.bincount(parent, np.linalg.norm(pieces[:, 1] - pieces[:, 0], axis=1), n)
    np.testing.assert_allclose(clipped, 0.8 * frac, atol=0.8 / 400 * 2.01)


def test_clip_rejects_bad_segments():
    with pytest.raises(DfnError, match=r"shape \(n, 2, 2\)"):
        clip_segments(np.zeros((3, 4)), RECT)
    with pytest.raises(DfnError, match="segment 1 is not finite"):
        clip_segments([[[0, 0], [1, 1]], [[0, np.inf], [1, 1]]], RECT)


def test_clip_empty_and_zero_length():
    pieces, parent = clip_segments(np.zeros((0, 2, 2)), RECT)
    assert pieces.shape == (0, 2, 2) and parent.shape == (0,)
    assert clip_one([0.5, 0.5], [0.5, 0.5], RECT).shape == (0, 2, 2)
