"""The initial stress field at points (pure numpy): constant, geostatic, layers, tectonic.

References are the closed forms of a rock column at rest: σv = −g Σ ρ_k h_k over the
layers above a point, σh = K0 σv (compression negative).
"""

import numpy as np
import pytest

from geofrac.geometry.insitu import (
    StressField,
    column_weight,
    evaluate,
    out_of_plane,
    surface_height,
)

G = 9.81


def test_constant_is_the_tensor_everywhere_plus_nothing():
    field = StressField(dim=2, kind="constant", stress=(-5.0, -10.0, 1.0))
    out = evaluate(field, np.array([[0.0, 0.0], [3.0, -7.0]]), np.array([1, 2]))
    assert out.shape == (2, 3)
    np.testing.assert_array_equal(out, [[-5.0, -10.0, 1.0]] * 2)


def test_geostatic_level_surface_2d_with_k0_per_region_and_tectonic():
    field = StressField(
        dim=2,
        kind="geostatic",
        surface=100.0,
        gravity=G,
        density=2500.0,
        k0=0.5,
        k0s={7: 2.0},
        tectonic=(-1e6, 0.0, 0.0),
    )
    points = np.array([[0.0, 40.0], [5.0, 40.0], [0.0, 120.0]])
    out = evaluate(field, points, np.array([3, 7, 3]))
    sv = -2500.0 * G * 60.0
    np.testing.assert_allclose(out[0], [0.5 * sv - 1e6, sv, 0.0])
    np.testing.assert_allclose(out[1], [2.0 * sv - 1e6, sv, 0.0])
    np.testing.assert_allclose(out[2], [-1e6, 0.0, 0.0])  # above the surface: no weight


def test_geostatic_3d_vertical_is_z():
    field = StressField(dim=3, kind="geostatic", surface=10.0, gravity=G, density=2000.0, k0=0.25)
    out = evaluate(field, np.array([[1.0, 2.0, 4.0]]), np.array([1]))
    sv = -2000.0 * G * 6.0
    np.testing.assert_allclose(out[0], [0.25 * sv, 0.25 * sv, sv, 0.0, 0.0, 0.0])


def test_polyline_surface_interpolates_and_refuses_points_outside_it():
    field = StressField(
        dim=2, kind="geostatic", surface=((0.0, 10.0), (10.0, 20.0)), gravity=G, density=1.0
    )
    np.testing.assert_allclose(surface_height(field, np.array([0.0, 2.5, 10.0])), [10, 12.5, 20])
    out = evaluate(field, np.array([[5.0, 0.0]]), np.array([0]))
    assert out[0, 1] == pytest.approx(-G * 15.0)
    with pytest.raises(ValueError, match="outside the surface polyline"):
        evaluate(field, np.array([[11.0, 0.0]]), np.array([0]))


def _layered_block() -> tuple[np.ndarray, np.ndarray]:
    """A 4 x 3 block of two layers, y in [0, 1] (ρ 3000) and [1, 3] (ρ 2000), as triangles."""
    tris, rho = [], []
    for (y0, y1), r in (((0.0, 1.0), 3000.0), ((1.0, 3.0), 2000.0)):
        for x0 in (0.0, 1.0, 2.5):  # uneven columns
            x1 = {0.0: 1.0, 1.0: 2.5, 2.5: 4.0}[x0]
            tris += [[(x0, y0), (x1, y0), (x1, y1)], [(x0, y0), (x1, y1), (x0, y1)]]
            rho += [r, r]
    return np.array(tris), np.array(rho)


def test_column_weight_sums_the_layers_above_each_point_exactly():
    tris, rho = _layered_block()
    points = np.array([[0.3, 0.5], [1.7, 2.0], [4.0, 0.0], [2.5, 1.0]])
    surface = np.full(4, 5.0)  # 2 m of cover above the block, at the density above
    got = column_weight(points, tris, rho, surface=surface, above=1500.0)
    expected = [
        3000 * 0.5 + 2000 * 2 + 1500 * 2,
        2000 * 1 + 1500 * 2,
        3000 * 1 + 2000 * 2 + 1500 * 2,
        2000 * 2 + 1500 * 2,
    ]
    np.testing.assert_allclose(got, expected, rtol=1e-12)
    # round-off off the mesh's right side or an inner vertical edge changes nothing
    nudged = np.array([[4.0 + 1e-13, 0.0], [1.0 - 1e-14, 0.5], [1.0 + 1e-14, 0.5]])
    got = column_weight(nudged, tris, rho, surface=np.full(3, 5.0), above=1500.0)
    np.testing.assert_allclose(got, [expected[2], expected[0], expected[0]], rtol=1e-12)
    # a surface inside the block clips the column there
    low = column_weight(points[:1], tris, rho, surface=np.array([2.0]), above=1500.0)
    np.testing.assert_allclose(low, [3000 * 0.5 + 2000 * 1.0])


def test_layered_geostatic_stress_uses_the_column():
    tris, rho = _layered_block()
    field = StressField(dim=2, kind="geostatic", surface=3.0, gravity=G, density=2000.0, k0=1.0)
    points = np.array([[1.0, 0.0]])
    column = column_weight(points, tris, rho, surface=np.array([3.0]), above=2000.0)
    out = evaluate(field, points, np.array([0]), column=column)
    assert out[0, 1] == pytest.approx(-G * (3000 * 1 + 2000 * 2))


def test_out_of_plane_is_nu_times_the_in_plane_sum_in_plane_strain():
    voigt = np.array([[-2.0, -6.0, 1.0]])
    np.testing.assert_allclose(out_of_plane(voigt, nu=0.25, plane="strain"), [-2.0])
    np.testing.assert_allclose(out_of_plane(voigt, nu=0.25, plane="stress"), [0.0])
    # geostatic with the default K0 = ν/(1 − ν): σzz = K0 σv, the horizontal stress
    nu = 0.2
    sv = -1.0
    k0 = nu / (1 - nu)
    np.testing.assert_allclose(
        out_of_plane(np.array([[k0 * sv, sv, 0.0]]), nu=nu, plane="strain"), [k0 * sv]
    )
