"""The registered shapes' weights: partition of unity, linear reproduction, the GIMP integral."""

import numpy as np
import pytest

from geofrac.mpm.grid import grid
from geofrac.mpm.shapes import REGISTRY, UGIMP, Shape, compiled_weights, get, gimp_1d, weights


def _hat(r: np.ndarray, L: float) -> np.ndarray:
    return np.clip(1.0 - np.abs(r) / L, 0.0, None)


@pytest.mark.parametrize("dim", [1, 2, 3])
@pytest.mark.parametrize("shape", REGISTRY.values(), ids=str)
def test_weights_are_a_linear_partition_of_unity(dim, shape: Shape):
    rng = np.random.default_rng(7)
    g = grid(np.full(dim, -1.0), 0.5, [8] * dim)
    x = rng.uniform(-0.6, 2.6, size=(40, dim))
    x[0] = -0.5  # exactly on a node
    lp = rng.uniform(0.05, 0.25, size=(40, dim)) if shape.boxes else None
    w = weights(g, x, shape, lp=lp)
    X = g.nodes()[w.nodes]  # shape=(n, k, dim)
    np.testing.assert_allclose(w.phi.sum(axis=1), 1.0, atol=1e-14)
    np.testing.assert_allclose(np.einsum("nk,nka->na", w.phi, X), x, atol=1e-13)
    np.testing.assert_allclose(w.grad.sum(axis=1), 0.0, atol=1e-13)
    # ∇ of the reproduced coordinate field is the identity
    np.testing.assert_allclose(
        np.einsum("nka,nkb->nab", X, w.grad),
        np.broadcast_to(np.eye(dim), (40, dim, dim)),
        atol=1e-12,
    )
    # a point particle on a node takes its gradients from the cell above it
    if not shape.boxes:
        assert np.abs(w.grad[0]).sum() > 0


def test_gimp_is_the_hat_averaged_over_the_particle():
    """Eq. 4.30 against its definition (4.24): (1/V_p) ∫ N_i χ_p, by the midpoint rule."""
    L, lp = 1.0, 0.3
    r = np.linspace(-1.45, 1.45, 59)
    s = (np.arange(20000) + 0.5) / 20000 * 2 * lp - lp  # midpoints over the box
    phi, dphi = gimp_1d(r[:, None], L, np.array([[lp]]))
    avg = _hat(r[:, None] + s[None, :], L).mean(axis=1)
    np.testing.assert_allclose(phi[:, 0], avg, atol=1e-8)
    # and the gradient is the derivative of that average (central differences)
    e = 1e-6
    num = (
        gimp_1d(r[:, None] + e, L, np.array([[lp]]))[0]
        - gimp_1d(r[:, None] - e, L, np.array([[lp]]))[0]
    ) / (2 * e)
    np.testing.assert_allclose(dphi, num, atol=1e-6)


def test_support_beyond_the_grid_is_refused():
    g = grid([0.0], 1.0, [4])
    with pytest.raises(ValueError, match="beyond the grid"):
        weights(g, np.array([[3.9]]), UGIMP, lp=np.array([[0.25]]))


def test_quadratic_bspline_values_partition_and_continuity():
    """N(0) = 3/4, N(±L) = 1/8, N(±3L/2) = 0; Σ N = 1, Σ N x_i = x; dN/dx continuous."""
    from geofrac.mpm.shapes import bspline2_1d

    L = 0.5
    phi, dphi = bspline2_1d(np.array([0.0, L, -L, 1.5 * L, 0.5 * L]), L)
    np.testing.assert_allclose(phi, [0.75, 0.125, 0.125, 0.0, 0.5], atol=1e-15)
    np.testing.assert_allclose(dphi, [0.0, -0.5 / L, 0.5 / L, 0.0, -1.0 / L], atol=1e-14)
    # the gradient is continuous at |r| = L/2 (C¹), unlike the hat's at r = 0
    eps = 1e-9
    left, right = bspline2_1d(np.array([0.5 * L - eps, 0.5 * L + eps]), L)[1]
    assert left == pytest.approx(right, abs=1e-7)
    g = grid([0.0, 0.0], L, [10, 10])
    x = np.random.default_rng(3).uniform(0.3, 4.7, (40, 2))
    w = weights(g, x, get("bspline2"))
    np.testing.assert_allclose(w.phi.sum(axis=1), 1.0, atol=1e-14)
    np.testing.assert_allclose(
        np.sum(w.phi[:, :, None] * g.nodes()[w.nodes], axis=1), x, atol=1e-13
    )
    np.testing.assert_allclose(w.grad.sum(axis=1), 0.0, atol=1e-13)
    fast = compiled_weights(g, x, get("bspline2"))
    np.testing.assert_array_equal(fast.nodes, w.nodes)
    np.testing.assert_allclose(fast.phi, w.phi, atol=1e-15)
    np.testing.assert_allclose(fast.grad, w.grad, atol=1e-13)


@pytest.mark.parametrize("shape", REGISTRY.values(), ids=str)
def test_every_shape_declares_itself_once(shape: Shape):
    """Registry entry, margin and nodes: what the step, driver and scene loader ask."""
    assert get(shape.name) is shape and str(shape) == shape.name
    lp = np.full((3, 2), 0.2)
    margin = shape.margin(0.5, lp)
    if shape.boxes:
        assert margin is lp
    else:
        assert margin == shape.reach(0.5) >= 0.0
    assert shape.nodes_per_direction(0.5, lp) >= 2
    assert not shape.follows_deformation or shape.boxes  # l_p only matters with boxes


def test_unknown_shape_names_the_registered_ones():
    with pytest.raises(ValueError, match="bspline2"):
        get("cubic")
