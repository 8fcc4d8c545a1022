"""The mesh cut along joints (geofrac.meshing.split): sectors, tips, junctions."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from geofrac.meshing.split import EDGES, split_along

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
