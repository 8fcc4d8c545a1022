"""The mesh cut along joints (geofrac.meshing.split): sectors, tips, junctions, in 2D and 3D."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from geofrac.meshing.split import EDGES, FACES, split_along, split_along_faces, split_model

#: a 4 x 4 grid of unit squares, each cut into 2 triangles by its rising diagonal
N = 4


def grid(*, order: int = 1) -> tuple[np.ndarray, np.ndarray]:
    """(nodes (x, y), shape=(k, 2); triangles, shape=(32, 3) or (32, 6))."""
    nodes = [(float(i), float(j)) for j in range(N + 1) for i in range(N + 1)]
    index = {p: k for k, p in enumerate(nodes)}
    cells = []
    for j in range(N):
        for i in range(N):
            a, b = index[(i, j)], index[(i + 1, j)]
            c, d = index[(i + 1, j + 1)], index[(i, j + 1)]
            cells += [[a, b, c], [a, c, d]]
    tri = np.array(cells)
    xy = np.array(nodes)
    if order == 2:
        mids: dict[tuple[int, int], int] = {}
        rows = []
        for cell in tri:
            row = list(cell)
            for e in EDGES:
                key = tuple(sorted(cell[e]))
                if key not in mids:
                    mids[key] = len(xy) + len(mids)
                row.append(mids[key])
            rows.append(row)
        xm = np.array([xy[list(k)].mean(axis=0) for k in mids])
        xy, tri = np.vstack([xy, xm]), np.array(rows)
    return xy, tri


def vertex(x: float, y: float) -> int:
    """The grid vertex at (x, y)."""
    return round(y) * (N + 1) + round(x)


def chain(points: list[tuple[float, float]]) -> np.ndarray:
    """Joint edges along a polyline through grid vertices (unit steps), shape=(m, 2)."""
    out = []
    for (x0, y0), (x1, y1) in itertools.pairwise(points):
        steps = int(max(abs(x1 - x0), abs(y1 - y0)))
        for k in range(steps):
            a = (x0 + (x1 - x0) * k / steps, y0 + (y1 - y0) * k / steps)
            b = (x0 + (x1 - x0) * (k + 1) / steps, y0 + (y1 - y0) * (k + 1) / steps)
            out.append([vertex(*a), vertex(*b)])
    return np.array(out)


def areas(xy: np.ndarray, cells: np.ndarray) -> np.ndarray:
    p = xy[cells[:, :3]]
    d1, d2 = p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]
    return 0.5 * (d1[:, 0] * d2[:, 1] - d1[:, 1] * d2[:, 0])


def edge_cells(cells: np.ndarray) -> dict[tuple[int, int], int]:
    """Vertex edge -> number of cells holding it."""
    count: dict[tuple[int, int], int] = {}
    for cell in cells:
        for e in EDGES:
            key = (int(min(cell[e])), int(max(cell[e])))
            count[key] = count.get(key, 0) + 1
    return count


def check(order: int, joints: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Split; cells, areas and midpoints unchanged, non-joint edges still shared."""
    xy, cells = grid(order=order)
    out, source = split_along(cells, joints)
    new_xy = np.vstack([xy, xy[source]])
    assert out.shape == cells.shape
    # every node of every cell is where it was: the same areas and shapes
    assert np.array_equal(new_xy[out], xy[cells])
    assert np.allclose(areas(new_xy, out), areas(xy, cells), atol=1e-14)
    before, after = edge_cells(cells), edge_cells(out)
    jset = {(int(min(e)), int(max(e))) for e in joints}
    interior = [k for k, v in before.items() if v == 2 and k not in jset]
    # a non-joint edge is one edge of two cells after the split, as before
    mapped = edge_cells(out)
    for cell_before, cell_after in zip(cells, out, strict=True):
        for e in EDGES:
            key = (int(min(cell_before[e])), int(max(cell_before[e])))
            if key in interior:
                k2 = (int(min(cell_after[e])), int(max(cell_after[e])))
                assert mapped[k2] == 2
    return xy, out, source, np.array(sorted(set(after) - set(before)))


def copies(source: np.ndarray, node: int) -> int:
    """How many nodes stand at ``node`` after the split."""
    return 1 + int(np.count_nonzero(source == node))


@pytest.mark.parametrize("order", [1, 2])
def test_through_going_line_doubles_every_vertex(order: int) -> None:
    joint = chain([(0, 2), (4, 2)])
    _, out, source, _ = check(order, joint)
    for x in range(N + 1):
        assert copies(source, vertex(x, 2)) == 2
    assert len(source) == (N + 1) + (N if order == 2 else 0)  # midpoints of the 4 edges
    # the rock is cut in two: no node is a node of a cell above the line and one below
    new_xy = np.vstack([grid(order=order)[0], grid(order=order)[0][source]])
    centre = new_xy[out[:, :3]][:, :, 1].mean(axis=1)
    above, below = set(out[centre > 2].ravel()), set(out[centre < 2].ravel())
    assert not above & below


@pytest.mark.parametrize("order", [1, 2])
def test_tip_inside_is_not_split(order: int) -> None:
    joint = chain([(0, 2), (2, 2)])
    _, _, source, _ = check(order, joint)
    assert copies(source, vertex(0, 2)) == 2  # on the boundary: cut
    assert copies(source, vertex(1, 2)) == 2
    assert copies(source, vertex(2, 2)) == 1  # the tip
    assert len(source) == 2 + (2 if order == 2 else 0)


@pytest.mark.parametrize("order", [1, 2])
def test_x_crossing_quadruples_the_crossing(order: int) -> None:
    joint = np.vstack([chain([(1, 2), (3, 2)]), chain([(2, 1), (2, 3)])])
    _, _, source, _ = check(order, joint)
    assert copies(source, vertex(2, 2)) == 4
    for tip in [(1, 2), (3, 2), (2, 1), (2, 3)]:
        assert copies(source, vertex(*tip)) == 1
    assert len(source) == 3 + (4 if order == 2 else 0)


@pytest.mark.parametrize("order", [1, 2])
def test_t_junction_triples_the_junction(order: int) -> None:
    joint = np.vstack([chain([(0, 2), (4, 2)]), chain([(2, 2), (2, 4)])])
    _, _, source, _ = check(order, joint)
    assert copies(source, vertex(2, 2)) == 3
    assert copies(source, vertex(2, 3)) == 2
    assert copies(source, vertex(2, 4)) == 2  # reaches the top boundary
    assert copies(source, vertex(0, 2)) == 2
    assert len(source) == (4 + 2 + 2) + (6 if order == 2 else 0)


def test_one_edge_joint_with_two_tips_stays_whole() -> None:
    """Both ends are tips: nothing to cut (no node split, the midpoint shared)."""
    out, source = split_along(grid(order=2)[1], chain([(1, 2), (2, 2)]))
    assert len(source) == 0 and np.array_equal(out, grid(order=2)[1])


def test_already_split_joint_is_left_alone() -> None:
    """A joint between two pieces split already (by hand): no new node."""
    xy, cells = grid()
    once, source = split_along(cells, chain([(0, 2), (4, 2)]))
    assert len(source) == N + 1
    new_xy = np.vstack([xy, xy[source]])
    ends = once[:, EDGES]
    both = np.all(np.abs(new_xy[ends][..., 1] - 2.0) < 1e-12, axis=2)
    again, more = split_along(once, ends[both])
    assert len(ends[both]) == 2 * N and len(more) == 0 and np.array_equal(again, once)


def test_bad_cells_refused() -> None:
    with pytest.raises(ValueError, match="triangles"):
        split_along(np.zeros((2, 4), dtype=int), np.array([[0, 1]]))


# --- 3D: tetrahedra cut along joint surfaces ------------------------------------------------

#: a 4 x 4 x 4 grid of unit cubes, each cut into 6 tetrahedra around its diagonal (Kuhn)
M = 4


def cube_grid() -> tuple[np.ndarray, np.ndarray]:
    """(nodes (x, y, z), shape=(125, 3); tetrahedra, shape=(384, 4)), conforming."""
    index = {p: k for k, p in enumerate(itertools.product(range(M + 1), repeat=3))}
    tets = []
    for o in itertools.product(range(M), repeat=3):
        for perm in itertools.permutations(range(3)):
            p, row = list(o), [index[o]]
            for axis in perm:
                p[axis] += 1
                row.append(index[tuple(p)])
            tets.append(row)
    return np.array(list(index), dtype=float), np.array(tets)


def faces_where(xyz: np.ndarray, tets: np.ndarray, on) -> np.ndarray:
    """The distinct tet faces whose 3 vertices all satisfy ``on(points)``, shape=(k, 3)."""
    faces = np.unique(np.sort(tets[:, FACES].reshape(-1, 3), axis=1), axis=0)
    return faces[np.all(on(xyz[faces]), axis=1)]


def face_cells(tets: np.ndarray) -> dict[tuple[int, ...], list[int]]:
    """Face (sorted vertex triple) -> the tets holding it."""
    out: dict[tuple[int, ...], list[int]] = {}
    for c, tet in enumerate(tets.tolist()):
        for face in FACES.tolist():
            out.setdefault(tuple(sorted(tet[i] for i in face)), []).append(c)
    return out


def volumes(xyz: np.ndarray, tets: np.ndarray) -> np.ndarray:
    """Signed volumes of the tetrahedra, shape=(n,)."""
    p = xyz[tets[:, :4]]
    return np.linalg.det(p[:, 1:] - p[:, :1]) / 6.0


def pieces(tets: np.ndarray) -> int:
    """Connected components of the tets joined through shared faces."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    pairs = [c for c in face_cells(tets).values() if len(c) == 2]
    r, c = np.array(pairs).T
    graph = coo_matrix((np.ones(len(r)), (r, c)), shape=(len(tets), len(tets)))
    return int(connected_components(graph, directed=False)[0])


def check_cut(
    xyz: np.ndarray, tets: np.ndarray, out: np.ndarray, source: np.ndarray, joint: np.ndarray
) -> np.ndarray:
    """The cut tets stand where they stood; joint faces have one tet, others as before.

    Returns:
        the nodes' coordinates after the split, shape=(k + q, 3).
    """
    new_xyz = np.vstack([xyz, xyz[source]])
    assert out.shape == tets.shape
    assert np.array_equal(new_xyz[out], xyz[tets])
    assert np.allclose(volumes(new_xyz, out), volumes(xyz, tets), atol=1e-14)
    assert np.abs(volumes(new_xyz, out)).sum() == pytest.approx(float(M**3), rel=1e-12)
    jset = {tuple(sorted(f)) for f in np.asarray(joint).tolist()}
    before, after = face_cells(tets), face_cells(out)
    for face, cells in before.items():
        # the face in each of its cells after the split
        mapped = set()
        for c in cells:
            where = [tets[c].tolist().index(n) for n in face]
            mapped.add(tuple(sorted(out[c, where].tolist())))
        copies = [len(after[f]) for f in mapped]
        if face not in jset or len(cells) == 1:
            assert len(mapped) == 1 and copies == [len(cells)]  # still shared, or boundary
        elif len(mapped) == 2:
            assert copies == [1, 1]  # the joint face cut: one per side
        else:
            # stayed whole: only where all three vertices kept a single copy (tips)
            assert copies == [2] and not np.isin(list(face), source).any()
    return new_xyz


def grid_copies(source: np.ndarray, xyz: np.ndarray, point: tuple[int, int, int]) -> int:
    """How many nodes stand at the grid point after the split."""
    node = int(np.flatnonzero(np.all(xyz == point, axis=1))[0])
    return 1 + int(np.count_nonzero(source == node))


def test_3d_through_going_plane_doubles_its_vertices() -> None:
    xyz, tets = cube_grid()
    joint = faces_where(xyz, tets, lambda p: p[..., 2] == 2)
    out, source = split_along_faces(tets, joint)
    check_cut(xyz, tets, out, source, joint)
    assert len(joint) == 2 * M * M
    assert len(source) == (M + 1) ** 2
    assert sorted(source.tolist()) == sorted(np.flatnonzero(xyz[:, 2] == 2).tolist())
    assert pieces(tets) == 1 and pieces(out) == 2


def test_3d_patch_inside_keeps_its_rim() -> None:
    """A square fracture [1, 3]^2 at z = 2: its free edge (tip line) is not split."""
    xyz, tets = cube_grid()

    def on(p: np.ndarray) -> np.ndarray:
        x, y, z = p[..., 0], p[..., 1], p[..., 2]
        return (z == 2) & (x >= 1) & (x <= 3) & (y >= 1) & (y <= 3)

    joint = faces_where(xyz, tets, on)
    out, source = split_along_faces(tets, joint)
    check_cut(xyz, tets, out, source, joint)
    assert grid_copies(source, xyz, (2, 2, 2)) == 2
    for rim in [(1, 1, 2), (2, 1, 2), (3, 3, 2), (1, 3, 2), (3, 2, 2)]:
        assert grid_copies(source, xyz, rim) == 1
    assert len(source) == 1 and pieces(out) == 1


def test_3d_x_line_quadruples_and_t_line_triples() -> None:
    xyz, tets = cube_grid()
    x, y, z = (xyz[:, k] for k in range(3))
    cross = np.vstack([faces_where(xyz, tets, lambda p, k=k: p[..., k] == 2) for k in (0, 1)])
    out, source = split_along_faces(tets, cross)
    check_cut(xyz, tets, out, source, cross)
    line = (x == 2) & (y == 2)
    for k in range(M + 1):
        assert grid_copies(source, xyz, (2, 2, k)) == 4  # ends on the boundary too
    assert len(source) == 3 * np.count_nonzero(line) + np.count_nonzero((x == 2) ^ (y == 2))
    assert pieces(out) == 4
    # a T: the plane z = 2 and the half-plane x = 2 above it
    plane = faces_where(xyz, tets, lambda p: p[..., 2] == 2)
    stem = faces_where(xyz, tets, lambda p: (p[..., 0] == 2) & (p[..., 2] >= 2))
    out, source = split_along_faces(tets, np.vstack([plane, stem]))
    check_cut(xyz, tets, out, source, np.vstack([plane, stem]))
    for k in range(M + 1):
        assert grid_copies(source, xyz, (2, k, 2)) == 3
        assert grid_copies(source, xyz, (2, k, 3)) == 2
        assert grid_copies(source, xyz, (0, k, 2)) == 2
    t_line = (x == 2) & (z == 2)
    others = ((z == 2) | ((x == 2) & (z > 2))) & ~t_line
    assert len(source) == 2 * np.count_nonzero(t_line) + np.count_nonzero(others)
    assert pieces(out) == 3


def test_3d_split_twice_adds_nothing_and_first_new_numbers() -> None:
    xyz, tets = cube_grid()
    joint = faces_where(xyz, tets, lambda p: p[..., 2] == 2)
    once, source = split_along_faces(tets, joint, first_new=1000)
    assert np.array_equal(np.setdiff1d(once, tets), 1000 + np.arange(len(source)))
    ends = once[:, FACES]
    new_xyz = np.vstack([xyz, np.full((1000 - len(xyz), 3), np.nan), xyz[source]])
    on = np.all(new_xyz[ends][..., 2] == 2, axis=2)
    again, more = split_along_faces(once, ends[on])
    assert len(ends[on]) == 2 * len(joint) and len(more) == 0 and np.array_equal(again, once)


def test_3d_bad_cells_refused() -> None:
    with pytest.raises(ValueError, match="first-order geometry is required"):
        split_along_faces(np.zeros((2, 10), dtype=int), np.array([[0, 1, 2]]))
    with pytest.raises(ValueError, match="4-node tetrahedra"):
        split_along_faces(np.zeros((2, 3), dtype=int), np.array([[0, 1, 2]]))
    three = np.array([[0, 1, 2, 3], [0, 1, 2, 4], [0, 1, 2, 5]])  # one face, three tets
    with pytest.raises(ValueError, match="a face is shared by more than two cells"):
        split_along_faces(three, np.array([[3, 4, 5]]))


# --- 3D gmsh models: split_model and the DOLFINx mesh --------------------------------------

#: the joints of each 3D model in the unit box: quads by their corners
JOINTS = {
    "through": [[(0, 0, 0.5), (1, 0, 0.5), (1, 1, 0.5), (0, 1, 0.5)]],
    "x": [
        [(0.5, 0, 0), (0.5, 1, 0), (0.5, 1, 1), (0.5, 0, 1)],
        [(0, 0.5, 0), (1, 0.5, 0), (1, 0.5, 1), (0, 0.5, 1)],
    ],
    "t": [
        [(0, 0, 0.5), (1, 0, 0.5), (1, 1, 0.5), (0, 1, 0.5)],
        [(0.5, 0, 0.5), (0.5, 1, 0.5), (0.5, 1, 1), (0.5, 0, 1)],
    ],
}
#: the disc fracture fully inside the box: centre and radius (in the plane z = 0.5)
CENTRE, RADIUS = (0.5, 0.5, 0.5), 0.3


def copies_expected(case: str, xyz: np.ndarray) -> np.ndarray:
    """Nodes standing at each node's place after the split, from geometry alone, shape=(k,)."""
    x, y, z = (xyz[:, k] for k in range(3))
    near = lambda a, b: np.abs(a - b) < 1e-9  # noqa: E731
    if case == "through":
        return 1 + near(z, 0.5)
    if case == "disc":
        r = np.hypot(x - CENTRE[0], y - CENTRE[1])
        return 1 + (near(z, 0.5) & (r < RADIUS - 1e-6))
    if case == "x":
        return 1 + near(x, 0.5) + near(y, 0.5) + (near(x, 0.5) & near(y, 0.5))
    # t: the plane z = 0.5 and the half-plane x = 0.5 above it
    plane, stem = near(z, 0.5), near(x, 0.5) & (z > 0.5 - 1e-9)
    return 1 + (plane | stem) + (plane & stem)


def box_model(gmsh, case: str, *, h: float = 0.25, order: int = 1) -> None:
    """The meshed unit box with the joints of ``case`` (groups rock, joint, boundary, line)."""
    occ = gmsh.model.occ
    box = occ.addBox(0, 0, 0, 1, 1, 1)
    tools = []
    if case == "disc":
        tools.append(occ.addDisk(*CENTRE, RADIUS, RADIUS))
    for corners in JOINTS.get(case, []):
        p = [occ.addPoint(*c) for c in corners]
        loop = occ.addCurveLoop([occ.addLine(p[i], p[(i + 1) % 4]) for i in range(4)])
        tools.append(occ.addPlaneSurface([loop]))
    _, children = occ.fragment([(3, box)], [(2, t) for t in tools])
    occ.synchronize()
    model = gmsh.model
    joint = sorted({t for kids in children[1:] for d, t in kids if d == 2})
    model.addPhysicalGroup(3, [t for _, t in model.getEntities(3)], name="rock")
    model.addPhysicalGroup(2, joint, name="joint")
    outer = [t for _, t in model.getEntities(2) if t not in joint]
    model.addPhysicalGroup(2, outer, name="boundary")
    # the curves inside the box (on none of its faces): the X or T line, or the disc's rim
    inner = []
    for _, c in model.getEntities(1):
        lo, hi = np.array(model.getBoundingBox(1, c)).reshape(2, 3)
        flat = (np.abs(hi - lo) < 1e-6) & ((np.abs(lo) < 1e-6) | (np.abs(lo - 1) < 1e-6))
        if not flat.any():
            inner.append(c)
    if inner:
        model.addPhysicalGroup(1, inner, name="line")
    gmsh.option.setNumber("Mesh.MeshSizeMax", h)
    model.mesh.generate(3)
    if order == 2:
        model.mesh.setOrder(2)


def model_mesh(gmsh) -> tuple[np.ndarray, np.ndarray, dict[str, np.ndarray]]:
    """(nodes by tag, shape=(max tag + 1, 3); tets, shape=(n, 4); group -> its elements)."""
    model = gmsh.model
    tags, coords, _ = model.mesh.getNodes()
    xyz = np.full((int(tags.max()) + 1, 3), np.nan)
    xyz[tags.astype(np.int64)] = coords.reshape(-1, 3)
    tets = model.mesh.getElementsByType(4)[1].astype(np.int64).reshape(-1, 4)
    groups = {}
    for d, tag in model.getPhysicalGroups():
        if d < 3:
            rows = [
                nt.astype(np.int64).reshape(-1, d + 1)
                for e in model.getEntitiesForPhysicalGroup(d, tag)
                for nt in model.mesh.getElements(d, e)[2]
            ]
            groups[model.getPhysicalName(d, tag)] = np.concatenate(rows)
    return xyz, tets, groups


@pytest.mark.parametrize("case", ["through", "disc", "x", "t"])
def test_3d_model_split(case: str) -> None:
    from geofrac.meshing.geo import gmsh_session

    with gmsh_session(None, {}) as gmsh:
        box_model(gmsh, case)
        xyz, tets, groups = model_mesh(gmsh)
        added = split_model(gmsh, ["joint"])
        new_xyz, out, after = model_mesh(gmsh)
    # each node is copied as often as the geometry says (the tip rim never)
    used = np.unique(tets)
    expected = copies_expected(case, xyz[used])
    assert added == int(np.sum(expected - 1)) > 0
    assert len(new_xyz) == len(xyz) + added
    assert np.array_equal(np.unique(out), np.arange(1, len(new_xyz)))  # tags 1 ... N
    stand = {tuple(p) for p in xyz[used].tolist()}
    count: dict[tuple[float, ...], int] = {}
    for p in new_xyz[np.unique(out)].tolist():
        count[tuple(p)] = count.get(tuple(p), 0) + 1
    assert set(count) == stand
    assert [count[tuple(p)] for p in xyz[used].tolist()] == expected.tolist()
    # the cut: volume, faces, pieces
    assert np.abs(volumes(new_xyz, out)).sum() == pytest.approx(1.0, rel=1e-12)
    assert np.array_equal(new_xyz[out], xyz[tets])
    holders = face_cells(out)
    for tri in after["joint"].tolist():
        assert len(holders[tuple(sorted(tri))]) == 1  # every joint triangle: one tet
    for tri in after["boundary"].tolist():
        assert len(holders[tuple(sorted(tri))]) == 1
    joint_keys = {tuple(sorted(t)) for t in after["joint"].tolist()}
    boundary_keys = {tuple(sorted(t)) for t in after["boundary"].tolist()}
    for face, cells in holders.items():
        if len(cells) == 1:
            assert face in joint_keys or face in boundary_keys
    assert len(after["joint"]) == 2 * len(groups["joint"])
    assert len(after["boundary"]) == len(groups["boundary"])
    # the twins: each joint triangle's copy stands at the same place, in the same order
    place = {tuple(map(tuple, xyz[t].round(12).tolist())) for t in groups["joint"]}
    twins = [tuple(map(tuple, new_xyz[t].round(12).tolist())) for t in after["joint"]]
    assert set(twins) == place and len(twins) == 2 * len(place)
    assert pieces(out) == {"through": 2, "disc": 1, "x": 4, "t": 3}[case]
    # the X or T line is a curve group: one line element per copy of each edge
    if case in ("x", "t"):
        edges = {
            tuple(sorted((t[i], t[j])))
            for t in out.tolist()
            for i, j in itertools.combinations(range(4), 2)
        }
        assert all(tuple(sorted(e)) in edges for e in after["line"].tolist())
        assert len(after["line"]) == (4 if case == "x" else 3) * len(groups["line"])
    if case == "disc":  # the rim is a tip: its line elements stay as they were
        assert np.array_equal(after["line"], groups["line"])


def test_3d_model_refusals() -> None:
    from geofrac.meshing.geo import gmsh_session

    with gmsh_session(None, {}) as gmsh:
        box_model(gmsh, "t", h=0.5)
        with pytest.raises(ValueError, match="no surface group 'rock'"):
            split_model(gmsh, ["rock"])
        with pytest.raises(ValueError, match="no surface group 'line'"):
            split_model(gmsh, ["line"])
        with pytest.raises(ValueError, match="no surface group 'nothing'"):
            split_model(gmsh, ["nothing"])
    with gmsh_session(None, {}) as gmsh:
        box_model(gmsh, "through", h=0.5, order=2)
        with pytest.raises(ValueError, match="first-order geometry is required"):
            split_model(gmsh, ["joint"])
    with gmsh_session(None, {}) as gmsh:  # hexahedra
        gmsh.model.occ.addBox(0, 0, 0, 1, 1, 1)
        gmsh.model.occ.synchronize()
        gmsh.model.addPhysicalGroup(3, [1], name="rock")
        gmsh.model.addPhysicalGroup(2, [1], name="side")
        gmsh.model.mesh.setTransfiniteAutomatic()
        gmsh.option.setNumber("Mesh.RecombineAll", 1)
        gmsh.option.setNumber("Mesh.Recombine3DAll", 1)
        gmsh.model.mesh.generate(3)
        with pytest.raises(ValueError, match="needs tetrahedra, the mesh has Hexahedron"):
            split_model(gmsh, ["side"])


class BoxBuilder:
    """A :class:`~geofrac.model.scene.GeometryBuilder` of the box with joints (tests)."""

    def __init__(self, case: str) -> None:
        self.case = case

    @property
    def name(self) -> str:
        return f"box-{self.case}"

    def build(self, gmsh) -> tuple[dict[str, int], object]:
        box_model(gmsh, self.case)
        _, tets, groups = model_mesh(gmsh)
        sizes = {f"{k}_elements": len(v) for k, v in groups.items()}
        return {"tets": len(tets), **sizes}, None


def distributed_cut(case: str) -> None:
    """Through build_mesh: each joint facet has one cell, the volume and cell count kept."""
    import dolfinx
    import ufl
    from mpi4py import MPI

    from geofrac.meshing.distribute import build_mesh
    from geofrac.model.scene import Geometry

    comm = MPI.COMM_WORLD
    groups = {"rock": 3, "joint": 2, "boundary": 2, "line": 1}
    geometry = Geometry(None, {}, None, 3, groups, builder=BoxBuilder(case), split=("joint",))
    tagged = build_mesh(geometry, comm)
    mesh, report = tagged.mesh, tagged.report
    assert tagged.num_global(3) == report["tets"]
    volume = dolfinx.fem.assemble_scalar(dolfinx.fem.form(1.0 * ufl.dx(domain=mesh)))
    assert comm.allreduce(volume, op=MPI.SUM) == pytest.approx(1.0, rel=1e-12)
    dim, joint = tagged.entities("joint")
    assert dim == 2
    mesh.topology.create_connectivity(2, 3)
    exterior = dolfinx.mesh.exterior_facet_indices(mesh.topology)
    assert np.all(np.isin(joint, exterior))  # one cell each, on whichever rank
    f2c = mesh.topology.connectivity(2, 3)
    assert all(len(f2c.links(f)) == 1 for f in joint)
    owned = comm.allreduce(len(tagged.owned(2, joint)), op=MPI.SUM)
    assert owned == 2 * report["joint_elements"]
    boundary = comm.allreduce(len(tagged.owned(2, tagged.entities("boundary")[1])), op=MPI.SUM)
    assert boundary == report["boundary_elements"]
    exterior_owned = comm.allreduce(len(tagged.owned(2, exterior)), op=MPI.SUM)
    assert exterior_owned == boundary + owned  # nothing else was cut open
    if "line_elements" in report:
        lines = comm.allreduce(len(tagged.owned(1, tagged.entities("line")[1])), op=MPI.SUM)
        assert lines == {"x": 4, "t": 3}[case] * report["line_elements"]


@pytest.mark.parametrize("case", ["through", "x"])
def test_3d_distributed_joint_facets_have_one_cell(case: str) -> None:
    distributed_cut(case)


@pytest.mark.mpi(min_size=2)
@pytest.mark.parametrize("case", ["through", "t"])
def test_3d_distributed_joint_facets_have_one_cell_mpi(case: str) -> None:
    distributed_cut(case)
