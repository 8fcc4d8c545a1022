"""The 3D cleaning rules: each tracker pain is cleaned, counted, and named by input number."""

import time

import numpy as np
import pytest

from geofrac.dfn3d.clean import (
    RULES,
    SNAP,
    box_corners,
    clean_discs,
    disc_pairs,
    seam_directions,
)
from geofrac.dfn3d.network import DiscNetwork, canonical_normals

BOX = np.array([[0.0, 0.0, 0.0], [1.0, 1.0, 1.0]])
TOL = 0.01


def _net(centres, normals, radii, sets=None):
    n = len(radii)
    return DiscNetwork(
        np.array(centres, dtype=float),
        canonical_normals(np.array(normals, dtype=float)),
        np.array(radii, dtype=float),
        np.zeros(n, dtype=np.int64) if sets is None else np.array(sets),
        ("a", "b"),
    )


# a far-away disc first, so that the affected fracture is not number 0
FAR = ([0.2, 0.2, 0.2], [0.0, 1.0, 0.0], 0.1)


def _with_far(centres, normals, radii):
    return _net([FAR[0], *centres], [FAR[1], *normals], [FAR[2], *radii])


def _clean(net, **kw):
    return clean_discs(net, box=BOX, tolerance=TOL, **kw)


def _gap_to_plane(net, a, b):
    """Gap between disc a's edge and disc b's plane (a perpendicular to b)."""
    extent = net.radius[a] * np.sqrt(1 - (net.normal[a] @ net.normal[b]) ** 2)
    return abs((net.centre[a] - net.centre[b]) @ net.normal[b]) - extent


def test_near_parallel_close_pair_drops_the_smaller():
    net = _with_far(
        [[0.5, 0.5, 0.5], [0.55, 0.5, 0.5 + 1e-4]], [[0, 0, 1], [0, 1e-3, 1]], [0.3, 0.2]
    )
    out, report = _clean(net)
    assert report.fractures("parallel") == [2]
    assert report.events["parallel"][0][1] == 1  # kept in favour of fracture 1
    assert report.kept.tolist() == [0, 1] and report.dropped == [2]
    np.testing.assert_array_equal(out.radius, net.radius[:2])


def test_near_parallel_but_apart_in_projection_is_kept():
    net = _net([[0.25, 0.5, 0.5], [0.75, 0.5, 0.5 + 1e-4]], [[0, 0, 1], [0, 0, 1]], [0.2, 0.2])
    out, report = _clean(net)
    assert report.summary() == "nothing to clean" and out.size == 2


@pytest.mark.parametrize("gap", [0.0, 1e-4, -1e-4])
def test_tee_and_near_tee_shrink_the_stem_to_the_tolerance(gap):
    """An exact T, a near-T 1e-4 short and one crossing by 1e-4 become gaps of SNAP·tol."""
    net = _with_far([[0.5, 0.5, 0.4], [0.5, 0.5, 0.6 + gap]], [[0, 0, 1], [1, 0, 0]], [0.3, 0.2])
    out, report = _clean(net)
    assert report.fractures("tee") == [2]
    assert report.events["tee"][0][1] == 1
    assert report.counts()["tee"] == 1 and report.passes == 2
    np.testing.assert_allclose(_gap_to_plane(out, 2, 1), SNAP * TOL, rtol=1e-9)
    np.testing.assert_array_equal(out.centre, net.centre)  # only radii change
    assert out.radius[1] == net.radius[1]


def test_a_gap_above_the_tolerance_is_left_alone():
    net = _net([[0.5, 0.5, 0.4], [0.5, 0.5, 0.6 + 2 * TOL]], [[0, 0, 1], [1, 0, 0]], [0.3, 0.2])
    out, report = _clean(net)
    assert report.summary() == "nothing to clean"
    np.testing.assert_array_equal(out.radius, net.radius)


def test_x_intersection_is_left_alone():
    net = _net([[0.5, 0.5, 0.5], [0.5, 0.5, 0.5]], [[0, 0, 1], [1, 0, 0]], [0.3, 0.2])
    out, report = _clean(net)
    assert report.summary() == "nothing to clean" and out.size == 2


@pytest.mark.parametrize("short", [0.0, 1e-4, -1e-4])
def test_tip_touching_or_just_short_of_a_face_is_pulled_back(short):
    """The top of a vertical disc at z = 1 - short: touching, 1e-4 short, 1e-4 through."""
    net = _with_far([[0.5, 0.5, 0.7 - short]], [[1, 0, 0]], [0.3])
    out, report = _clean(net)
    assert report.fractures("boundary_tip") == [1]
    top = out.centre[1, 2] + out.radius[1]
    np.testing.assert_allclose(1.0 - top, SNAP * TOL, rtol=1e-9)


def test_crossing_a_face_well_is_left_alone():
    net = _net([[0.5, 0.5, 0.9]], [[1, 0, 0]], [0.3])
    out, report = _clean(net)
    assert report.summary() == "nothing to clean" and out.radius[0] == 0.3


def test_crossing_a_box_edge_and_corner_is_left_alone():
    net = _net([[0.9, 0.9, 0.9], [0.5, 0.95, 0.95]], [[1, 1, 1], [1, 0, 0]], [0.3, 0.2])
    out, report = _clean(net)
    assert report.summary() == "nothing to clean" and out.size == 2


def test_edge_passing_a_box_edge_within_the_tolerance_is_shrunk():
    # vertical disc x = 0.5 centred 0.2 from the box edge y = z = 1 (in-plane), r just short
    d = np.hypot(0.1414, 0.1414)
    net = _net([[0.5, 1 - 0.1414, 1 - 0.1414]], [[1, 0, 0]], [d + 1e-4])
    out, report = _clean(net)
    assert report.fractures("boundary_edge") == [0]
    np.testing.assert_allclose(out.radius[0], d - SNAP * TOL, rtol=1e-9)


def test_plane_passing_a_box_corner_within_the_tolerance_is_shrunk_off_it():
    corner = np.ones(3)
    n = np.array([1.0, -1.0, 0.3]) / np.linalg.norm([1.0, -1.0, 0.3])
    inward = (0.5 - corner) - ((0.5 - corner) @ n) * n  # in-plane, towards the box
    centre = corner + 1e-4 * n + 0.3 * inward / np.linalg.norm(inward)
    net = _net([centre], [n], [0.5])
    out, report = _clean(net)
    assert report.fractures("boundary_corner") == [0]
    rho = 0.3  # the corner's in-plane distance from the centre
    assert rho - 3 * TOL < out.radius[0] <= rho - SNAP * TOL + 1e-12


def test_tiny_intersection_shrinks_the_smaller_disc():
    # two perpendicular discs whose chords on their common line overlap by 1e-4
    net = _with_far(
        [[0.5, 0.5, 0.5], [0.5, 0.5 + 0.3 + 0.15 - 1e-4, 0.5]], [[0, 0, 1], [1, 0, 0]], [0.3, 0.15]
    )
    out, report = _clean(net)
    assert report.fractures("tiny_intersection") == [2]
    assert report.events["tiny_intersection"][0][1] == 1
    # the smaller chord now ends SNAP·tol before the larger one's end (y = 0.8)
    np.testing.assert_allclose(out.centre[2, 1] - out.radius[2], 0.8 + SNAP * TOL, rtol=1e-9)


def test_near_edges_shrinks_the_smaller_disc():
    # the two chords end 1e-4 apart at the same end, overlapping by 0.2
    net = _net([[0.5, 0.5, 0.5], [0.5, 0.6 + 1e-4, 0.5]], [[0, 0, 1], [1, 0, 0]], [0.3, 0.2])
    out, report = _clean(net)
    assert report.fractures("near_edges") == [1]
    assert out.radius[1] < 0.2 - TOL


def test_junction_next_to_a_face_is_pulled_back():
    """Two discs crossing the face y = 1; disc 1's chord on their line ends 1e-4 past it."""
    h = 0.2 + 1e-4
    net = _with_far(
        [[0.7, 0.8, 0.5], [0.5, 0.85, 0.5]], [[0, 0, 1], [1, 0, 0]], [np.hypot(0.2, h), 0.3]
    )
    out, report = _clean(net)
    assert report.summary() == "junction_at_face 1"
    assert report.fractures("junction_at_face") == [1]
    end = out.centre[1, 1] + np.sqrt(out.radius[1] ** 2 - 0.2**2)  # chord end on x = 0.5
    np.testing.assert_allclose(end, 1.0 - SNAP * TOL, rtol=1e-9)


def test_outside_small_and_on_boundary_are_dropped():
    net = _net(
        [[1.5, 0.5, 0.5], [0.5, 0.5, 1.2], [0.5, 0.5, 0.5], [0.5, 0.5, 1e-3], [0.5, 0.5, 1.0]],
        [[1, 0, 0], [1, 0, 0], [0, 0, 1], [0, 0, 1], [1, 1, 1]],
        [0.3, 0.19, 0.005, 0.3, 0.2],
    )
    out, report = _clean(net)
    assert report.fractures("outside") == [0, 1]
    assert report.fractures("small") == [2]
    assert report.fractures("on_boundary") == [3]
    assert report.kept.tolist() == [4] and out.size == 1


def test_disc_missing_the_box_at_a_corner_is_outside():
    # the plane x + y + z = 3.3 misses the unit box; its bounding box still overlaps
    n = np.ones(3) / np.sqrt(3)
    centre = np.array([1.1, 1.1, 1.1]) + 0.05 * np.array([1, -1, 0])
    net = _net([centre], [n], [0.3])
    out, report = _clean(net)
    assert report.fractures("outside") == [0] and out.size == 0


def _random(count, seed=3, rmin=0.02, rmax=0.4):
    rng = np.random.default_rng(seed)
    centre = rng.uniform(0, 1, (count, 3))
    normal = canonical_normals(rng.normal(size=(count, 3)))
    u = rng.uniform(size=count)
    radius = (rmin**-2.5 + u * (rmax**-2.5 - rmin**-2.5)) ** (1 / -2.5)
    sets = rng.integers(0, 2, count)
    return DiscNetwork(centre, normal, radius, sets, ("a", "b"))


def test_random_network_settles_shrinks_only_and_cleans_again_to_nothing():
    net = _random(1500)
    start = time.perf_counter()
    out, report = clean_discs(net, box=BOX, tolerance=5e-3)
    assert time.perf_counter() - start < 5.0
    kept = report.kept
    assert out.size == len(kept) < net.size
    np.testing.assert_array_equal(out.centre, net.centre[kept])
    np.testing.assert_array_equal(out.normal, net.normal[kept])
    np.testing.assert_array_equal(out.set_index, net.set_index[kept])
    assert np.all(out.radius <= net.radius[kept]) and np.all(out.radius >= 5e-3)
    shrunk = kept[out.radius < net.radius[kept]]
    assert shrunk.tolist() == report.shrunk
    assert set(report.dropped).isdisjoint(kept.tolist())
    assert len(report.dropped) + len(kept) == net.size
    _, again = clean_discs(out, box=BOX, tolerance=5e-3)
    assert again.summary() == "nothing to clean"
    summary = report.as_dict()
    assert set(summary["counts"]) == set(RULES) and summary["kept"] == out.size


def test_disc_pairs_match_brute_force():
    net = _random(300, seed=5)
    i, j = disc_pairs(net.centre, net.normal, net.radius, pad=0.01)
    half = net.radius[:, None] * np.sqrt(1 - net.normal**2) + 0.01
    lo, hi = net.centre - half, net.centre + half
    overlap = np.all((lo[:, None] <= hi[None]) & (lo[None] <= hi[:, None]), axis=2)
    a, b = np.nonzero(np.triu(overlap, 1))
    assert sorted(zip(i.tolist(), j.tolist(), strict=True)) == sorted(
        zip(a.tolist(), b.tolist(), strict=True)
    )


def test_seam_avoids_the_crossings():
    net = _net([[0.5, 0.5, 0.5], [0.5, 0.5, 0.5]], [[0, 0, 1], [1, 0, 0]], [0.3, 0.2])
    seam = seam_directions(net, box=BOX)
    np.testing.assert_allclose(np.linalg.norm(seam, axis=1), 1.0)
    np.testing.assert_allclose(np.einsum("nk,nk->n", seam, net.normal), 0.0, atol=1e-12)
    # disc 0's edge is crossed by nothing (disc 1 is inside it); disc 1's edge by disc 0's
    # plane z = 0.5 at y = 0.5 ± 0.2: its seam is at z = 0.5 ± 0.2, far from them
    assert abs(abs(seam[1, 2]) - 1.0) < 1e-9


def test_box_corners_and_bad_input():
    corners = box_corners(BOX)
    assert corners.shape == (8, 3) and len({tuple(c) for c in corners.tolist()}) == 8
    net = _net([[0.5, 0.5, 0.5]], [[0, 0, 1]], [0.2])
    with pytest.raises(ValueError, match="tolerance"):
        clean_discs(net, box=BOX, tolerance=0.0)
    with pytest.raises(ValueError, match="box"):
        clean_discs(net, box=[[0, 0, 0], [1, 1, 0.01]], tolerance=0.01)
