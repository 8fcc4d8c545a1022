"""Polygonal blocks from triangles (Edo (2016), §5.2.2(a), Fig. 5.6-5.8)."""

import numpy as np
import pytest

from geofrac.blocks.dual2d import blocks_2d
from geofrac.geometry.triangles import inner_points
from tests.blocks.conftest import square_mesh


def _mesh(n=6, seed=0, amount=0.3):
    points, tris = square_mesh(n)
    inside = np.all((points > 0) & (points < 1), axis=1)
    points[inside] += np.random.default_rng(seed).uniform(-amount, amount, (inside.sum(), 2)) / n
    return points, tris


def _ring_areas(blocks):
    areas = []
    for b in range(blocks.num_blocks):
        r = blocks.points[blocks.faces[blocks.face_offsets[b] : blocks.face_offsets[b + 1], 0]]
        areas.append(0.5 * np.sum(r[:, 0] * np.roll(r[:, 1], -1) - np.roll(r[:, 0], -1) * r[:, 1]))
    return np.array(areas)


def _turns(quads):
    """Cross products of consecutive edges at each corner of CCW quads, shape=(n, 4)."""
    d = np.roll(quads, -1, axis=1) - quads
    return (
        d[:, :, 0] * np.roll(d, -1, axis=1)[:, :, 1] - d[:, :, 1] * np.roll(d, -1, axis=1)[:, :, 0]
    )


def _piece_areas(blocks):
    q = blocks.points[blocks.pieces]
    a = 0.5 * np.sum(
        q[:, :, 0] * np.roll(q[:, :, 1], -1, 1) - np.roll(q[:, :, 0], -1, 1) * q[:, :, 1], 1
    )
    return np.bincount(blocks.piece_block, weights=a, minlength=blocks.num_blocks)


@pytest.mark.parametrize("inner", ["incentre", "random"])
def test_rings_are_counter_clockwise_and_tile_the_square(inner):
    points, tris = _mesh()
    tris[::3] = tris[::3][:, [0, 2, 1]]  # clockwise triangles give the same blocks
    blocks = blocks_2d(points, tris, inner=inner, seed=7)
    areas = _ring_areas(blocks)
    assert areas.min() > 0
    assert abs(areas.sum() - 1.0) < 1e-12
    np.testing.assert_allclose(areas, _piece_areas(blocks), rtol=1e-12)


def test_boundary_vertices_keep_their_boundary_pieces():
    points, tris = _mesh(4, seed=1)
    blocks = blocks_2d(points, tris)
    on_boundary = np.any((points == 0) | (points == 1), axis=1)
    for b in range(blocks.num_blocks):
        ring = blocks.points[blocks.faces[blocks.face_offsets[b] : blocks.face_offsets[b + 1], 0]]
        assert np.any(np.all(ring == points[blocks.ids[b]], axis=1)) == on_boundary[blocks.ids[b]]
    corner = np.flatnonzero((points[:, 0] == 1) & (points[:, 1] == 0))[0]  # in one triangle
    b = int(np.searchsorted(blocks.ids, corner))
    assert blocks.face_offsets[b + 1] - blocks.face_offsets[b] == 4  # v, m, incentre, m


def test_incentre_pieces_are_convex_random_ones_can_be_concave_unless_asked():
    points, tris = _mesh(12, seed=2, amount=0.25)
    incentre = blocks_2d(points, tris)
    assert _turns(incentre.points[incentre.pieces]).min() > 0
    loose = blocks_2d(points, tris, inner="random", radius=1.0, seed=3)
    assert _turns(loose.points[loose.pieces]).min() < 0  # a dart: the doc's warning
    convex = blocks_2d(points, tris, inner="random", radius=1.0, convex=True, seed=3)
    assert _turns(convex.points[convex.pieces]).min() > 0
    np.testing.assert_allclose(_ring_areas(convex).sum(), 1.0, rtol=1e-12)


def test_random_points_stay_in_the_movable_region():
    points, tris = _mesh(8, seed=4)
    x = points[np.sort(tris, axis=1)]
    keys = np.arange(len(tris))
    centre = inner_points(x, keys)
    side = np.linalg.norm(x[:, [2, 0, 1]] - x[:, [1, 2, 0]], axis=2)
    e1, e2 = x[:, 1] - x[:, 0], x[:, 2] - x[:, 0]
    r = np.abs(e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0]) / side.sum(axis=1)
    for radius in (0.0, 0.3, 1.0):
        p = inner_points(x, keys, "random", radius=radius, seed=5)
        distance = np.linalg.norm(p - centre, axis=1)
        assert np.all(distance <= radius * r * (1 + 1e-12) + 1e-15)
    spread = (
        np.linalg.norm(inner_points(x, keys, "random", radius=1.0, seed=5) - centre, axis=1) / r
    )
    assert spread.max() > 0.8  # the whole disc is used, not only its middle
    assert not np.allclose(inner_points(x, keys, "random", radius=1.0, seed=6), p)  # seed matters


def test_blocks_do_not_depend_on_the_order_of_the_triangles():
    points, tris = _mesh(5, seed=5)
    a = blocks_2d(points, tris, inner="random", seed=9)
    b = blocks_2d(
        points, tris[np.random.default_rng(0).permutation(len(tris))], inner="random", seed=9
    )
    np.testing.assert_array_equal(a.ids, b.ids)
    np.testing.assert_array_equal(_ring_areas(a), _ring_areas(b))


def test_a_vertex_shared_by_two_separate_fans_is_refused():
    points = np.array([[0.0, 0], [1, 0], [0, 1], [-1, 0], [0, -1]])
    tris = np.array([[0, 1, 2], [0, 3, 4]])  # two triangles touching only at vertex 0
    with pytest.raises(ValueError, match="one fan"):
        blocks_2d(points, tris)


def test_unknown_inner_point_is_refused():
    points, tris = square_mesh(1)
    with pytest.raises(ValueError, match="inner point 'centroid'"):
        blocks_2d(points, tris, inner="centroid")
