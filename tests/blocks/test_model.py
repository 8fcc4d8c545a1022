"""Block set containers (geofrac.blocks.model)."""

import numpy as np
import pytest

from geofrac.blocks.model import _lexicographic_order, weld


@pytest.mark.parametrize(
    "points",
    [
        np.random.default_rng(0).integers(0, 3, (500, 3)).astype(float),  # mostly ties
        np.random.default_rng(1).normal(size=(300, 2)),  # no ties
        np.zeros((0, 3)),
    ],
)
def test_lexicographic_order_is_numpys_stable_lexsort(points):
    np.testing.assert_array_equal(_lexicographic_order(points), np.lexsort(points.T[::-1]))


def test_weld_merges_exactly_equal_points_only(dual3d):
    from geofrac.blocks.model import join

    twice = join(dual3d, dual3d)  # every point twice
    twice.points[-1] += 1e-15  # no longer equal to its twin
    welded = weld(twice)
    assert len(welded.points) == len(dual3d.points) + 1
    np.testing.assert_array_equal(welded.points[welded.faces], twice.points[twice.faces])
