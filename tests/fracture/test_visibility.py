"""Visibility of nodes across cracks (the fan of Edo (2016), Fig. 2.3)."""

import numpy as np

from geofrac.fracture.state import CrackState, MlsSettings
from geofrac.fracture.topology import edge_mesh
from geofrac.fracture.visibility import Bins, PointIndex, blocked, visible_nodes
from tests.fracture.helpers import grid_mesh


def test_blocked_touching_and_crossing():
    p = np.zeros(2)
    a, b = np.array([[1.0, -1.0]]), np.array([[1.0, 1.0]])
    q = np.array([[2.0, 0.0], [0.5, 0.0], [1.0, 0.0], [1.0, 1.0], [2.0, 3.0]])
    np.testing.assert_array_equal(blocked(p, q, a=a, b=b), [True, False, True, True, False])
    # collinear: overlapping blocks, disjoint does not
    a2, b2 = np.array([[1.0, 0.0]]), np.array([[2.0, 0.0]])
    q2 = np.array([[3.0, 0.0], [0.5, 0.0]])
    np.testing.assert_array_equal(blocked(p, q2, a=a2, b=b2), [True, False])


def test_edge_mesh_counts():
    coords, cells = grid_mesh(4)
    m = edge_mesh(coords, cells)
    assert len(m.edges) == 4 * 5 * 2 + 16  # horizontal + vertical + diagonals
    assert m.boundary_edges.sum() == 16
    for c, edges in enumerate(m.cell_edges):
        for e in edges:
            assert c in m.edge_cells[e]


def _crack_line(m, y, x0, x1):
    """Edges on the horizontal line y between x0 and x1."""
    seg = m.coords[m.edges]
    on = (seg[:, 0, 1] == y) & (seg[:, 1, 1] == y)
    lo, hi = seg[:, :, 0].min(axis=1), seg[:, :, 0].max(axis=1)
    return np.flatnonzero(on & (lo >= x0) & (hi <= x1))


def test_nodes_across_a_crack_are_hidden():
    coords, cells = grid_mesh(8)
    m = edge_mesh(coords, cells)
    state = CrackState(m, np.zeros(len(cells), bool), np.zeros(len(cells), bool), MlsSettings())
    crack = _crack_line(m, 4.0, 0.0, 8.0)  # a through crack along y = 4
    state.start(crack)
    for c, fit in state.fits.items():
        assert fit is not None
        above = m.centroids()[c, 1] > 4.0
        ys = coords[fit.nodes, 1]
        assert np.all(ys > 4.0) if above else np.all(ys < 4.0)
        assert len(fit.nodes) >= 10


def test_node_with_every_edge_cracked_is_seen_by_no_cell():
    coords, cells = grid_mesh(6)
    m = edge_mesh(coords, cells)
    node = 3 * 7 + 3  # the centre (3, 3)
    star = np.flatnonzero((m.edges == node).any(axis=1))
    state = CrackState(m, np.zeros(len(cells), bool), np.zeros(len(cells), bool), MlsSettings())
    state.start(star)
    for fit in state.fits.values():
        assert fit is None or node not in fit.nodes


def test_fragment_cell_is_void():
    coords, cells = grid_mesh(4)
    m = edge_mesh(coords, cells)
    state = CrackState(m, np.zeros(len(cells), bool), np.zeros(len(cells), bool), MlsSettings())
    state.start(m.cell_edges[9])  # all three edges of one cell
    assert 9 in state.void_cells()


def test_crack_refits_only_nearby_cells():
    coords, cells = grid_mesh(12)
    m = edge_mesh(coords, cells)
    state = CrackState(m, np.zeros(len(cells), bool), np.zeros(len(cells), bool), MlsSettings())
    state.start(np.concatenate([_crack_line(m, 6.0, 0.0, 5.0), _crack_line(m, 6.0, 7.0, 12.0)]))
    before = {c: f.nodes.copy() for c, f in state.fits.items()}
    nxt = _crack_line(m, 6.0, 5.0, 6.0)
    changed = state.crack(int(nxt[0]))
    far = [c for c in before if np.hypot(*(m.centroids()[c] - [5.5, 6.0])) > 5.0]
    assert far and not set(far) & set(changed.tolist())
    for c in far:
        np.testing.assert_array_equal(state.fits[c].nodes, before[c])


def test_visible_nodes_grow_to_target():
    coords, _cells = grid_mesh(10)
    ids, h = visible_nodes(
        np.array([5.2, 5.3]),
        coords,
        PointIndex(coords),
        crack_bins=Bins(2.0),
        crack_segments=np.zeros((0, 2, 2)),
        start=0.5,
        target=10,
        max_radius=20.0,
    )
    assert len(ids) >= 10
    assert np.all(np.hypot(*(coords[ids] - [5.2, 5.3]).T) < h)


def test_kept_fits_equal_a_full_refit():
    """Edge by edge (fits kept when no satellite is hidden) equals fitting from scratch.

    A fresh state with all those edges cracked computes every fit anew.
    """
    coords, cells = grid_mesh(12)
    rng = np.random.default_rng(11)
    inner = (coords[:, 0] > 0) & (coords[:, 0] < 12)
    coords[inner, 0] += rng.uniform(-0.2, 0.2, inner.sum())  # x only: the lines stay
    m = edge_mesh(coords, cells)
    none = np.zeros(len(cells), bool)
    step = CrackState(m, none, none, MlsSettings())
    step.start(np.zeros(0, dtype=np.int64))
    path = np.concatenate([_crack_line(m, 6.0, 1.0, 9.0), _crack_line(m, 3.0, 2.0, 10.0)])
    kept = 0
    for e in path:
        before = dict(step.fits)
        changed = step.crack(int(e))
        kept += sum(1 for c in before if c not in changed and step.fits[c] is before[c])
    fresh = CrackState(m, none, none, MlsSettings())
    fresh.start(path)
    assert kept > 0
    assert set(step.fits) == set(fresh.fits)
    for c, fit in fresh.fits.items():
        if fit is None:
            assert step.fits[c] is None
        else:
            np.testing.assert_array_equal(step.fits[c].nodes, fit.nodes)
            assert step.fits[c].h == fit.h


def _hinge_state(cut=True):
    """All cells but cell 0 use MLS; no fit uses cell 0's vertices but the first."""
    from types import SimpleNamespace

    coords, cells = grid_mesh(4)
    m = edge_mesh(coords, cells)
    n = len(cells)
    state = CrackState(m, np.zeros(n, bool), np.zeros(n, bool), MlsSettings(), cut=cut)
    a, b, c = cells[0]
    others = np.setdiff1d(np.arange(len(coords)), [b, c])
    state.own_fits = state.fits = {k: SimpleNamespace(nodes=others) for k in range(1, n)}
    return state, (a, b, c)


def test_an_element_cell_hanging_on_one_node_is_hinged():
    """It would turn about that node without strain energy, so it takes an MLS field."""
    state, _ = _hinge_state()
    np.testing.assert_array_equal(state.hinged_cells(), [0])
    assert not len(_hinge_state(cut=False)[0].hinged_cells())  # the rule is contact's


def test_an_element_cell_held_by_two_nodes_or_a_support_is_not_hinged():
    from types import SimpleNamespace

    state, (a, b, _) = _hinge_state()
    state.fits[1] = SimpleNamespace(nodes=np.array([a, b]))
    assert not len(state.hinged_cells())
    state, _ = _hinge_state()
    state.frozen[0] = True  # touches a Dirichlet node
    assert not len(state.hinged_cells())


def test_point_index_finds_exactly_the_points_in_a_disk():
    """Against brute force, points on the circle included, nothing beyond the 1e-9 hair."""
    rng = np.random.default_rng(3)
    points = np.round(rng.random((2000, 2)) * 10, 1)  # many exact distances
    index = PointIndex(points)
    for centre, r in [((5.0, 5.0), 1.0), ((0.0, 0.0), 2.5), ((3.3, 7.1), 0.05)]:
        d = np.hypot(*(points - centre).T)
        got = index.query(np.array(centre), r)
        np.testing.assert_array_equal(got, np.flatnonzero(d <= r * (1 + 1e-9)))


def test_only_interior_edges_are_crack_sites():
    """An edge on the boundary has one cell, no second face: never a crack site."""
    coords, cells = grid_mesh(4)
    m = edge_mesh(coords, cells)
    state = CrackState(m, np.zeros(len(cells), bool), np.zeros(len(cells), bool), MlsSettings())
    one_cell = (m.edge_cells < 0).any(axis=1)
    assert one_cell.sum() == 16
    np.testing.assert_array_equal(state.crackable, ~one_cell)


def test_no_satellite_across_a_notch():
    """A cracked cell beside a slot does not see the nodes across the slot's gap.

    A slot from the bottom of a 9 x 9 grid, 1 wide (4 < x < 5) and 5 deep, is modelled by
    removing its cells. A crack beside its left face hides nothing on the right, yet the
    nodes on the slot's right face lie within the fitted cells' influence circles: none
    of them below the slot's top may be a satellite.
    """
    coords, cells = grid_mesh(9)
    centre = coords[cells].mean(axis=1)
    keep = ~((centre[:, 0] > 4.0) & (centre[:, 0] < 5.0) & (centre[:, 1] < 5.0))
    m = edge_mesh(coords, cells[keep])
    n = int(keep.sum())
    state = CrackState(m, np.zeros(n, bool), np.zeros(n, bool), MlsSettings())
    seg = m.coords[m.edges]
    # the horizontal edge 3 <= x <= 4 at y = 2, ending on the slot's left face
    crack = np.flatnonzero(
        (seg[:, 0, 1] == 2.0) & (seg[:, 1, 1] == 2.0) & (seg[:, :, 0].max(axis=1) == 4.0)
    )
    assert len(crack) == 1
    state.start(crack)
    assert state.fits
    for fit in state.fits.values():
        assert fit is not None
        x, y = m.coords[fit.nodes].T
        assert np.all(x[y < 5.0] <= 4.0)


def _hinged_by_definition(state):
    """Hinged cells from the definition, cell by cell (union-find over uncracked edges)."""
    m = state.mesh
    elem = [c for c in range(m.num_cells) if c not in state.own_fits]
    parent = {c: c for c in elem}

    def root(c):
        while parent[c] != c:
            c = parent[c]
        return c

    for e, (c0, c1) in enumerate(m.edge_cells):
        if c0 in parent and c1 in parent and not state.cracked[e]:
            parent[root(c0)] = root(c1)
    pieces = {}
    for c in elem:
        pieces.setdefault(root(c), []).append(c)
    used = set()
    for fit in state.own_fits.values():
        if fit is not None:
            used.update(int(v) for v in fit.nodes)
    node_pieces = {}
    for r, cs in pieces.items():
        for c in cs:
            for v in m.cells[c]:
                node_pieces.setdefault(int(v), set()).add(r)
    out = []
    for cs in pieces.values():
        if any(state.frozen[c] for c in cs):
            continue
        nodes = {int(v) for c in cs for v in m.cells[c]}
        if sum(1 for v in nodes if v in used or len(node_pieces[v]) > 1) <= 1:
            out += cs
    return sorted(out)


def test_hinged_cells_match_the_definition_on_random_crack_states():
    """The vectorised search (loose pieces only) finds what the definition finds."""
    from types import SimpleNamespace

    coords, cells = grid_mesh(8)
    m = edge_mesh(coords, cells)
    n = len(cells)
    rng = np.random.default_rng(7)
    found = 0
    for trial in range(40):
        frozen = np.zeros(n, bool)
        frozen[rng.choice(n, size=2, replace=False)] = True
        state = CrackState(m, frozen, np.zeros(n, bool), MlsSettings(), cut=True)
        mls = rng.choice(n, size=rng.integers(n // 2, 7 * n // 8), replace=False)
        state.own_fits = state.fits = {
            int(c): (
                None
                if rng.random() < 0.2
                else SimpleNamespace(nodes=rng.choice(len(coords) // 4, size=2, replace=False))
            )
            for c in mls
        }
        state.cracked[rng.random(len(m.edges)) < rng.uniform(0.3, 0.9)] = True
        expected = _hinged_by_definition(state)
        found += len(expected)
        np.testing.assert_array_equal(state.hinged_cells(), expected, err_msg=f"trial {trial}")
    assert found > 20  # the trials do leave hanging pieces
