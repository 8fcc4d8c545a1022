"""Landslide terrain (Edo (2016), §5.4, eq. 5.1, Fig. 5.23): moving tets + immobile patch."""

import math

import dolfinx_solver  # noqa: F401

import numpy as np
import pytest
from mpi4py import MPI

from geofrac.meshing.geo import gmsh_session
from geofrac.meshing.terrain import (
    TerrainBuilder,
    TerrainSpec,
    _column_size,
    footprint_radius,
    ground,
    immobile_volume,
    mesh_size,
    slip_surface,
    tet_volumes,
)

GROUPS = {"layer": 3, "top": 2, "slip": 2, "side": 2}
#: Coarse versions of the default terrain: about 1,500 layer vertices, well under a second.
SPEC = TerrainSpec(h=10.0, h_immobile=50.0)


def _build(spec):
    """Run the builder.

    Returns report, payload, layer points (n, 3), tets (m, 4), the triangles of each
    surface group as point coordinates, shape=(k, 3, 3), and the physical groups.
    """
    with gmsh_session(None, {}) as gmsh:
        report, payload = TerrainBuilder(spec).build(gmsh)
        model = gmsh.model
        tags, coords, _ = model.mesh.getNodes()
        x = coords.reshape(-1, 3)
        index = np.zeros(int(tags.max()) + 1, dtype=np.int64)
        index[tags.astype(np.int64)] = np.arange(len(tags))
        tets = index[model.mesh.getElementsByType(4)[1].astype(np.int64).reshape(-1, 4)]
        surfaces = {}
        for dim, tag in model.getPhysicalGroups(2):
            (entity,) = model.getEntitiesForPhysicalGroup(dim, tag)
            nodes = model.mesh.getElementsByType(2, entity)[1].astype(np.int64)
            surfaces[model.getPhysicalName(dim, tag)] = x[index[nodes].reshape(-1, 3)]
        groups = {model.getPhysicalName(d, t): d for d, t in model.getPhysicalGroups()}
    return report, payload, x, tets, surfaces, groups


@pytest.fixture(scope="module")
def built():
    return _build(SPEC)


def _keys(tri_xyz):
    """Orientation-free keys of triangles given by coordinates, shape=(k, 3, 3)."""
    return {tuple(sorted(map(tuple, t))) for t in tri_xyz.tolist()}


def _normals(tri_xyz):
    return np.cross(tri_xyz[:, 1] - tri_xyz[:, 0], tri_xyz[:, 2] - tri_xyz[:, 0])


def test_ground_is_eq_5_1_and_slip_depths():
    s = SPEC
    x, y = np.array([[0.0, 100.0], [-300.0, 40.0]]), np.array([[0.0, -50.0], [20.0, 10.0]])
    expected = s.b * np.exp((x**2 + y**2) / s.a) + s.c
    np.testing.assert_allclose(ground(x, y, s), expected, rtol=1e-15)
    assert ground(x, y, s).shape == (2, 2)
    cx, cy = s.footprint_centre
    assert ground(cx, cy, s) - slip_surface(cx, cy, s) == pytest.approx(s.max_depth)
    t = np.linspace(0, 2 * np.pi, 7)
    rot = math.radians(s.footprint_rotation)
    u, v = s.footprint_axes[0] * np.cos(t), s.footprint_axes[1] * np.sin(t)
    bx = cx + u * math.cos(rot) - v * math.sin(rot)
    by = cy + u * math.sin(rot) + v * math.cos(rot)
    np.testing.assert_allclose(footprint_radius(bx, by, s), 1.0, rtol=1e-12)
    np.testing.assert_allclose(ground(bx, by, s) - slip_surface(bx, by, s), s.rim_depth)
    np.testing.assert_allclose(ground(0, 0, s) - slip_surface(0, 0, s), s.rim_depth)  # outside


@pytest.mark.parametrize(
    "change",
    [{"footprint_centre": (420.0, 0.0)}, {"rim_depth": 0.0}, {"h": -1.0}, {"algorithm_3d": "x"}],
)
def test_inconsistent_specs_are_rejected(change):
    with pytest.raises(ValueError):
        TerrainSpec(**change)


def test_sizes_of_the_2d_callback_and_of_the_field_agree():
    zones = (((200.0, 100.0, 100.0), 30.0, 3.0), ((250.0, 150.0, 70.0), 40.0, 20.0))
    s = TerrainSpec(h=10.0, zones=zones)
    rng = np.random.default_rng(7)
    xy = rng.uniform([100, 0], [350, 250], size=(200, 2))
    column = np.array([_column_size(x, y, s) for x, y in xy])
    on_ground = mesh_size(np.column_stack([xy, ground(*xy.T, s)]), s)
    on_slip = mesh_size(np.column_stack([xy, slip_surface(*xy.T, s)]), s)
    np.testing.assert_allclose(column, np.minimum(on_ground, on_slip), rtol=1e-13)
    sizes = mesh_size(np.array([[200.0, 100.0, 100.0], [250.0, 150.0, 70.0], [0, 0, 0]]), s)
    np.testing.assert_allclose(sizes, [3.0, 20.0, 10.0])


def test_layer_mesh_and_groups(built):
    report, _, x, tets, surfaces, groups = built
    assert groups == GROUPS
    assert report["vertices"] == len(np.unique(tets)) == len(x)
    assert report["tets"] == len(tets)
    vols = tet_volumes(x, tets)
    assert np.all(np.abs(vols) > 0)
    assert report["layer_volume"] == pytest.approx(np.abs(vols).sum(), rel=1e-12)
    assert {"time_2d_s", "time_surface_s", "time_3d_s"} <= set(report)
    # the top lies on eq. 5.1, the slip surface below it
    top = surfaces["top"].reshape(-1, 3)
    np.testing.assert_allclose(top[:, 2], ground(top[:, 0], top[:, 1], SPEC), atol=1e-9)
    slip = surfaces["slip"].reshape(-1, 3)
    np.testing.assert_allclose(slip[:, 2], slip_surface(slip[:, 0], slip[:, 1], SPEC), atol=1e-9)


def test_immobile_patch_is_closed_and_outward(built):
    _, (points, tris), *_ = built
    assert points.dtype == np.float64 and points.shape[1] == 3
    assert tris.dtype == np.int64 and tris.shape[1] == 3
    assert np.array_equal(np.unique(tris), np.arange(len(points)))  # no unused point
    edges = np.concatenate([tris[:, [0, 1]], tris[:, [1, 2]], tris[:, [2, 0]]])
    directed, counts = np.unique(edges, axis=0, return_counts=True)
    assert counts.max() == 1  # no directed edge twice: consistent orientation
    reverse = {tuple(e) for e in directed[:, ::-1].tolist()}
    assert reverse == {tuple(e) for e in directed.tolist()}  # each edge met in both directions
    assert immobile_volume(points, tris) > 0  # outward normals
    assert len(np.unique(np.round(points, 9), axis=0)) == len(points)  # no duplicate point


def test_the_pit_is_the_layer_slip_surface(built):
    _, (points, tris), _, _, surfaces, _ = built
    patch = points[tris]
    keys = [tuple(sorted(map(tuple, t))) for t in patch.tolist()]
    row = {k: i for i, k in enumerate(keys)}
    for name in ("slip", "side"):  # the pit's floor and walls
        layer = surfaces[name]
        assert _keys(layer) <= set(row)  # the same coordinates, bit for bit
        mine = patch[[row[k] for k in [tuple(sorted(map(tuple, t))) for t in layer.tolist()]]]
        # opposite normals: outward of the layer is inward of the immobile part
        assert np.all(np.einsum("ij,ij->i", _normals(mine), _normals(layer)) < 0)
    # and no other triangle of the patch above the bottom reaches below the ground inside
    # the footprint
    below = np.any(patch[..., 2] < ground(patch[..., 0], patch[..., 1], SPEC) - 1e-6, axis=1)
    bottom = np.all(patch[..., 2] == SPEC.base_z, axis=1)
    c = patch.mean(axis=1)
    pit = below & ~bottom & (footprint_radius(c[:, 0], c[:, 1], SPEC) < 1)
    assert pit.sum() == len(surfaces["slip"]) + len(surfaces["side"])


def _ground_volume_exact(s):
    """∫∫ (ground - base_z) over the extent by Gauss-Legendre quadrature (200 x 200)."""
    x0, x1, y0, y1 = s.extent
    g, w = np.polynomial.legendre.leggauss(200)
    x, wx = 0.5 * (x1 - x0) * g + 0.5 * (x1 + x0), 0.5 * (x1 - x0) * w
    y, wy = 0.5 * (y1 - y0) * g + 0.5 * (y1 + y0), 0.5 * (y1 - y0) * w
    return float(wx @ (ground(x[:, None], y[None, :], s) - s.base_z) @ wy)


def _interpolation_bound(tri_xyz, s):
    """Bound on |∫ (I g - g)| over the ground triangles (k, 3, 3), I = linear interpolation.

    With λ_i the barycentric coordinates of x in T, I g(x) - g(x) = Σ λ_i (g(x_i) - g(x))
    = ½ Σ λ_i (x_i - x)ᵀ H(ξ_i) (x_i - x) (the gradient terms cancel as Σ λ_i (x_i - x)
    = 0), so |I g - g| ≤ ½ M_T ℓ_T² with ℓ_T the longest edge and M_T a bound of the
    Hessian's eigenvalues on T. For g = b exp(-r²/|a|) + c these are
    (b/|a|) e^{-u} (4u - 2) (radial) and -(2b/|a|) e^{-u} (tangential), u = r²/|a|; over
    u ≥ u_T (the smallest u on T, r ≥ r_min(vertices) - ℓ_T) both are at most
    max(2 e^{-u_T}, (4v - 2) e^{-v}) with v = max(u_T, 3/2) (the radial one peaks at
    u = 3/2). The bound is rigorous, so the test has no tuned tolerance.
    """
    assert s.a < 0
    xy = tri_xyz[:, :, :2]
    edges = np.linalg.norm(xy - np.roll(xy, 1, axis=1), axis=2)
    ell = edges.max(axis=1)
    e1, e2 = xy[:, 1] - xy[:, 0], xy[:, 2] - xy[:, 0]
    area = 0.5 * np.abs(e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0])
    r_min = np.maximum(np.linalg.norm(xy, axis=2).min(axis=1) - ell, 0.0)
    u = r_min**2 / -s.a
    v = np.maximum(u, 1.5)
    m = abs(s.b) / -s.a * np.maximum(2 * np.exp(-u), (4 * v - 2) * np.exp(-v))
    return float(np.sum(area * 0.5 * m * ell**2))


def test_layer_and_immobile_fill_the_box_under_the_ground(built):
    report, (points, tris), _, _, surfaces, _ = built
    total = report["layer_volume"] + immobile_volume(points, tris)
    assert report["immobile_volume"] == pytest.approx(immobile_volume(points, tris), rel=1e-12)
    # the ground of the whole terrain: the layer's top and the patch's upward ground triangles
    patch = points[tris]
    on_ground = np.all(
        np.abs(patch[:, :, 2] - ground(patch[..., 0], patch[..., 1], SPEC)) < 1e-9, 1
    )
    up = _normals(patch)[:, 2] > 1e-9 * np.linalg.norm(_normals(patch), axis=1)
    surface = np.concatenate([patch[on_ground & up], surfaces["top"]])
    # 1. exactly (round-off) the prism volume under that piecewise-linear ground: no gap and
    # no overlap between the two parts, whatever the interpolation error
    prisms = 0.5 * _normals(surface)[:, 2] * (surface[:, :, 2].mean(axis=1) - SPEC.base_z)
    x0, x1, y0, y1 = SPEC.extent
    assert 0.5 * _normals(surface)[:, 2].sum() == pytest.approx((x1 - x0) * (y1 - y0), rel=1e-12)
    assert total == pytest.approx(prisms.sum(), rel=1e-11)
    # 2. eq. 5.1 integrated independently, within the rigorous bound of the interpolation error
    exact = _ground_volume_exact(SPEC)
    separable = SPEC.b * (math.sqrt(-math.pi * SPEC.a) * math.erf(500 / math.sqrt(-SPEC.a))) ** 2
    assert exact == pytest.approx(separable + (SPEC.c - SPEC.base_z) * 1e6, rel=1e-12)
    bound = _interpolation_bound(surface, SPEC)
    assert abs(total - exact) <= bound
    hill = exact - (SPEC.c - SPEC.base_z) * (x1 - x0) * (y1 - y0)
    assert bound < 0.03 * hill  # the check is not vacuous


def _mean_edges(x, tets, centre, radius):
    edges = np.unique(
        np.sort(tets[:, [0, 1, 0, 2, 0, 3, 1, 2, 1, 3, 2, 3]].reshape(-1, 2), 1), axis=0
    )
    mid = 0.5 * (x[edges[:, 0]] + x[edges[:, 1]])
    length = np.linalg.norm(x[edges[:, 0]] - x[edges[:, 1]], axis=1)
    d = np.linalg.norm(mid - centre, axis=1)
    return length[d < radius].mean(), length[d > 2 * radius].mean()


def test_zones_refine_and_coarsen_the_layer_locally():
    fine_c, coarse_c = np.array([160.0, 80.0, 130.0]), np.array([250.0, 150.0, 70.0])
    zones = ((tuple(fine_c), 25.0, 4.0), (tuple(coarse_c), 30.0, 20.0))
    spec = TerrainSpec(h=10.0, h_immobile=50.0, zones=zones)
    report, (points, tris), x, tets, *_ = _build(spec)
    inside, outside = _mean_edges(x, tets, fine_c, 25.0)
    assert inside < 0.7 * outside
    inside, outside = _mean_edges(x, tets, coarse_c, 30.0)
    assert inside > 1.3 * outside
    assert report["vertices"] > 1.2 * _build(SPEC)[0]["vertices"]
    assert immobile_volume(points, tris) > 0


@pytest.mark.mpi
def test_build_mesh_distributes_the_layer(built):
    from geofrac.meshing.distribute import build_mesh
    from geofrac.model.scene import Geometry

    geometry = Geometry(
        file=None, parameters={}, mesh_size=None, dim=3, groups=GROUPS, builder=TerrainBuilder(SPEC)
    )
    tagged = build_mesh(geometry, MPI.COMM_WORLD)
    assert tagged.num_global(0) == built[0]["vertices"]
    assert tagged.num_global(3) == built[0]["tets"]
    assert set(tagged.groups) == set(GROUPS)
    points, tris = tagged.fractures
    assert points.shape == built[1][0].shape and np.array_equal(tris, built[1][1])
    assert tagged.report["vertices"] == built[0]["vertices"]
