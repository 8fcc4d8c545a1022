"""Integration-consistent MLS cells (geofrac/fracture/consistent.py) against the patch test.

A discretisation passes the patch test in stress when a linear displacement field gives
its exact (uniform) strain in every cell and a uniform stress is in equilibrium at every
node with the boundary's and the crack faces' tractions. The MLS cells of Edo (2016),
eq. 2.19, fail the second (docs/cracking.md, "Joint slip"); the consistent cells must
pass both to round-off, on a distorted mesh with cracks, a crack tip, a fragment (a void
cell) and cells refitted around them.
"""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from geofrac.fracture.consistent import void_sides
from geofrac.fracture.state import CrackState, MlsSettings
from geofrac.fracture.topology import edge_mesh
from tests.fracture.helpers import grid_mesh

#: Uniform stress (σ_xx, σ_yy, σ_xy) of the balance test.
SIGMA = np.array([[-1.3, 0.4], [0.4, -2.1]])
#: A linear field u = G x + u0 of the reproduction test.
GRAD = np.array([[0.3, -0.7], [1.1, 0.2]])


def _mesh(n: int = 12, seed: int = 3):
    """A grid on [0, n]² with its interior nodes moved by up to 0.2 (seeded)."""
    coords, cells = grid_mesh(n)
    rng = np.random.default_rng(seed)
    inner = (coords > 0).all(axis=1) & (coords < n).all(axis=1)
    coords[inner] += rng.uniform(-0.2, 0.2, (int(inner.sum()), 2))
    return edge_mesh(coords, cells)


def _path(m, nodes: list[int]) -> list[int]:
    """The edges joining consecutive ``nodes``."""
    key = {tuple(sorted(e)): i for i, e in enumerate(m.edges.tolist())}
    return [key[tuple(sorted(p))] for p in itertools.pairwise(nodes)]


def _cracks(m, n: int = 12) -> list[int]:
    """Two interior cracks (one kinked) and the three edges of one cell (a fragment)."""
    row = lambda j, i: j * (n + 1) + i  # noqa: E731
    a = _path(m, [row(6, i) for i in range(2, 8)])  # horizontal, tips inside
    b = _path(m, [row(3, 4), row(3, 5), row(4, 6), row(5, 6), row(5, 7)])
    cell = 2 * (9 * n + 9)  # a cell away from both
    return sorted(set(a + b + m.cell_edges[cell].tolist()))


def _state(gradient: str, *, step: bool = False) -> CrackState:
    m = _mesh()
    none = np.zeros(m.num_cells, dtype=bool)
    held = (m.coords[m.cells, 1] == 0.0).any(axis=1)  # cells on a supported bottom
    state = CrackState(m, held, none, MlsSettings(gradient=gradient), cut=True)
    cracks = _cracks(m)
    if step:  # crack by crack, as the event loop does
        state.start(np.zeros(0, dtype=np.int64))
        for e in cracks:
            state.crack(e)
    else:
        state.start(np.array(cracks, dtype=np.int64))
    return state


def _normal(m, c: int, e: int) -> np.ndarray:
    """Edge e's outward normal of cell c times its length, shape=(2,)."""
    p, q = m.coords[m.edges[e]]
    mid, d = 0.5 * (p + q), q - p
    n = np.array([d[1], -d[0]])
    return n if n @ (mid - m.coords[m.cells[c]].mean(axis=0)) > 0 else -n


def _imbalance(state: CrackState) -> np.ndarray:
    """Nodal force of the uniform SIGMA: cells − boundary tractions − crack faces, (n, 2).

    Element cells by their CST gradients, MLS cells by their fields' gradients, void
    cells by :func:`void_sides`; the boundary and every crack face between two live cells
    (a face pair) carry σ n, on the boundary by the nodal interpolation, on a face by its
    cell's own fit.
    """
    m = state.mesh
    f = np.zeros((len(m.coords), 2))
    for c in range(m.num_cells):
        fit = state.fits.get(c, False)
        if fit is False:  # an element cell: A ∇N_a = ½ L n of the opposite side
            for e in m.cell_edges[c].tolist():
                for v in m.edges[e].tolist():
                    f[v] += 0.5 * SIGMA @ _normal(m, c, e)
        elif fit is None:
            for nodes, w, ln in void_sides(
                c, mesh=m, own=state.own_fits, cracked=state.cracked, node_cracks=state.node_cracks
            ):
                np.add.at(f, nodes, np.outer(w, SIGMA @ ln))
        else:
            np.add.at(f, fit.nodes, state.areas[c] * (SIGMA @ fit.gradients()).T)
    for e in np.flatnonzero(m.boundary_edges | state.cracked).tolist():
        p, q = m.coords[m.edges[e]]
        sides = [state.own_fits.get(c, False) if c >= 0 else None for c in m.edge_cells[e]]
        if state.cracked[e] and None in sides:
            continue  # beside a void cell: no face pair, the void cell carries σ
        for c, own in zip(m.edge_cells[e].tolist(), sides, strict=True):
            if own is None:
                continue
            t = SIGMA @ _normal(m, c, e)
            if own is False:
                for v in m.edges[e].tolist():
                    f[v] -= 0.5 * t
            else:
                np.add.at(f, own.nodes, -np.outer(own.shape_functions(0.5 * (p + q))[0], t))
    return f


def test_consistent_cells_reproduce_a_linear_field():
    state = _state("consistent")
    assert len(state.void_cells()) >= 1 and len(state.mls_cells) > 40
    u = state.mesh.coords @ GRAD.T + [0.5, -0.25]
    for c, fit in state.fits.items():
        if fit is None:
            continue
        np.testing.assert_allclose(fit.gradients() @ u[fit.nodes], GRAD.T, atol=1e-12)
        at = fit.shape_functions(state.centroids[c])[0] @ u[fit.nodes]
        np.testing.assert_allclose(at, GRAD @ state.centroids[c] + [0.5, -0.25], atol=1e-12)


@pytest.mark.parametrize("step", [False, True])
def test_a_uniform_stress_is_in_balance_at_every_node(step):
    """Cells, fragment and faces carry SIGMA in balance to round-off, also crack by crack."""
    f = _imbalance(_state("consistent", step=step))
    assert np.abs(f).max() < 1e-12 * np.abs(SIGMA).max()


def test_the_fits_own_gradient_is_not_in_balance():
    """The same check fails for Edo (2016)'s eq. 2.19 cells: it can fail."""
    f = _imbalance(_state("fit"))
    assert np.abs(f).max() > 1e-2 * np.abs(SIGMA).max()


def test_crack_by_crack_equals_all_at_once():
    """The cells updated after each crack (touched_cells) are all that change."""
    step, fresh = _state("consistent", step=True), _state("consistent")
    assert set(step.fits) == set(fresh.fits)
    for c, fit in fresh.fits.items():
        other = step.fits[c]
        if fit is None:
            assert other is None
            continue
        assert other is not None
        np.testing.assert_array_equal(other.nodes, fit.nodes)
        np.testing.assert_allclose(other.coefficients, fit.coefficients, atol=1e-13)
