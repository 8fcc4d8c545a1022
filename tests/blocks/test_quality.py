"""Block quality checks (geofrac.blocks.quality) on hand-built median-dual block sets."""

import dataclasses
import json

import numpy as np
import pytest

from geofrac.blocks import quality as q
from geofrac.blocks.model import Blocks
from tests.blocks.conftest import median_dual_2d, median_dual_3d, pieces_as_blocks, take_blocks


def flipped(blocks: Blocks, face: int) -> Blocks:
    """A copy with one face (3D) reversed."""
    faces = blocks.faces.copy()
    faces[face] = faces[face][::-1]
    return dataclasses.replace(blocks, faces=faces)


def interior_face(blocks: Blocks) -> int:
    """A face of an interior block (its first face)."""
    inner = np.flatnonzero(np.all((blocks.seeds > 0.01) & (blocks.seeds < 0.99), axis=1))
    return int(blocks.face_offsets[inner[0]])


def face_owner(blocks: Blocks, face: int) -> int:
    return int(np.searchsorted(blocks.face_offsets, face, side="right") - 1)


def unit_cube(shift: np.ndarray) -> Blocks:
    """One cube block [0, 1]^3 + shift, faces outward, itself its convex piece."""
    corners = np.array(
        [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [0, 0, 1], [1, 0, 1], [1, 1, 1], [0, 1, 1]],
        dtype=float,
    )
    hexa = np.arange(8)[None, :]
    return Blocks(
        dim=3,
        points=corners + shift,
        faces=hexa[0, q.HEX_FACES],
        face_offsets=np.array([0, 6]),
        pieces=hexa,
        piece_block=np.array([0]),
        ids=np.array([0]),
        seeds=(corners + shift).mean(axis=0, keepdims=True),
    )


def l_shape() -> Blocks:
    """2D: the L (unit square minus its upper-right quarter), counter-clockwise."""
    pts = np.array([[0, 0], [1, 0], [1, 0.5], [0.5, 0.5], [0.5, 1], [0, 1], [0.5, 0]], float)
    return Blocks(
        dim=2,
        points=pts,
        faces=np.array([[0], [6], [1], [2], [3], [4], [5]]),
        face_offsets=np.array([0, 7]),
        pieces=np.array([[0, 1, 2, 3], [0, 3, 4, 5]]),
        piece_block=np.array([0, 0]),
        ids=np.array([7]),
        seeds=np.array([[0.25, 0.25]]),
    )


@pytest.mark.parametrize("dual", ["dual2d", "dual3d"])
def test_volumes_tile_the_unit_domain(dual, request):
    blocks = request.getfixturevalue(dual)
    vol = q.block_volumes(blocks)
    assert abs(vol.sum() - 1.0) < 1e-12
    assert vol.min() > 0
    # the convex pieces are an independent split of the same blocks
    pieces = q.piece_volumes(blocks)
    assert pieces.min() > 0
    np.testing.assert_allclose(np.bincount(blocks.piece_block, pieces), vol, atol=1e-15)
    # first moments add up to the domain's: the centroid of the unit square/cube
    c = q.block_centroids(blocks)
    np.testing.assert_allclose((c * vol[:, None]).sum(axis=0), 0.5, atol=1e-14)


def test_exact_volume_and_centroid_of_known_shapes():
    cube = unit_cube(np.array([1e3, 2e3, -5e2]))  # far from the origin
    assert q.block_volumes(cube)[0] == pytest.approx(1.0, abs=1e-9)
    np.testing.assert_allclose(q.block_centroids(cube)[0], [1000.5, 2000.5, -499.5], atol=1e-9)
    assert q.euler_characteristic(cube)[0] == 2
    assert q.check_closed(cube)[0]
    ell = l_shape()
    assert q.block_volumes(ell)[0] == pytest.approx(0.75, abs=1e-15)
    # centroid of the L: (3 squares of 1/4 at (1/4,1/4), (3/4,1/4), (1/4,3/4)) / 3
    np.testing.assert_allclose(q.block_centroids(ell)[0], [5 / 12, 5 / 12], atol=1e-15)
    assert q.check_closed(ell)[0]
    assert q.piece_volumes(ell).sum() == pytest.approx(0.75, abs=1e-15)


def test_closed_and_euler_on_the_duals(dual2d, dual3d):
    assert q.check_closed(dual3d).all()
    assert (q.euler_characteristic(dual3d) == 2).all()
    assert q.check_closed(dual2d).all()
    assert (q.euler_characteristic(dual2d) == 1).all()


def test_flipped_face_is_not_closed_and_breaks_pairing(dual3d):
    face = interior_face(dual3d)
    bad = flipped(dual3d, face)
    closed = q.check_closed(bad)
    assert np.flatnonzero(~closed).tolist() == [face_owner(dual3d, face)]
    pairing = q.check_pairing(bad)
    assert pairing["same_orientation"] == 2  # the flipped face and its neighbour's copy
    assert pairing["bad_blocks"] == 2
    assert not pairing["ok"]
    assert q.check_pairing(dual3d)["ok"]


def test_missing_face_breaks_closure_euler_and_pairing(dual3d):
    face = interior_face(dual3d)
    keep = np.ones(len(dual3d.faces), dtype=bool)
    keep[face] = False
    owner = face_owner(dual3d, face)
    offsets = dual3d.face_offsets.copy()
    offsets[owner + 1 :] -= 1
    bad = dataclasses.replace(dual3d, faces=dual3d.faces[keep], face_offsets=offsets)
    assert np.flatnonzero(~q.check_closed(bad)).tolist() == [owner]
    assert q.euler_characteristic(bad)[owner] == 1  # a disc, not a sphere
    pairing = q.check_pairing(bad)
    assert pairing["unmatched_interior"] == 1
    assert not pairing["boundary_closed"]


def test_pairing_counts_of_the_duals(dual2d, dual3d):
    p3 = q.check_pairing(dual3d)
    # 3 x 3 x 3 cubes: 6 faces x 9 boundary squares x 2 triangles x 3 quads per triangle
    assert p3["boundary"] == 6 * 9 * 2 * 3
    assert p3["matched"] + p3["boundary"] == p3["faces"]
    assert p3["boundary_closed"]
    p2 = q.check_pairing(dual2d)
    assert p2["boundary"] == 4 * 4 * 2  # two half edges per boundary edge
    assert p2["ok"]
    # a non-box domain: every unpaired face counts as boundary, closure still checked
    anywhere = q.check_pairing(dual3d, on_boundary=lambda p: np.ones(len(p), bool))
    assert anywhere["ok"]
    nowhere = q.check_pairing(dual3d, on_boundary=lambda p: np.zeros(len(p), bool))
    assert nowhere["unmatched_interior"] == p3["boundary"]


def test_duplicated_block_is_caught(dual3d):
    inner = np.flatnonzero(np.all((dual3d.seeds > 0.01) & (dual3d.seeds < 0.99), axis=1))[0]
    twice = take_blocks(dual3d, np.r_[np.arange(dual3d.num_blocks), inner])
    pairing = q.check_pairing(twice)
    assert pairing["more_than_two"] == 3 * np.diff(dual3d.face_offsets)[inner]
    assert not pairing["ok"]
    assert q.block_volumes(twice).sum() > 1.0 + 1e-3
    # sample points inside the duplicated block are covered twice, elsewhere once
    rng = np.random.default_rng(0)
    samples = rng.random((3000, 3))
    count = q.overlap_samples(twice, samples)
    once = q.overlap_samples(dual3d, samples)
    assert (once == 1).all()
    assert set(np.unique(count)) == {1, 2}
    near = np.linalg.norm(samples - dual3d.seeds[inner], axis=1) < 0.1  # inside the block
    assert near.any()
    assert (count[near] == 2).all()


@pytest.mark.parametrize("dim", [2, 3])
def test_overlap_samples_cover_once_and_outside_zero(dim):
    blocks = median_dual_2d(6) if dim == 2 else median_dual_3d(4)
    rng = np.random.default_rng(dim)
    inside = rng.random((4000, dim))
    assert (q.overlap_samples(blocks, inside) == 1).all()
    outside = inside + 1.5
    assert (q.overlap_samples(blocks, outside) == 0).all()


def test_overlap_samples_on_graded_blocks():
    """Piece sizes spanning a factor ~20 use several levels of the search grid."""
    blocks = median_dual_2d(12)
    x = blocks.points
    graded = (np.expm1(3.0 * x)) / np.expm1(3.0)
    blocks = dataclasses.replace(blocks, points=graded)
    assert q.piece_volumes(blocks).max() / q.piece_volumes(blocks).min() > 100
    assert abs(q.block_volumes(blocks).sum() - 1.0) < 1e-12
    samples = np.random.default_rng(7).random((5000, 2))
    assert (q.overlap_samples(blocks, samples) == 1).all()


def test_face_planarity_and_validator_catch_a_moved_point(dual3d):
    assert q.face_planarity(dual3d).max() < 1e-12
    face = interior_face(dual3d)
    point = dual3d.faces[face, 1]
    moved = dual3d.points.copy()
    moved[point] += [0.0, 0.0, 0.05]
    bad = dataclasses.replace(dual3d, points=moved)
    planarity = q.face_planarity(bad)
    users = np.flatnonzero(np.any(dual3d.faces == point, axis=1))
    assert planarity[users].max() > 0.05
    assert np.all(np.delete(planarity, users) < 1e-12)
    summary = q.summarize(bad, 1.0, validate=False)
    owners = np.unique(np.searchsorted(dual3d.face_offsets, users, side="right") - 1)
    assert summary["non_planar"] == summary["invalid_blocks"] == len(owners)
    # VTK checks planarity only on convex polyhedra: the hexahedral pieces as blocks
    hexes = pieces_as_blocks(dual3d)
    assert q.validate_cells(hexes)["failed"] == 0
    report = q.validate_cells(dataclasses.replace(hexes, points=moved))
    assert report["states"]["NON_PLANAR_FACES"] >= 1
    assert report["failed"] >= 1


def test_validator_on_valid_and_flipped_blocks(dual2d, dual3d):
    ok3 = q.validate_cells(dual3d)
    assert ok3["checked"] == dual3d.num_blocks
    assert ok3["failed"] == 0
    assert ok3["non_convex"] > 0  # median-dual blocks are not convex, which is fine
    # the counts read one way: every checked block passed, though VTK flagged some
    assert ok3["passed"] == ok3["checked"] and ok3["no_flags"] < ok3["passed"]
    assert q.validate_cells(dual2d)["failed"] == 0
    face = interior_face(dual3d)
    bad = flipped(dual3d, face)
    report = q.validate_cells(bad)
    assert report["passed"] + report["failed"] == report["checked"]
    assert report["states"]["INVERTED_FACES"] >= 1
    owner = face_owner(dual3d, face)
    # VTK's inverted-face test is a centroid heuristic, not trusted on non-convex blocks;
    # the exact orientation test is closure, which catches the flipped face
    assert owner in report["failed_blocks"] or report["inverted_faces_non_convex"] >= 1
    assert not q.check_closed(bad)[owner]
    assert q.summarize(bad, 1.0, validate=False)["invalid_blocks"] >= 1
    sampled = q.validate_cells(dual3d, sample=10, seed=3)
    assert sampled["checked"] == 10


def test_ring_checks_2d(dual2d):
    ell = l_shape()
    square = np.array([[0, 0], [1, 0], [1, 1], [0, 1]], float)
    bow = dataclasses.replace(  # (0,0) (1,0) (0,1) (1,1): two edges cross
        ell, points=square, faces=np.array([[0], [1], [3], [2]]), face_offsets=[0, 4]
    )
    assert not q.check_closed(bow)[0]
    good = dataclasses.replace(bow, faces=np.array([[0], [1], [2], [3]]))
    assert q.check_closed(good)[0]
    repeated = dataclasses.replace(ell, faces=np.r_[ell.faces, ell.faces[:1]], face_offsets=[0, 8])
    assert not q.check_closed(repeated)[0]
    # a reversed ring is still a simple ring, but clockwise: negative area, pairing broken
    b = 7
    ring = dual2d.faces.copy()
    lo, hi = dual2d.face_offsets[b], dual2d.face_offsets[b + 1]
    ring[lo:hi] = ring[lo:hi][::-1]
    rev = dataclasses.replace(dual2d, faces=ring)
    assert q.block_volumes(rev)[b] < 0
    assert not q.check_pairing(rev)["ok"]
    assert q.summarize(rev, 1.0, validate=False)["invalid_blocks"] == 1


def test_summarize_is_json_ready_and_flags_invalid_blocks(dual3d):
    report = q.summarize(dual3d, 1.0)
    json.dumps(report)
    assert report["count"] == dual3d.num_blocks
    assert abs(report["volume_rel_error"]) < 1e-12
    assert report["invalid_blocks"] == 0
    assert report["pairing"]["ok"]
    d = report["equivalent_diameter"]
    assert d["min"] <= d["mean"] <= d["max"]
    assert report["aspect_ratio"]["min"] > 1.0
    bad = q.summarize(flipped(dual3d, interior_face(dual3d)), 1.0, validate=False)
    assert bad["invalid_blocks"] == 1
    assert bad["not_closed"] == 1


def test_exact_self_intersection_test_finds_a_pushed_through_point():
    from geofrac.blocks.immobile import surface_block

    corners = np.array(
        [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [0, 0, 1], [1, 0, 1], [1, 1, 1], [0, 1, 1]],
        float,
    )
    quads = [(0, 3, 2, 1), (4, 5, 6, 7), (0, 1, 5, 4), (1, 2, 6, 5), (2, 3, 7, 6), (3, 0, 4, 7)]
    tris = np.array([t for a, b, c, d in quads for t in ((a, b, c), (a, c, d))])
    cube = surface_block(corners, tris)
    assert q.self_intersections(cube, 0) == 0
    dented = corners.copy()
    dented[6] = [0.5, 0.5, -0.5]  # the top corner pushed down through the bottom face
    assert q.self_intersections(surface_block(dented, tris), 0) > 0


def _subdivided_cube_surface(n):
    """Outward triangles of the unit cube's surface, n x n squares per side."""
    g = np.linspace(0.0, 1.0, n + 1)
    points, tris = [], []
    for axis in range(3):
        for side in (0.0, 1.0):
            u, v = np.meshgrid(g, g, indexing="ij")
            p = np.zeros((n + 1, n + 1, 3))
            p[..., axis] = side
            p[..., (axis + 1) % 3], p[..., (axis + 2) % 3] = u, v
            base = sum(len(x) for x in points)
            points.append(p.reshape(-1, 3))
            idx = base + np.arange((n + 1) ** 2).reshape(n + 1, n + 1)
            a, b = idx[:-1, :-1].ravel(), idx[1:, :-1].ravel()
            c, d = idx[1:, 1:].ravel(), idx[:-1, 1:].ravel()
            t = np.concatenate([np.column_stack([a, b, c]), np.column_stack([a, c, d])])
            if side == 0.0:  # (u, v, axis) is right-handed: flip the low side outward
                t = t[:, [0, 2, 1]]
            tris.append(t)
    points = np.concatenate(points)
    unique, inverse = np.unique(np.round(points, 12), axis=0, return_inverse=True)
    return unique, inverse.ravel()[np.concatenate(tris)]


def test_a_block_of_many_faces_gets_the_exact_test_instead_of_vtk():
    from geofrac.blocks.immobile import surface_block

    points, tris = _subdivided_cube_surface(20)  # 2400 triangles, 7200 quads
    block = surface_block(points, tris)
    assert abs(q.block_volumes(block)[0] - 1.0) < 1e-12
    report = q.validate_cells(block)
    assert report["large_exact"] == 1 and report["checked"] == 1 and report["failed"] == 0
    centre = np.flatnonzero(np.all(np.isclose(points, [0.5, 0.5, 1.0]), axis=1))[0]
    points[centre, 2] = -0.5  # pushed from the top through the bottom
    report = q.validate_cells(surface_block(points, tris))
    assert report["failed"] == 1 and report["failed_blocks"] == [0]


@pytest.mark.parametrize("dual", ["dual2d", "dual3d"])
def test_block_checks_of_parts_concatenate_to_the_whole(dual, request):
    # what the ranks rely on: each checks its own blocks, rank 0 concatenates in join order
    from geofrac.blocks.model import join

    blocks = request.getfixturevalue(dual)
    n = blocks.num_blocks
    first = take_blocks(blocks, np.arange(n // 3))
    second = take_blocks(blocks, np.arange(n // 3, n))
    whole = q.block_checks(join(first, second))
    parts = [q.block_checks(first), q.block_checks(second)]
    for key, values in whole.items():
        np.testing.assert_allclose(np.concatenate([p[key] for p in parts]), values, rtol=1e-12)
    report = q.summarize(blocks, 1.0, validate=False, checked=whole)
    assert report == q.summarize(blocks, 1.0, validate=False)
    with pytest.raises(ValueError, match="one value per block"):
        q.summarize(blocks, 1.0, validate=False, checked=parts[0])
