"""Grain polygons of the EFMM integration domains (geofrac.io.grains) and their files."""

import warnings
import xml.etree.ElementTree as ET

import h5py
import numpy as np
import pytest

from geofrac.elements.efmm_numpy import integration_domains
from geofrac.io import grains as io
from tests.blocks.conftest import square_mesh

pv = pytest.importorskip("pyvista")

N = 5


def _mesh(perturbed: bool) -> tuple[np.ndarray, np.ndarray]:
    points, tris = square_mesh(N)
    if perturbed:
        inside = np.all((points > 0) & (points < 1), axis=1)
        shift = np.random.default_rng(7).uniform(-0.3, 0.3, (inside.sum(), 2)) / N
        points[inside] += shift
    return points, tris


def _sub_areas(corners: np.ndarray) -> np.ndarray:
    """Unsigned sub-triangle areas, shape=(num_sub,)."""
    d1, d2 = corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0]
    return 0.5 * np.abs(d1[:, 0] * d2[:, 1] - d1[:, 1] * d2[:, 0])


def _polygons(grains: io.Grains) -> list[np.ndarray]:
    """Each polygon's points in order, shape=(n_g, 2)."""
    off = grains.offsets
    return [grains.points[grains.connectivity[off[g] : off[g + 1]]] for g in range(len(off) - 1)]


def _shoelace(poly: np.ndarray) -> float:
    x, y = poly[:, 0], poly[:, 1]
    return 0.5 * float(np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y))


def _winding(poly: np.ndarray, p: np.ndarray) -> int:
    """Winding number of the closed polygon around the point p (not on it)."""
    a = poly - p
    b = np.roll(a, -1, axis=0)
    up = (a[:, 1] <= 0) & (b[:, 1] > 0)
    down = (a[:, 1] > 0) & (b[:, 1] <= 0)
    side = a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0]
    return int(np.sum(up & (side > 0)) - np.sum(down & (side < 0)))


def _convex(poly: np.ndarray) -> bool:
    d = np.roll(poly, -1, axis=0) - poly
    e = np.roll(d, -1, axis=0)
    return bool(np.all(d[:, 0] * e[:, 1] - d[:, 1] * e[:, 0] >= -1e-14))


CASES = [(False, 0.0), (False, 0.5), (True, 0.0), (True, 0.5)]
IDS = ["square-incentre", "square-random", "perturbed-incentre", "perturbed-random"]


@pytest.fixture(scope="module", params=CASES, ids=IDS)
def case(request):
    perturbed, q_rand = request.param
    points, tris = _mesh(perturbed)
    domains = integration_domains(points, tris, q_rand, seed=3)
    return points, tris, domains, io.grain_polygons(domains.node, domains.corners)


def test_one_grain_per_node_with_the_sub_triangle_areas(case):
    points, _, domains, grains = case
    np.testing.assert_array_equal(grains.node, np.arange(len(points)))
    assert grains.num_grains == len(points)
    per_node = np.bincount(domains.node, weights=_sub_areas(domains.corners))
    np.testing.assert_allclose(grains.area, per_node, rtol=0, atol=1e-15)
    assert grains.area.min() > 0
    assert abs(grains.area.sum() - 1.0) < 1e-12  # the unit square
    assert grains.offsets.dtype == grains.connectivity.dtype == np.int64
    assert grains.offsets[0] == 0 and grains.offsets[-1] == len(grains.connectivity)
    assert grains.points.shape == (len(np.unique(grains.points, axis=0)), 2)
    assert set(np.unique(grains.connectivity)) == set(range(len(grains.points)))


def test_polygons_are_simple_counter_clockwise_loops_of_the_grain_area(case):
    _, _, _, grains = case
    polys = _polygons(grains)
    shoelace = np.array([_shoelace(p) for p in polys])
    np.testing.assert_allclose(shoelace, grains.area, rtol=1e-12, atol=0)  # > 0: CCW
    off = grains.offsets
    for g in range(grains.num_grains):
        ids = grains.connectivity[off[g] : off[g + 1]]
        assert len(ids) >= 3 and len(np.unique(ids)) == len(ids)  # no point twice
        assert ids[0] == ids.min()
    # every boundary point of the domain tiling is shared: each polygon edge is either on
    # the square's boundary or traversed the other way by exactly one other grain
    conn, nxt = grains.connectivity, np.arange(len(grains.connectivity)) + 1
    nxt[off[1:] - 1] = off[:-1]
    edges = np.column_stack([conn, conn[nxt]])
    forward = {tuple(e) for e in edges}
    assert len(forward) == len(edges)
    x = grains.points
    for a, b in edges:
        on_side = np.any((x[a] == x[b]) & ((x[a] == 0) | (x[a] == 1)))
        assert on_side or (b, a) in forward


def test_node_points_are_on_boundary_polygons_and_inside_interior_ones(case):
    points, _, _, grains = case
    boundary = np.any((points == 0) | (points == 1), axis=1)
    for g, poly in enumerate(_polygons(grains)):
        at_node = np.all(poly == points[grains.node[g]], axis=1)
        if boundary[grains.node[g]]:
            assert at_node.sum() == 1
        else:
            assert not at_node.any()
            assert _winding(poly, points[grains.node[g]]) == 1


def test_clockwise_input_gives_the_same_grains():
    points, tris = _mesh(True)
    domains = integration_domains(points, tris, 0.5, seed=1)
    corners = domains.corners.copy()
    corners[::3] = corners[::3][:, [0, 2, 1]]
    order = np.random.default_rng(0).permutation(len(corners))  # any order of sub-triangles
    a = io.grain_polygons(domains.node, domains.corners)
    b = io.grain_polygons(domains.node[order], corners[order])
    for name in ("points", "offsets", "connectivity", "node"):
        np.testing.assert_array_equal(getattr(a, name), getattr(b, name))
    np.testing.assert_allclose(a.area, b.area, rtol=1e-15)


def _broken(kind: str) -> tuple[np.ndarray, np.ndarray, int]:
    """Sub-triangles of a 5x5 mesh with one grain broken, and that grain's node."""
    points, tris = _mesh(True)
    d = integration_domains(points, tris, 0.5, seed=3)
    node, corners = d.node.copy(), d.corners.copy()
    centre = int(np.argmin(np.linalg.norm(points - 0.5, axis=1)))
    mine = np.flatnonzero(node == centre)
    if kind == "hole":  # the neighbours' domains as one grain: a ring around the centre's
        neighbours = np.unique(tris[np.any(tris == centre, axis=1)])
        ring = np.isin(node, neighbours[neighbours != centre])
        target = int(neighbours[neighbours != centre][0])
        node[ring] = target
        keep = node != centre
        return node[keep], corners[keep], target
    if kind == "pinched":  # two opposite wedges of the centre's star, touching at the node
        c = corners[mine].mean(axis=1) - points[centre]
        by_angle = mine[np.argsort(np.arctan2(c[:, 1], c[:, 0]))]
        keep = np.ones(len(node), dtype=bool)
        keep[by_angle[[0, len(by_angle) // 2]]] = False
        return node[keep], corners[keep], centre
    if kind == "pieces":  # a far sub-triangle given to the centre's grain
        far = int(np.argmax(np.linalg.norm(corners[:, 0] - points[centre], axis=1)))
        node[far] = centre
        return node, corners, centre
    if kind == "duplicate":  # one sub-triangle twice
        return np.append(node, node[mine[0]]), np.concatenate([corners, corners[mine[:1]]]), centre
    raise AssertionError(kind)


@pytest.mark.parametrize(
    ("kind", "message"),
    [
        ("hole", r"not a single closed loop \(a hole"),
        ("pinched", r"not a single closed loop \(pieces touch at a point"),
        ("pieces", r"not a single closed loop \(a hole, or pieces"),
        ("duplicate", "overlap"),
    ],
)
def test_broken_grains_raise(kind, message):
    node, corners, culprit = _broken(kind)
    with pytest.raises(ValueError, match=message) as err:
        io.grain_polygons(node, corners)
    assert f"node(s) {culprit}" in str(err.value)


def test_bad_shapes_raise():
    with pytest.raises(ValueError, match="shape"):
        io.grain_polygons(np.zeros(3, dtype=int), np.zeros((3, 2, 2)))
    with pytest.raises(ValueError, match="shape"):
        io.grain_polygons(np.zeros(2, dtype=int), np.zeros((3, 3, 2)))
    with pytest.raises(ValueError, match="finite"):
        io.grain_polygons(np.zeros(1, dtype=int), np.array([[[0, 0], [1, 0], [0, np.nan]]]))


@pytest.fixture(scope="module")
def written(tmp_path_factory):
    points, tris = _mesh(True)
    domains = integration_domains(points, tris, 0.5, seed=3)
    grains = io.grain_polygons(domains.node, domains.corners)
    n = grains.num_grains
    cell_data = {
        "stress": np.arange(9.0 * n).reshape(n, 9),
        "velocity": np.ones((n, 3)),
        "pair": np.ones((n, 2), dtype=np.float32),
        "damage": np.linspace(0, 1, n),
        "broken": np.arange(n) % 2 == 0,
    }
    stem = tmp_path_factory.mktemp("grains") / "grains"
    return grains, cell_data, io.write_grains(stem, grains, cell_data)


def test_write_returns_the_three_files_and_leaves_no_temporaries(written):
    _, _, paths = written
    assert [p.name for p in paths] == ["grains.vtu", "grains.xdmf", "grains.h5"]
    assert sorted(p.name for p in paths[0].parent.iterdir()) == sorted(p.name for p in paths)


def test_vtu_reads_back_with_pyvista(written):
    grains, cell_data, paths = written
    grid = pv.read(paths[0])
    assert grid.n_cells == grains.num_grains
    assert set(np.unique(grid.celltypes)) == {pv.CellType.POLYGON}
    np.testing.assert_array_equal(grid.points[:, :2], grains.points)
    assert not grid.points[:, 2].any()
    np.testing.assert_array_equal(grid.cell_offsets, grains.offsets)
    np.testing.assert_array_equal(grid.cell_connectivity, grains.connectivity)
    np.testing.assert_array_equal(grid.cell_data["node"], grains.node)
    np.testing.assert_array_equal(grid.cell_data["area"], grains.area)
    for name, values in cell_data.items():
        np.testing.assert_array_equal(grid.cell_data[name], values)
    # VTK's cell size fans each polygon from its first point: right for convex ones only
    convex = np.array([_convex(p) for p in _polygons(grains)])
    assert convex.sum() >= grains.num_grains // 2
    sizes = grid.compute_cell_sizes(length=False, volume=False).cell_data["Area"]
    np.testing.assert_allclose(sizes[convex], grains.area[convex], rtol=1e-12)
    # VTK's own triangulation of every polygon (ear cutting) gives the grain areas
    tri = grid.triangulate().compute_cell_sizes(length=False, volume=False)
    assert set(np.unique(tri.celltypes)) == {pv.CellType.TRIANGLE}
    by_node = np.bincount(tri.cell_data["node"], weights=tri.cell_data["Area"])
    np.testing.assert_allclose(by_node, grains.area, rtol=1e-12)


def test_xdmf_and_h5_read_back(written):
    grains, cell_data, paths = written
    _, xdmf, h5 = paths
    root = ET.parse(xdmf).getroot()
    assert root.tag == "Xdmf" and root.get("Version") == "3.0"
    grid = root.find("Domain/Grid")
    top = grid.find("Topology")
    assert top.get("TopologyType") == "Mixed"
    assert int(top.get("NumberOfElements")) == grains.num_grains
    geo = grid.find("Geometry")
    assert geo.get("GeometryType") == "XYZ"
    items = {}
    for element in grid.iter("DataItem"):
        assert element.get("Format") == "HDF"
        file, dataset = element.text.strip().split(":")
        assert file == h5.name
        items[dataset] = element
    with h5py.File(h5, "r") as f:
        stream = f["topology"][()]
        xyz = f["geometry"][()]
        for dataset, element in items.items():
            assert tuple(int(v) for v in element.get("Dimensions").split()) == f[dataset].shape
            assert int(element.get("Precision")) == f[dataset].dtype.itemsize
        stored = {name: f[f"cell_data/{name}"][()] for name in f["cell_data"]}
    assert len(stream) == len(grains.connectivity) + 2 * grains.num_grains
    np.testing.assert_array_equal(xyz[:, :2], grains.points)
    assert not xyz[:, 2].any()
    # walk the Mixed stream: type 3 (polygon), point count, point ids
    r, cells = 0, []
    while r < len(stream):
        assert stream[r] == io.XDMF_POLYGON
        cells.append(stream[r + 2 : r + 2 + stream[r + 1]])
        r += 2 + stream[r + 1]
    assert len(cells) == grains.num_grains
    np.testing.assert_array_equal(np.concatenate(cells), grains.connectivity)
    kinds = {a.get("Name"): a for a in grid.findall("Attribute")}
    assert set(kinds) == {"node", "area", *cell_data}
    assert all(a.get("Center") == "Cell" for a in kinds.values())
    expect = {"stress": "Tensor", "velocity": "Vector", "pair": "Matrix", "damage": "Scalar"}
    for name, attribute_type in {**expect, "node": "Scalar", "area": "Scalar"}.items():
        assert kinds[name].get("AttributeType") == attribute_type
    np.testing.assert_array_equal(stored["node"], grains.node)
    np.testing.assert_array_equal(stored["area"], grains.area)
    for name, values in cell_data.items():
        np.testing.assert_array_equal(stored[name], values)


def test_xdmf_reads_in_vtk(written):
    """VTK's XDMF reader (the one pyvista and ParaView wrap) reads the Mixed polygons."""
    xdmf_io = pytest.importorskip("vtkmodules.vtkIOXdmf2")
    grains, cell_data, paths = written
    reader = xdmf_io.vtkXdmfReader()
    reader.SetFileName(str(paths[1]))
    reader.Update()
    with warnings.catch_warnings():  # this legacy (XDMF 2) reader reads a Matrix as one tuple
        warnings.simplefilter("ignore")
        grid = pv.wrap(reader.GetOutputDataObject(0))
    assert grid.n_cells == grains.num_grains
    assert set(np.unique(grid.celltypes)) == {pv.CellType.POLYGON}
    np.testing.assert_array_equal(grid.cell_connectivity, grains.connectivity)
    np.testing.assert_array_equal(grid.cell_data["stress"], cell_data["stress"])
    np.testing.assert_array_equal(grid.cell_data["area"], grains.area)


def test_xdmf_reads_in_meshio(written):
    meshio = pytest.importorskip("meshio")
    from meshio.xdmf import common

    if io.XDMF_POLYGON not in common.xdmf_idx_to_meshio_type:
        pytest.skip(f"meshio {meshio.__version__} reads no polygons in a Mixed XDMF topology")
    grains, _, paths = written
    mesh = meshio.read(paths[1])
    assert sum(len(block.data) for block in mesh.cells) == grains.num_grains


def test_bad_cell_data_raises_before_writing(tmp_path, written):
    grains, _, _ = written
    n = grains.num_grains
    for bad in ({"short": np.ones(n - 1)}, {"area": np.ones(n)}, {"a/b": np.ones(n)}):
        with pytest.raises(ValueError, match="cell array"):
            io.write_grains(tmp_path / "g", grains, bad)
    assert not list(tmp_path.iterdir())


def test_a_failed_write_leaves_the_old_files(tmp_path, written, monkeypatch):
    grains, cell_data, _ = written
    paths = io.write_grains(tmp_path / "g", grains, cell_data)
    before = [p.read_bytes() for p in paths]

    def fail(*args, **kwargs):
        raise OSError("disk full")

    monkeypatch.setattr(io, "_write_xdmf", fail)  # after the VTU is written
    with pytest.raises(OSError, match="disk full"):
        io.write_grains(tmp_path / "g", grains, {"other": np.zeros(grains.num_grains)})
    assert [p.read_bytes() for p in paths] == before
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(p.name for p in paths)
