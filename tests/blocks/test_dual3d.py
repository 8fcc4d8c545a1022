"""Polyhedral blocks from tetrahedra (Edo (2016), §5.2.2(b)): geometry from first principles."""

import numpy as np
import pytest

from geofrac.blocks.dual3d import blocks_3d
from tests.blocks.conftest import cube_mesh


def _face_volumes(blocks):
    """Signed volume each quad face contributes (divergence theorem), shape=(num_faces,)."""
    p = blocks.points[blocks.faces]
    t1 = np.einsum("ij,ij->i", p[:, 0], np.cross(p[:, 1], p[:, 2]))
    t2 = np.einsum("ij,ij->i", p[:, 0], np.cross(p[:, 2], p[:, 3]))
    return (t1 + t2) / 6.0


def _volumes(blocks):
    return np.add.reduceat(_face_volumes(blocks), blocks.face_offsets[:-1])


def _tet_volumes(points, tets):
    p = points[tets]
    return (
        np.abs(
            np.einsum("ij,ij->i", p[:, 1] - p[:, 0], np.cross(p[:, 2] - p[:, 0], p[:, 3] - p[:, 0]))
        )
        / 6.0
    )


def _perturbed_cube(n, seed=0, amount=0.3):
    points, tets = cube_mesh(n)
    inside = np.all((points > 0) & (points < 1), axis=1)
    rng = np.random.default_rng(seed)
    points[inside] += rng.uniform(-amount, amount, (inside.sum(), 3)) / n
    return points, tets


def test_one_tetrahedron_gives_four_blocks_of_six_faces_and_a_quarter_volume():
    points = np.array([[0.0, 0, 0], [2, 0, 0], [0, 1, 0], [0.3, 0.2, 1.5]])
    blocks = blocks_3d(points, np.array([[0, 1, 2, 3]]))
    assert blocks.num_blocks == 4
    np.testing.assert_array_equal(np.diff(blocks.face_offsets), 6)  # Edo (2016): 6 faces each
    volume = _tet_volumes(points, np.array([[0, 1, 2, 3]]))[0]
    np.testing.assert_allclose(_volumes(blocks), volume / 4, rtol=1e-13)


@pytest.mark.parametrize("flip", [False, True])
def test_block_volumes_are_a_quarter_of_their_tetrahedra_and_fill_the_cube(flip):
    points, tets = _perturbed_cube(4)
    if flip:  # negatively oriented cells must give the same outward faces
        tets[::2] = tets[::2][:, [1, 0, 2, 3]]
    blocks = blocks_3d(points, tets)
    volumes = _volumes(blocks)
    expected = np.zeros(len(points))
    np.add.at(expected, tets.ravel(), np.repeat(_tet_volumes(points, tets) / 4, 4))
    np.testing.assert_allclose(volumes, expected[blocks.ids], rtol=1e-12, atol=1e-16)
    assert abs(volumes.sum() - 1.0) < 1e-12
    assert volumes.min() > 0


def test_faces_are_planar_quads_closed_and_shared_in_opposite_orders():
    points, tets = _perturbed_cube(3, seed=1)
    blocks = blocks_3d(points, tets)
    p = blocks.points[blocks.faces]
    normal = np.cross(p[:, 2] - p[:, 0], p[:, 3] - p[:, 1])
    off_plane = np.abs(np.einsum("ij,ij->i", normal, p[:, 1] - p[:, 0]))
    assert off_plane.max() < 1e-13 * np.linalg.norm(normal, axis=1).max()
    block_of = np.repeat(np.arange(blocks.num_blocks), np.diff(blocks.face_offsets))
    f = blocks.faces
    edges = np.stack([f, np.roll(f, -1, axis=1)], axis=2).reshape(-1, 2)
    edge_block = np.repeat(block_of, 4)
    forward = {(b, u, v) for b, (u, v) in zip(edge_block.tolist(), edges.tolist(), strict=True)}
    assert len(forward) == len(edges)  # no directed edge twice in a block
    assert all((b, v, u) in forward for b, u, v in forward)  # each has its reverse: closed
    # a face is on the cube's boundary or appears reversed in exactly one other block
    owner = {}
    for row, b in zip(f.tolist(), block_of.tolist(), strict=True):
        owner.setdefault(frozenset(row), []).append((b, row))
    unmatched = 0
    for sharing in owner.values():
        if len(sharing) == 1:
            unmatched += 1
            continue
        assert len(sharing) == 2
        (b1, r1), (b2, r2) = sharing
        assert b1 != b2
        assert any(
            r2 == [r1[0], r1[3], r1[2], r1[1]][s:] + [r1[0], r1[3], r1[2], r1[1]][:s]
            for s in range(4)
        )
    # unmatched faces are exactly the boundary quads: 3 per boundary triangle
    boundary_triangles = 2 * 6 * 3 * 3
    assert unmatched == 3 * boundary_triangles


def test_only_boundary_vertices_are_points_of_their_blocks():
    points, tets = _perturbed_cube(3, seed=2)
    blocks = blocks_3d(points, tets)
    on_boundary = np.any((points == 0) | (points == 1), axis=1)
    for b in range(blocks.num_blocks):
        mine = blocks.points[
            np.unique(blocks.faces[blocks.face_offsets[b] : blocks.face_offsets[b + 1]])
        ]
        has_seed = np.any(np.all(mine == points[blocks.ids[b]], axis=1))
        assert has_seed == on_boundary[blocks.ids[b]]


def test_pieces_are_convex_hexahedra_that_add_up_to_their_block():
    points, tets = _perturbed_cube(3, seed=3)
    tets[1::3] = tets[1::3][:, [0, 2, 1, 3]]
    blocks = blocks_3d(points, tets)
    hexa = blocks.points[blocks.pieces]  # VTK order
    faces = [(0, 3, 2, 1), (4, 5, 6, 7), (0, 1, 5, 4), (1, 2, 6, 5), (2, 3, 7, 6), (3, 0, 4, 7)]
    centre = hexa.mean(axis=1)
    volume = np.zeros(len(hexa))
    for f in faces:  # outward normals: every corner on the inner side of every face plane
        q = hexa[:, f]
        normal = np.cross(q[:, 2] - q[:, 0], q[:, 3] - q[:, 1])
        assert np.all(np.einsum("ij,ij->i", normal, centre - q[:, 0]) < 0)
        for c in range(8):
            assert np.all(np.einsum("ij,ij->i", normal, hexa[:, c] - q[:, 0]) < 1e-14)
        volume += (
            np.einsum("ij,ij->i", q[:, 0], np.cross(q[:, 1], q[:, 2]))
            + np.einsum("ij,ij->i", q[:, 0], np.cross(q[:, 2], q[:, 3]))
        ) / 6
    per_block = np.bincount(blocks.piece_block, weights=volume, minlength=blocks.num_blocks)
    np.testing.assert_allclose(per_block, _volumes(blocks), rtol=1e-12)
