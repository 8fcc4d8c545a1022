"""Pure geometry of crack pieces: rigid motions left free by the supports."""

from types import SimpleNamespace

import numpy as np
import pytest

from geofrac.fracture.contact import SLIP, STICK, constraint_terms, pair_operator
from geofrac.fracture.topology import (
    components,
    constraint_rank,
    free_motions,
    motion_pins,
    motion_rows,
    zero_energy_rows,
)
from geofrac.materials import d_matrix
from geofrac.mls.shape import linear_fit

NO_EXTRA = np.zeros(0)
RGNT = np.array([0.5])  # θ = ½ ω under a rigid rotation ω


def free_motion_pins(
    points: np.ndarray, components: np.ndarray, rotation: np.ndarray, candidates: np.ndarray
) -> list[tuple[int, int]]:
    """(candidate, component) pins of one piece held by the fixed DOFs (points, components)."""
    c = np.asarray(candidates, dtype=float)
    centre = c.mean(axis=0, keepdims=True)
    pts = np.asarray(points, dtype=float).reshape(-1, 2)
    scale = max(1.0, float(np.abs(np.vstack([pts, c]) - centre).max()))
    C = motion_rows(
        pts, components, rotation, pieces=np.zeros(len(pts), int), centres=centre, scale=scale
    )
    return [
        (node, comp) for _, node, comp in motion_pins(C, rotation, [c], centres=centre, scale=scale)
    ]


def column() -> tuple[np.ndarray, np.ndarray]:
    """u_y fixed on the top and bottom rows of a column: free to slide in x."""
    xs = np.arange(3.0)
    pts = np.vstack([np.c_[xs, np.zeros(3)], np.c_[xs, np.full(3, 10.0)]])
    return pts, np.ones(6, dtype=np.int64)


def test_constraint_rank_counts_prevented_rigid_motions():
    assert constraint_rank(np.zeros((0, 2)), np.zeros(0, dtype=np.int64), NO_EXTRA) == 0
    one = np.array([[3.0, 4.0], [3.0, 4.0]])
    assert constraint_rank(one, np.array([0, 1]), NO_EXTRA) == 2  # a pin: rotation free
    # RGNT's θ at the pin also stops the rotation
    assert constraint_rank(np.vstack([one, one[:1]]), np.array([0, 1, 2]), RGNT) == 3
    pts, comps = column()
    assert constraint_rank(pts, comps, NO_EXTRA) == 2
    assert constraint_rank(pts, comps, RGNT) == 2
    assert constraint_rank(np.vstack([pts, [[0.0, 0.0]]]), np.append(comps, 0), NO_EXTRA) == 3
    # far from the origin and at a large scale the rank is unchanged
    assert constraint_rank(pts * 1e3 + 1e6, comps, NO_EXTRA) == 2


def test_free_motion_pins_complete_the_supports_with_fewest_dofs():
    pts, comps = column()
    cand = np.array([[x, y] for x in range(3) for y in range(11)], dtype=float)
    pins = free_motion_pins(pts, comps, NO_EXTRA, cand)
    assert len(pins) == 1 and pins[0][1] == 0  # one u_x stops the sliding
    node = pins[0][0]
    np.testing.assert_array_equal(cand[node], [1.0, 5.0])  # nearest the centroid
    for extra in (NO_EXTRA, RGNT):
        free = free_motion_pins(np.zeros((0, 2)), np.zeros(0, dtype=np.int64), extra, cand)
        assert len(free) == 3
        p = cand[[i for i, _ in free]]
        c = np.array([k for _, k in free])
        assert constraint_rank(p, c, extra) == 3


def test_free_motion_pins_do_not_depend_on_candidate_order():
    rng = np.random.default_rng(7)
    cand = rng.uniform(0.0, 10.0, size=(40, 2))
    pts = np.array([[0.0, 0.0]])
    comps = np.array([1])
    pins = free_motion_pins(pts, comps, NO_EXTRA, cand)
    perm = rng.permutation(len(cand))
    again = free_motion_pins(pts, comps, NO_EXTRA, cand[perm])
    assert [(tuple(cand[i]), k) for i, k in pins] == [(tuple(cand[perm][i]), k) for i, k in again]
    p = np.vstack([pts, cand[[i for i, _ in pins]]])
    assert constraint_rank(p, np.append(comps, [k for _, k in pins]), NO_EXTRA) == 3


def test_zero_energy_rows_are_those_of_the_null_modes():
    """Two DOFs joined by a spring and held by nothing else move freely together.

    One null vector, (1, 1); a DOF with its own spring, or tied to one that has, does not
    move; the answer does not depend on how the DOFs are ordered.
    """
    k = 30.0
    K = np.zeros((4, 4))
    K[np.ix_([0, 1], [0, 1])] = k * np.array([[1.0, -1.0], [-1.0, 1.0]])
    K[2, 2] = k
    K[np.ix_([2, 3], [2, 3])] += k * np.array([[1.0, -1.0], [-1.0, 1.0]])
    assert zero_energy_rows(K, 1e-10 * k).tolist() == [True, True, False, False]
    perm = np.array([3, 1, 2, 0])
    assert zero_energy_rows(K[np.ix_(perm, perm)], 1e-10 * k).tolist() == [False, True, False, True]
    K[0, 0] += 1e-3 * k  # a weak spring is still stiffness
    assert not zero_energy_rows(K, 1e-10 * k).any()
    assert zero_energy_rows(np.zeros((0, 0)), 1.0).shape == (0,)


def test_components_label_each_node_with_its_pieces_smallest_node():
    # pieces {0, 3, 5}, {1, 4}, {2} (alone), {6, 7}; pairs in no particular order,
    # one repeated, one a self-loop
    a = np.array([5, 4, 3, 7, 5, 6])
    b = np.array([3, 1, 0, 6, 3, 6])
    labels = components(8, a, b)
    np.testing.assert_array_equal(labels, [0, 1, 2, 0, 1, 0, 6, 6])
    np.testing.assert_array_equal(components(3, np.zeros(0, int), np.zeros(0, int)), [0, 1, 2])


# -- pieces joined by crack-face contact ---------------------------------------------
#: A crack along the x axis: piece 1 above it (nodes 0-11), piece 0 below (12-23).
T, N = np.array([1.0, 0.0]), np.array([0.0, 1.0])
_RNG = np.random.default_rng(3)
_ABOVE = np.c_[_RNG.uniform(-3.0, 3.0, 12), _RNG.uniform(0.1, 1.5, 12)]
XY = np.vstack([_ABOVE, _ABOVE * [1.0, -1.0] + [0.05, 0.0]])
PIECE = np.repeat([1, 0], 12)
CENTRES = np.array([XY[12:].mean(axis=0), XY[:12].mean(axis=0)])
SCALE = 3.0


def _pairs(at: list[float], states: list[int]) -> SimpleNamespace:
    """Face pairs at x = ``at`` on the crack: MLS fits of each side's nodes.

    Carries what :func:`~geofrac.fracture.contact.constraint_terms` reads (the pairs' operators,
    states, frames and teeth).
    """
    ops = {}
    for e, x in enumerate(at):
        p = np.array([x, 0.0])
        plus = linear_fit(p + 0.3 * N, 3.0, np.arange(12), coords=XY[:12])
        minus = linear_fit(p - 0.3 * N, 3.0, np.arange(12, 24), coords=XY[12:])
        ops[e] = pair_operator(
            plus, minus, p, tangent=T, normal=N, D=d_matrix(1.0, 0.25, 2, plane="strain")
        )
    k = len(at)
    return SimpleNamespace(
        ops=ops,
        state=np.array(states),
        normal=np.tile(N, (k, 1)),
        tangent=np.tile(T, (k, 1)),
        tooth=np.full(k, -1),  # no cohesive pair (fracture energy)
    )


def _constraints(pairs: SimpleNamespace) -> np.ndarray:
    """Piece 0 held by three Dirichlet DOFs; the pairs' rows on both pieces' motions."""
    fixed = [12, 12, 13]
    C = motion_rows(
        XY[fixed], [0, 1, 1], NO_EXTRA, pieces=PIECE[fixed], centres=CENTRES, scale=SCALE
    )
    rows, nodes, comps, weights = constraint_terms(pairs)
    if not len(rows):
        return C
    jumps = motion_rows(
        XY[nodes],
        comps,
        NO_EXTRA,
        pieces=PIECE[nodes],
        centres=CENTRES,
        scale=SCALE,
        rows=rows,
        weights=weights,
    )
    return np.vstack([C, jumps])


def _velocity(motion: np.ndarray, piece: int, x: np.ndarray) -> np.ndarray:
    """The velocity at x of a piece under a motion of :func:`motion_rows`'s columns."""
    tx, ty, w = motion[3 * piece : 3 * piece + 3] / [1.0, 1.0, SCALE]
    r = x - CENTRES[piece]
    return np.array([tx - w * r[1], ty + w * r[0]])


def test_a_piece_stuck_at_one_point_turns_about_it():
    """One sticking pair ties the faces' jump at one point: the piece can only turn there."""
    free = free_motions(_constraints(_pairs([0.4], [STICK])), 6)
    assert free.shape[1] == 1
    motion = free[:, 0]
    np.testing.assert_allclose(motion[:3], 0.0, atol=1e-9)  # the supported piece stays
    np.testing.assert_allclose(_velocity(motion, 1, np.array([0.4, 0.0])), 0.0, atol=1e-9)
    assert np.linalg.norm(_velocity(motion, 1, np.array([2.4, 0.0]))) > 0.1
    assert free_motions(_constraints(_pairs([-1.0, 1.0], [STICK, STICK])), 6).shape[1] == 0


def test_a_piece_on_parallel_slipping_faces_slides_along_them():
    """Slipping pairs tie the normal jump only: the piece slides along the crack."""
    free = free_motions(_constraints(_pairs([-1.0, 0.0, 1.5], [SLIP] * 3)), 6)
    assert free.shape[1] == 1
    motion = free[:, 0]
    np.testing.assert_allclose(motion[:3], 0.0, atol=1e-9)
    for x in (np.array([-2.0, 1.0]), np.array([2.5, 0.3])):
        v = _velocity(motion, 1, x)
        assert abs(v @ N) < 1e-9 and abs(v @ T) > 0.1


@pytest.mark.parametrize(
    "states, num_pins", [([STICK], 1), ([SLIP, SLIP], 1), ([STICK, STICK], 0), ([], 3)]
)
def test_motion_pins_hold_what_the_pairs_leave_free(states, num_pins):
    """Pins go on the piece that moves, and leave nothing free."""
    at = [-1.0, 1.0][: len(states)]
    C = _constraints(_pairs(at, states))
    candidates = [XY[12:], XY[:12]]
    pins = motion_pins(C, NO_EXTRA, candidates, centres=CENTRES, scale=SCALE)
    assert len(pins) == num_pins
    assert all(piece == 1 for piece, _, _ in pins)
    extra = [
        motion_rows(candidates[i][n], [k], NO_EXTRA, pieces=[i], centres=CENTRES, scale=SCALE)
        for i, n, k in pins
    ]
    assert free_motions(np.vstack([C, *extra]), 6).shape[1] == 0
