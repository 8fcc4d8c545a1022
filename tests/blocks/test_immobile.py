"""The immobile part as one block (Edo (2016), §5.3.2), and joining/welding block sets."""

import numpy as np

from geofrac.blocks import quality as q
from geofrac.blocks.dual3d import blocks_3d
from geofrac.blocks.immobile import surface_block
from geofrac.blocks.model import join, weld
from tests.blocks.conftest import cube_mesh


def _box_surface(lo, hi):
    c = np.array(
        [[x, y, z] for z in (lo[2], hi[2]) for y in (lo[1], hi[1]) for x in (lo[0], hi[0])]
    )
    quads = [(0, 2, 3, 1), (4, 5, 7, 6), (0, 1, 5, 4), (2, 6, 7, 3), (0, 4, 6, 2), (1, 3, 7, 5)]
    return c.astype(float), np.array([t for a, b, cc, d in quads for t in ((a, b, cc), (a, cc, d))])


def test_a_box_surface_gives_one_closed_block_of_three_quads_per_triangle():
    points, tris = _box_surface([0, 0, 0], [2, 1, 3])
    block = surface_block(points, tris)
    assert block.num_blocks == 1 and block.kind[0] == 1 and block.ids[0] == -1
    assert len(block.faces) == 3 * len(tris)  # Edo (2016), §5.5: three faces per triangle
    assert abs(q.block_volumes(block)[0] - 6.0) < 1e-12
    assert q.check_closed(block)[0] and q.euler_characteristic(block)[0] == 2
    np.testing.assert_allclose(block.seeds[0], [1, 0.5, 1.5], atol=1e-12)


def test_welding_merges_identical_points_so_an_overlap_shows_in_the_pairing():
    points, tets = cube_mesh(2)
    layer = blocks_3d(points, tets)
    everywhere = lambda p: np.ones(len(p), bool)  # noqa: E731
    twice = join(layer, layer)
    assert q.check_pairing(twice, everywhere)["ok"]  # two unconnected copies: blind
    welded = weld(twice)
    assert len(welded.points) == len(layer.points)
    report = q.check_pairing(welded, everywhere)
    assert not report["ok"] and report["bad_blocks"] == 2 * layer.num_blocks
    below_points, below_tris = _box_surface([0, 0, -1], [1, 1, 0])
    whole = weld(join(layer, surface_block(below_points, below_tris)))
    assert abs(q.block_volumes(whole).sum() - 2.0) < 1e-12
    assert len(whole.points) < len(layer.points) + 3 * len(below_tris)  # corners welded
