"""Region outlines: polygons from shapes, the bench-line cut, layout checks, cleaning rules.

The cleaning treats a region's outline like the boundary; fractures crossing it are split
there and stay fractures.

References are closed forms: the area of an inscribed regular polygon (n/2 R² sin(2π/n)),
of a fan of equal triangles minus the triangle on the chord, of a rectangle.
"""

import math

import numpy as np
import pytest

from geofrac.dfn.clean import clean_network
from geofrac.dfn.errors import DfnError
from geofrac.dfn.polygon import point_segment_distance, polygon_area, rectangle
from geofrac.dfn.regions import (
    Region,
    circle_polygon,
    cut_polygon,
    horseshoe_polygon,
    layout_regions,
    strictly_inside,
)
from geofrac.dfn.sampling import FractureSet, Network, generate_network

from .test_clean import _check_invariants, _unmodified_keep_their_length

DOMAIN = rectangle((-10.0, -10.0), (10.0, 10.0))
TOL = 0.05


def _network(*segments):
    segs = np.array(segments, dtype=float).reshape(-1, 2, 2)
    return Network(segs, np.zeros(len(segs), dtype=np.int64), ("s",))


def _tunnel(level=-0.5, radius=3.0, segments=48):
    full = circle_polygon([0.0, 0.0], radius, segments, level=level)
    heading = Region("heading", cut_polygon(full, level, keep="above"))
    bench = Region("bench", cut_polygon(full, level, keep="below"))
    return layout_regions([heading, bench], DOMAIN, tol=TOL, margin=1.0), full


# ------------------------------------------------------------------------------ shapes


@pytest.mark.parametrize("n", [3, 8, 64])
def test_circle_polygon_is_the_inscribed_regular_polygon(n):
    poly = circle_polygon([1.0, -2.0], 3.0, n)
    assert poly.shape == (n, 2)
    np.testing.assert_allclose(np.hypot(poly[:, 0] - 1.0, poly[:, 1] + 2.0), 3.0, rtol=1e-15)
    assert polygon_area(poly) == pytest.approx(n / 2 * 9.0 * math.sin(2 * math.pi / n), rel=1e-13)
    np.testing.assert_allclose(poly[0], [4.0, -2.0])
    if n % 4 == 0:  # the quarter points lie exactly on the axes
        assert poly[n // 4, 0] == 1.0 and poly[n // 2, 1] == -2.0


@pytest.mark.parametrize("level", [-2.0, -0.5, 0.0, 1.3])
def test_circle_cut_into_heading_and_bench(level):
    r, n = 3.0, 64
    full = circle_polygon([0.0, 0.0], r, n, level=level)
    above = cut_polygon(full, level, keep="above")
    below = cut_polygon(full, level, keep="below")
    # every vertex lies on the circle, and the cut points exactly on the line
    np.testing.assert_allclose(np.hypot(*full.T), r, rtol=1e-15)
    assert np.all(above[:, 1] >= level) and np.all(below[:, 1] <= level)
    on_line = lambda p: {tuple(v) for v in p[p[:, 1] == level]}  # noqa: E731
    assert on_line(above) == on_line(below) and len(on_line(above)) == 2  # the shared chord
    # the heading is a fan of equal triangles from the centre minus the chord's triangle
    beta = math.asin(level / r)
    k = len(above) - 1  # sides on the arc
    fan = k / 2 * r * r * math.sin((math.pi - 2 * beta) / k)
    assert polygon_area(above) == pytest.approx(fan - r * r * math.sin(beta) * math.cos(beta))
    assert polygon_area(above) + polygon_area(below) == pytest.approx(polygon_area(full), 1e-13)
    # no short side at the cut: every side is close to 2πR/n
    for part in (above[:-1], below[:-1]):  # the arcs (the chord is the last side)
        side = np.hypot(*np.diff(part, axis=0).T)
        assert side.min() > 0.5 * 2 * math.pi * r / n


def test_horseshoe_polygon_and_its_cuts():
    w, h, n = 6.0, 2.0, 16
    poly = horseshoe_polygon([0.0, 1.0], w, h, segments=n)
    assert poly.shape == (n + 3, 2)
    roof = n / 2 * 9.0 * math.sin(math.pi / n)
    assert polygon_area(poly) == pytest.approx(roof + w * h, rel=1e-13)
    assert poly[1 + n // 2].tolist() == [0.0, 4.0]  # the crown
    assert poly[0].tolist() == [3.0, -1.0] and poly[-1].tolist() == [-3.0, -1.0]  # the invert
    # cut at the springline: the roof and the rectangle below it
    full = horseshoe_polygon([0.0, 1.0], w, h, segments=n, level=1.0)
    assert polygon_area(cut_polygon(full, 1.0, keep="above")) == pytest.approx(roof, 1e-13)
    assert polygon_area(cut_polygon(full, 1.0, keep="below")) == pytest.approx(w * h, 1e-13)
    # cut inside the roof: the cut points are roof vertices on the line
    full = horseshoe_polygon([0.0, 1.0], w, h, segments=n, level=2.5)
    above = cut_polygon(full, 2.5, keep="above")
    assert np.sum(above[:, 1] == 2.5) == 2 and np.allclose(
        np.hypot(above[:, 0], above[:, 1] - 1), 3, rtol=1e-15
    )
    below = cut_polygon(full, 2.5, keep="below")
    assert polygon_area(above) + polygon_area(below) == pytest.approx(polygon_area(full), 1e-13)


def test_cut_of_a_square_and_a_line_that_misses():
    square = rectangle((0.0, 0.0), (2.0, 2.0))
    assert polygon_area(cut_polygon(square, 0.5, keep="above")) == pytest.approx(3.0)
    assert polygon_area(cut_polygon(square, 0.5, keep="below")) == pytest.approx(1.0)
    with pytest.raises(DfnError, match="leaves nothing"):
        cut_polygon(square, 2.0, keep="above")
    with pytest.raises(DfnError, match="misses the circle"):
        circle_polygon([0.0, 0.0], 1.0, 16, level=1.0)


# ------------------------------------------------------------------------------ layout


def test_heading_and_bench_share_the_bench_line():
    layout, full = _tunnel()
    assert layout.names == ("heading", "bench")
    assert len(layout.vertices) == len(full)  # the cut points are shared, not repeated
    assert len(layout.edges) == len(full) + 1  # the circle's sides plus the chord
    (he, hf), (be, bf) = layout.loops
    shared = set(he.tolist()) & set(be.tolist())
    assert len(shared) == 1  # the chord, run in opposite directions
    (chord,) = shared
    assert hf[he.tolist().index(chord)] != bf[be.tolist().index(chord)]
    assert np.all(layout.vertices[layout.edges[chord], 1] == -0.5)
    # the hole in the rock is the circle polygon, counter-clockwise
    (hole_edges, hole_fwd) = layout.holes[0]
    assert len(layout.holes) == 1 and chord not in hole_edges.tolist()
    start = np.where(hole_fwd, layout.edges[hole_edges, 0], layout.edges[hole_edges, 1])
    hole = layout.vertices[start]
    assert polygon_area(hole) == pytest.approx(polygon_area(full), rel=1e-13)
    x, y = hole.T
    assert 0.5 * np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y) > 0


def test_a_vertex_of_one_region_on_the_side_of_another_splits_that_side():
    a = Region("a", rectangle((-2.0, 0.0), (2.0, 1.0)))
    b = Region("b", rectangle((0.0, -1.0), (1.0, 0.0)))  # touches a's bottom in [0, 1]
    layout = layout_regions([a, b], DOMAIN, tol=TOL, margin=1.0)
    lengths = np.hypot(*np.diff(layout.segments, axis=1)[:, 0].T)
    assert len(layout.edges) == 4 + 4 - 1 + 2  # a's bottom in three pieces, one shared
    assert lengths.sum() == pytest.approx(10.0 + 4.0 - 1.0)
    assert len(layout.holes) == 1


@pytest.mark.parametrize(
    "regions, match",
    [
        ([rectangle((0, 0), (2, 2)), rectangle((1, 1), (3, 3))], "outlines cross"),
        ([rectangle((0, 0), (2, 2)), rectangle((0, 0), (2, 2))], "along their common edge"),
        ([rectangle((0, 0), (4, 4)), rectangle((1, 1), (2, 2))], "'b' and 'a' overlap"),
        ([rectangle((0, 0), (2, 2)), rectangle((0, 0), (1, 2))], "overlap"),
        ([rectangle((0, 0), (1, 1)), rectangle((1, 1), (2, 2))], "single point"),
        ([rectangle((5, 5), (9.5, 6))], "lies 0.5 from its boundary"),
        ([rectangle((5, 5), (12, 6))], "leaves the domain"),
        ([rectangle((0, 0), (2, 0.03))], "closer than the cleaning tolerance"),
    ],
)
def test_bad_layouts_are_errors_naming_the_regions(regions, match):
    named = [Region(name, poly) for name, poly in zip("abc", regions, strict=False)]
    with pytest.raises(DfnError, match=match):
        layout_regions(named, DOMAIN, tol=TOL, margin=1.0)


def test_regions_enclosing_rock_are_an_error():
    u_shape = np.array([[0, 0], [3, 0], [3, 3], [2, 3], [2, 1], [1, 1], [1, 3], [0, 3]], float)
    lid = rectangle((0.0, 3.0), (3.0, 4.0))
    with pytest.raises(DfnError, match="enclose rock"):
        layout_regions([Region("u", u_shape), Region("lid", lid)], DOMAIN, tol=TOL, margin=1.0)


# ---------------------------------------------------------------------- cleaning rules


def _clean(layout, *segments):
    return clean_network(_network(*segments), DOMAIN, TOL, constraints=layout.segments)


def _on_outline(points, layout, eps=1e-12):
    segs = layout.segments
    d, _ = point_segment_distance(points[:, None, :], segs[None, :, 0], segs[None, :, 1])
    return d.min(axis=1) <= eps * 20.0


def _left_wall(layout, y):
    """The x where the line at height y meets the outline on the left of the centre."""
    (a, b) = next(
        (a, b) for a, b in layout.segments if min(a[1], b[1]) < y < max(a[1], b[1]) and a[0] < 0
    )
    return a[0] + (y - a[1]) * (b[0] - a[0]) / (b[1] - a[1])


def _check_outline_invariants(clean, layout):
    """No edge crosses an outline; vertices and edges keep tol from it unless on it."""
    _check_invariants(clean)
    on = _on_outline(clean.vertices, layout)
    segs = layout.segments
    d, _ = point_segment_distance(clean.vertices[:, None, :], segs[None, :, 0], segs[None, :, 1])
    assert np.all(d.min(axis=1)[~on] >= TOL * (1 - 1e-12)), "vertex near an outline"
    # outline vertices keep tol from the edges they are not on
    e = clean.segments
    d, _ = point_segment_distance(layout.vertices[:, None, :], e[None, :, 0], e[None, :, 1])
    hit = (d < TOL) & (d > 1e-9)
    assert not hit.any(), "an outline corner near a fracture edge"
    # each edge lies inside one region or outside all of them (midpoints and ends agree)
    for region in layout.regions:
        mid_in = strictly_inside(e.mean(axis=1), region.polygon)
        for end in (0, 1):
            end_in = strictly_inside(e[:, end], region.polygon)
            off = ~_on_outline(e[:, end], layout)
            assert np.array_equal(mid_in[off], end_in[off])


def test_fracture_crossing_the_outline_is_split_there_and_not_moved():
    layout, _ = _tunnel()
    c = _clean(layout, [[-8.0, 1.0], [8.0, 1.7]])  # through the heading, both sides
    _check_outline_invariants(c, layout)
    assert not c.modified.any()
    _unmodified_keep_their_length(c)
    assert len(c.edges) == 3  # rock, heading, rock
    on = _on_outline(c.vertices, layout)
    assert on.sum() == 2
    np.testing.assert_allclose(np.hypot(*c.vertices[on].T), 3.0, rtol=0.01)  # on the circle
    assert c.report.counts()["crossings"] == 0  # not an X-junction between fractures


def test_fracture_through_heading_and_bench_is_split_at_the_bench_line():
    layout, _ = _tunnel()
    c = _clean(layout, [[0.0, -8.0], [0.05, 8.0]])  # crosses the circle between vertices
    _check_outline_invariants(c, layout)
    assert not c.modified.any() and len(c.edges) == 4  # rock, bench, heading, rock
    on = c.vertices[_on_outline(c.vertices, layout)]
    assert np.sum(np.abs(on[:, 1] + 0.5) < 1e-12) == 1 and len(on) == 3


def test_fracture_ending_just_short_of_the_outline_is_snapped_onto_it():
    layout, _ = _tunnel()
    c = _clean(layout, [[-8.0, 1.0], [_left_wall(layout, 1.0) - 0.03, 1.0]])  # 0.03 short
    _check_outline_invariants(c, layout)
    assert len(c.report.events["boundary_snap"]) == 1
    assert 0 < c.moved[0] < TOL
    assert _on_outline(c.vertices, layout).sum() == 1


def test_fracture_overshooting_the_outline_by_less_than_tol_leaves_no_stub():
    layout, _ = _tunnel()
    c = _clean(layout, [[-8.0, 1.0], [_left_wall(layout, 1.0) + 0.03, 1.0]])
    _check_outline_invariants(c, layout)
    assert len(c.edges) == 1 and c.moved[0] < TOL


def test_fracture_passing_near_an_outline_corner_is_bent_through_it():
    layout, _ = _tunnel()
    corner = layout.vertices[np.argmax(layout.vertices[:, 1])]  # a vertex at the crown
    normal = corner / np.hypot(*corner)
    tangent = np.array([-normal[1], normal[0]])
    p = corner + 0.02 * tangent  # a radial fracture passing 0.02 beside the vertex
    c = _clean(layout, [p - 2 * normal, p + 2 * normal])
    _check_outline_invariants(c, layout)
    assert any(np.all(v == corner) for v in c.vertices)
    assert len(c.report.events["tee_snap"]) == 1 and c.moved[0] == pytest.approx(0.02)


def test_fracture_along_the_bench_line_is_dropped():
    layout, _ = _tunnel()
    c = _clean(layout, [[-1.0, -0.48], [1.0, -0.49]], [[-8.0, 5.0], [8.0, 5.0]])
    assert [f for f, _, _ in c.report.events["on_boundary"]] == [0]
    assert np.all(c.edge_fracture == 1)
    # dropped whole as a piece along the outline, before any snapping
    assert c.moved[0] == np.inf and not c.report.events["boundary_snap"]


def test_junction_near_the_outline_is_snapped_onto_it():
    layout, _ = _tunnel(radius=3.0, segments=400 // 4)
    y = -0.5 + 0.02  # two fractures crossing 0.02 above the bench line
    c = _clean(layout, [[-1.0, y - 1.0], [1.0, y + 1.0]], [[-1.0, y + 1.0], [1.0, y - 1.0]])
    _check_outline_invariants(c, layout)
    on = c.vertices[_on_outline(c.vertices, layout)]
    assert len(on) == 1 and on[0, 1] == pytest.approx(-0.5, abs=1e-12)


def test_junction_angle_counts_the_outline():
    layout, _ = _tunnel()
    # crossing the bench line (horizontal) at 10 degrees
    t = math.radians(10.0)
    c = _clean(
        layout, [[-1.0 * math.cos(t), -0.5 - math.sin(t)], [math.cos(t), -0.5 + math.sin(t)]]
    )
    assert c.min_junction_angle() == pytest.approx(10.0, abs=1e-9)
    # without the outline the lone fracture meets nothing
    alone = clean_network(c.network, DOMAIN, TOL)
    assert alone.min_junction_angle() == 180.0


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_dense_random_networks_with_a_tunnel_satisfy_the_invariants(seed):
    layout, _ = _tunnel(segments=64)
    sets = [
        FractureSet("a", 30.0, 5.0, 1.0, 8.0, 2.0, p21=1.0),
        FractureSet("b", 115.0, 8.0, 1.0, 8.0, 2.0, p21=1.0),
    ]
    net = generate_network(sets, DOMAIN, seed, domain=DOMAIN)
    c = clean_network(net, DOMAIN, 0.1, constraints=layout.segments)
    tol = 0.1
    assert c.tol == tol
    _check_invariants(c)
    on = _on_outline(c.vertices, layout)
    d, _ = point_segment_distance(
        c.vertices[:, None, :], layout.segments[None, :, 0], layout.segments[None, :, 1]
    )
    assert np.all(d.min(axis=1)[~on] >= tol * (1 - 1e-12))
    e = c.segments  # no fracture edge crosses an outline: its midpoint is off the outline
    for region in layout.regions:
        ends_in = [
            strictly_inside(e[:, k], region.polygon) | _on_outline(e[:, k], layout) for k in (0, 1)
        ]
        mid_in = strictly_inside(e.mean(axis=1), region.polygon)
        assert np.all(~mid_in | (ends_in[0] & ends_in[1]))
    assert on.sum() > 10  # fractures cross the outline
    _unmodified_keep_their_length(c)
