"""Compiled block loops (geofrac.blocks.kernels) against closed forms and brute force."""

from collections import defaultdict

import numpy as np
import pytest

from geofrac.blocks import kernels
from geofrac.blocks.model import HEX_FACES

CUBE = np.array(
    [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [0, 0, 1], [1, 0, 1], [1, 1, 1], [0, 1, 1]],
    dtype=float,
)


def brute_status(faces: np.ndarray, owner: np.ndarray) -> np.ndarray:
    """Pairing codes from every rotation and reflection of every face (no sorting trick)."""
    groups = defaultdict(list)
    for i, face in enumerate(faces.tolist()):
        k = len(face)
        rotations = [tuple(face[j:] + face[:j]) for j in range(k)]
        reflections = [tuple(r[::-1]) for r in rotations]
        key = min(rotations + reflections)
        groups[key].append((i, key in rotations))
    status = np.empty(len(faces), dtype=np.int8)
    for members in groups.values():
        if len(members) == 1:
            code = 1
        elif len(members) == 2:
            (i, si), (j, sj) = members
            code = 4 if owner[i] == owner[j] else (0 if si != sj else 3)
        else:
            code = 5
        for i, _ in members:
            status[i] = code
    return status


@pytest.mark.parametrize("pool", [6, 40])
def test_face_status_matches_brute_force(pool):
    # a pool of 6 points makes buckets of over 32 faces (the merge-sort branch) and
    # groups of more than two; 40 points mostly singles and pairs
    rng = np.random.default_rng(pool)
    faces = np.array([rng.choice(pool, 4, replace=False) for _ in range(300)])
    # pairs: reversed copies in other blocks, same-way copies, copies in the same block
    extra = faces[:60][:, ::-1].copy()
    extra[20:40] = np.roll(faces[20:40], 1, axis=1)
    faces = np.concatenate([faces, extra])
    owner = rng.integers(0, 5, len(faces))
    owner[300:340] = owner[:40] + 1
    owner[340:360] = owner[40:60]
    status = kernels.face_status(faces.astype(np.int32), owner, pool)
    np.testing.assert_array_equal(status, brute_status(faces, owner))
    assert set(np.unique(status)) >= ({0, 1, 3, 4} if pool == 40 else {5})


def test_face_status_of_edges():
    # 2D faces are ring edges: a reversed partner in another block pairs, the same way
    # or the same block does not; an edge alone is a single, three copies are too many
    faces = [[1, 2], [2, 1], [3, 4], [3, 4], [5, 6], [6, 5], [7, 8], [9, 10], [10, 9], [9, 10]]
    owner = np.array([0, 1, 0, 1, 0, 0, 2, 0, 1, 2])
    status = kernels.face_status(np.array(faces, dtype=np.int32), owner, 11)
    assert status.tolist() == [0, 0, 3, 3, 4, 4, 1, 5, 5, 5]


def cube_blocks(faces: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    return faces, np.array([0, len(faces)])


def test_edge_groups_of_a_cube_and_of_broken_cubes():
    closed, edges, vertices = kernels.edge_groups(*cube_blocks(HEX_FACES), 8)
    assert closed.tolist() == [True] and edges.tolist() == [12] and vertices.tolist() == [8]
    flipped = HEX_FACES.copy()
    flipped[2] = flipped[2][::-1]
    missing = HEX_FACES[1:]
    doubled = np.concatenate([HEX_FACES, HEX_FACES[:1]])
    pinched = HEX_FACES.copy()
    pinched[0, 1] = pinched[0, 0]  # an edge from a point to itself
    for broken in (flipped, missing, doubled, pinched):
        assert not kernels.edge_groups(*cube_blocks(broken), 8)[0][0]
    # two cubes and a block without faces: each judged alone
    faces = np.concatenate([HEX_FACES, HEX_FACES + 8])
    closed, _, _ = kernels.edge_groups(faces, np.array([0, 6, 12, 12]), 16)
    assert closed.tolist() == [True, True, False]


def test_unique_segments_are_each_segments_sorted_set():
    rng = np.random.default_rng(1)
    values = rng.integers(0, 30, 200)
    offsets = np.array([0, 0, 17, 17, 90, 200])
    new_off, uniq = kernels.unique_segments(values.astype(np.int32), offsets)
    for b in range(len(offsets) - 1):
        expected = sorted(set(values[offsets[b] : offsets[b + 1]].tolist()))
        assert uniq[new_off[b] : new_off[b + 1]].tolist() == expected


def test_integrals_of_a_cube_far_from_the_origin():
    shift = np.array([3.0e6, -2.0e6, 1.0e5])
    faces = np.concatenate([HEX_FACES, HEX_FACES[:, ::-1] + 8, np.zeros((1, 4), int) + 16])
    points = np.concatenate([CUBE * [2, 1, 1] + shift, CUBE, np.zeros((1, 3))])
    volume, centroid = kernels.block_integrals(points, faces, np.array([0, 6, 12, 13]))
    np.testing.assert_allclose(volume, [2.0, -1.0, 0.0], atol=1e-8)
    np.testing.assert_allclose(centroid[0], shift + np.array([1.0, 0.5, 0.5]), rtol=0, atol=1e-8)
    np.testing.assert_allclose(centroid[1], [0.5, 0.5, 0.5], atol=1e-12)
    assert np.isnan(centroid[2]).all()
    reach = kernels.reach(points, faces, np.array([0, 6, 12, 13]), centres=np.nan_to_num(centroid))
    np.testing.assert_allclose(reach[:2], [np.sqrt(1.5), np.sqrt(0.75)], rtol=1e-9)


@pytest.mark.parametrize("h", [0.0, 1e-3, 0.5])
def test_face_planarity_of_a_square_with_a_lifted_corner(h):
    # corner D of the unit square lifted by h: the diagonals' lines are h / sqrt(2 h^2 + 4)
    # apart; every corner is half that from the best plane; the diameter is |BD|
    rotation = np.linalg.qr(np.random.default_rng(2).normal(size=(3, 3)))[0]
    quad = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, h]]) @ rotation.T + 7.0
    value = kernels.face_planarity(quad, np.array([[0, 1, 2, 3]]))[0]
    expected = h / np.sqrt(2 * h**2 + 4) / 2 / np.sqrt(2 + h**2)
    assert value == pytest.approx(expected, rel=1e-9, abs=1e-15)


def test_quadrilateral_kernels_refuse_other_faces():
    with pytest.raises(ValueError, match="quadrilaterals"):
        kernels.block_integrals(CUBE, HEX_FACES[:, :3], np.array([0, 6]))
    with pytest.raises(ValueError, match="quadrilaterals"):
        kernels.face_planarity(CUBE, HEX_FACES[:, :3])


def test_face_stream_layout():
    faces = np.array([[0, 1, 2, 3], [3, 2, 1, 0], [4, 5, 6, 7]], dtype=np.int32)
    stream, ends = kernels.face_stream(faces, np.array([0, 2, 2, 3]))
    assert stream.tolist() == [2, 4, 0, 1, 2, 3, 4, 3, 2, 1, 0, 0, 1, 4, 4, 5, 6, 7]
    assert ends.tolist() == [11, 12, 18]
    assert stream.dtype == np.int32


def test_warm_up_compiles_every_kernel():
    ready = []
    assert kernels.warm_up(lambda name, seconds: ready.append(name)) >= 0.0
    assert set(ready) == set(kernels.__all__) - {"overlapping_pairs", "warm_up"}
    for name in ("_unique_segments", "_edge_groups", "_block_integrals", "_face_status"):
        assert getattr(kernels, name).signatures, name
