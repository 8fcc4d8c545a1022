"""C-MultiMLSM node field (Edo (2016), App. C, eqs. 3.12-3.28): numpy reference and C kernel."""

import warnings

import numpy as np
import pytest

from geofrac.mls.cmulti import (
    ORDER_TERMS,
    compiled_node,
    node_fit,
    node_stiffness,
    order_for,
)

CENTRE = np.array([1.3, -0.7])
H = 0.8
T = 0.25
E, NU = 30.0, 0.25
D_EL = E / (1 - NU**2) * np.array([[1, NU, 0], [NU, 1, 0], [0, 0, (1 - NU) / 2]])


def _satellites(n, seed, centre=CENTRE, h=H):
    """Satellites (n) spread around the centre at 0.2 h < r < 0.95 h, shape=(n, 2)."""
    rng = np.random.default_rng(seed)
    angle = 2 * np.pi * (np.arange(n) + rng.uniform(0.0, 0.6, n)) / max(n, 1)
    r = h * rng.uniform(0.2, 0.95, n)
    return centre + np.column_stack([r * np.cos(angle), r * np.sin(angle)])


def _grain(centre=CENTRE, h=H, k=6):
    """A hexagonal grain of k sub-triangles around the centre, shape=(k, 3, 2)."""
    angle = 2 * np.pi * np.arange(k) / k + 0.3
    rim = centre + 0.4 * h * np.column_stack([np.cos(angle), np.sin(angle)])
    return np.array([[centre, rim[i], rim[(i + 1) % k]] for i in range(k)])


def _inside(k, seed, centre=CENTRE, h=H):
    """Random points (k) inside the influence circle, shape=(k, 2)."""
    rng = np.random.default_rng(seed)
    r = 0.99 * h * np.sqrt(rng.uniform(0.0, 1.0, k))
    a = rng.uniform(0.0, 2 * np.pi, k)
    return centre + np.column_stack([r * np.cos(a), r * np.sin(a)])


def _fit(n, seed=0, **kw):
    xy = _satellites(n, seed)
    return node_fit(CENTRE, H, 100, ids=np.arange(n) + 1, xy=xy, **kw), xy


def _nodal(field, xy):
    """u_nodes = (u_i, v_i, u_1, v_1, ...) of a vector field, shape=(2(n+1),)."""
    return field(np.vstack([CENTRE, xy])).ravel()


class Quadratic:
    """u(x) = a · q(d), v(x) = b · q(d), q = (1, dx, dy, dx², dx dy, dy²), d = x - x_i."""

    def __init__(self, seed, linear_only=False):
        rng = np.random.default_rng(seed)
        self.a, self.b = rng.normal(size=6), rng.normal(size=6)
        if linear_only:
            self.a[3:] = self.b[3:] = 0.0

    def __call__(self, x):
        d = np.atleast_2d(x) - CENTRE
        q = np.column_stack(
            [np.ones(len(d)), d[:, 0], d[:, 1], d[:, 0] ** 2, d[:, 0] * d[:, 1], d[:, 1] ** 2]
        )
        return np.column_stack([q @ self.a, q @ self.b])

    def strain(self, x):
        d = np.atleast_2d(x) - CENTRE
        a, b = self.a, self.b
        ux = a[1] + 2 * a[3] * d[:, 0] + a[4] * d[:, 1]
        uy = a[2] + a[4] * d[:, 0] + 2 * a[5] * d[:, 1]
        vx = b[1] + 2 * b[3] * d[:, 0] + b[4] * d[:, 1]
        vy = b[2] + b[4] * d[:, 0] + 2 * b[5] * d[:, 1]
        return np.column_stack([ux, vy, uy + vx])

    def parameters(self):
        """(θ, εx, εy, γ, εx,x, εx,y, εy,x, εy,y, γ,x, γ,y) at the centre."""
        a, b = self.a, self.b
        return np.array(
            [
                (b[1] - a[2]) / 2,
                a[1],
                b[2],
                a[2] + b[1],
                2 * a[3],
                a[4],
                b[4],
                2 * b[5],
                a[4] + 2 * b[3],
                2 * a[5] + b[4],
            ]
        )


def _rel(actual, expected):
    return np.abs(actual - expected).max() / np.abs(expected).max()


@pytest.mark.parametrize(("n", "order"), [(10, 2), (9, 1), (4, 1), (3, 0), (1, 0), (0, -1)])
def test_order_follows_the_satellite_count(n, order):
    assert order_for(n) == order
    fit, _ = _fit(n, seed=n)
    assert fit.order == order
    assert fit.coefficients.shape == (ORDER_TERMS[order], 2 * (n + 1))
    assert fit.nodes.dtype == np.int64
    assert fit.nodes[0] == 100
    np.testing.assert_array_equal(fit.nodes[1:], np.arange(n) + 1)


@pytest.mark.parametrize("n", [10, 13])
def test_order_2_reproduces_quadratic_fields(n):
    fit, xy = _fit(n, seed=n)
    assert fit.order == 2
    field = Quadratic(seed=7)
    u = _nodal(field, xy)
    x = _inside(20, seed=1)
    assert _rel(fit.displacement_matrix(x) @ u, field(x)) < 1e-10
    assert _rel(fit.strain_matrix(x) @ u, field.strain(x)) < 1e-10
    np.testing.assert_allclose(fit.parameters(u), field.parameters(), rtol=1e-10, atol=1e-10)


@pytest.mark.parametrize("n", [4, 7, 9])
def test_order_1_reproduces_linear_but_not_quadratic_fields(n):
    fit, xy = _fit(n, seed=n)
    assert fit.order == 1
    x = _inside(20, seed=2)
    linear = Quadratic(seed=3, linear_only=True)
    u = _nodal(linear, xy)
    assert _rel(fit.displacement_matrix(x) @ u, linear(x)) < 1e-10
    assert _rel(fit.strain_matrix(x) @ u, linear.strain(x)) < 1e-10
    np.testing.assert_allclose(fit.parameters(u), linear.parameters()[:4], rtol=1e-10)
    quadratic = Quadratic(seed=3)
    u = _nodal(quadratic, xy)
    assert _rel(fit.displacement_matrix(x) @ u, quadratic(x)) > 1e-3


@pytest.mark.parametrize("n", [1, 2, 3])
def test_order_0_reproduces_rigid_rotation(n):
    fit, xy = _fit(n, seed=n)
    assert fit.order == 0
    omega, pivot, shift = 0.03, np.array([-2.0, 0.5]), np.array([0.4, -0.1])

    def rotation(x):
        d = np.atleast_2d(x) - pivot
        return shift + omega * np.column_stack([-d[:, 1], d[:, 0]])

    u = _nodal(rotation, xy)
    x = _inside(10, seed=4)
    assert _rel(fit.displacement_matrix(x) @ u, rotation(x)) < 1e-12
    np.testing.assert_allclose(fit.parameters(u), [omega], rtol=1e-12)
    assert not fit.strain_matrix(x).any()
    assert not node_stiffness(fit, D_EL, T, triangles=_grain()).any()


def test_fragment_moves_rigidly_with_its_node():
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        fit = node_fit(CENTRE, H, 5, ids=np.zeros(0, dtype=int), xy=np.zeros((0, 2)))
        assert fit.order == -1
        assert fit.coefficients.shape == (0, 2)
        x = _inside(4, seed=5)
        N = fit.displacement_matrix(x)
        np.testing.assert_array_equal(N, np.broadcast_to(np.eye(2), (4, 2, 2)))
        assert fit.parameters(np.array([0.1, 0.2])).shape == (0,)
        K = node_stiffness(fit, D_EL, T, triangles=_grain())
        assert K.shape == (2, 2)
        assert not K.any()
        order, G, Kc = compiled_node(
            CENTRE, H, np.zeros((0, 2)), order=None, triangles=_grain(), D=D_EL, thickness=T
        )
        assert order == -1
        assert G.shape == (0, 2)
        assert not Kc.any()


def _line(n, offset, wobble=0.0):
    """Satellites (n) on a line at ``offset`` from CENTRE, moved off it by up to ``wobble`` h.

    Returns:
        positions, shape=(n, 2).
    """
    s = np.linspace(-0.6, 0.6, n) * H
    s = s[np.abs(s) > 1e-3]
    direction, normal = np.array([0.8, 0.6]), np.array([-0.6, 0.8])
    off = offset + wobble * H * np.cos(1.7 * np.arange(len(s)))
    return CENTRE + np.outer(off, normal) + np.outer(s, direction)


# Nearly collinear: A is positive definite but its pivot ratio is ~6e-14 (order 1, through
# the node) or ~7e-14 (order 2, off the node), so the pivot rule rejects it.
@pytest.mark.parametrize(
    ("offset", "wobble", "order"),
    [(0.0, 0.0, 0), (0.3 * H, 0.0, 1), (0.0, 1e-7, 0), (0.3 * H, 1e-6, 1)],
)
def test_collinear_satellites_drop_below_order_2(offset, wobble, order):
    xy = _line(12, offset, wobble)
    n = len(xy)
    assert order_for(n) == 2
    fit = node_fit(CENTRE, H, 0, ids=np.arange(n) + 1, xy=xy)
    assert fit.order == order
    assert np.all(np.isfinite(fit.coefficients))
    K = node_stiffness(fit, D_EL, T, triangles=_grain())
    assert np.all(np.isfinite(K))
    field = Quadratic(seed=8, linear_only=True)
    x = _inside(5, seed=6)
    assert np.all(np.isfinite(fit.displacement_matrix(x) @ _nodal(field, xy)))


def _rigid_modes(points):
    """Two translations and an infinitesimal rotation about CENTRE, shape=(3, 2 len(points))."""
    d = points - CENTRE
    modes = np.zeros((3, len(points), 2))
    modes[0, :, 0] = 1.0
    modes[1, :, 1] = 1.0
    modes[2] = np.column_stack([-d[:, 1], d[:, 0]])
    return modes.reshape(3, -1)


@pytest.mark.parametrize("n", [6, 12])
def test_stiffness_is_symmetric_psd_with_rigid_null_space_and_strain_energy(n):
    fit, xy = _fit(n, seed=20 + n)
    assert fit.order == (2 if n >= 10 else 1)
    grain = _grain()
    K = node_stiffness(fit, D_EL, T, triangles=grain)
    scale = np.abs(K).max()
    assert scale > 0
    np.testing.assert_allclose(K, K.T, atol=1e-13 * scale)
    assert np.linalg.eigvalsh(K).min() > -1e-12 * scale
    rigid = _rigid_modes(np.vstack([CENTRE, xy]))
    assert np.abs(K @ rigid.T).max() < 1e-12 * scale * np.abs(rigid).max()
    linear = Quadratic(seed=9, linear_only=True)
    u = _nodal(linear, xy)
    eps = linear.strain(CENTRE)[0]
    e1, e2 = grain[:, 1] - grain[:, 0], grain[:, 2] - grain[:, 0]
    area = 0.5 * np.abs(e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0]).sum()
    assert 0.5 * u @ K @ u == pytest.approx(0.5 * T * area * eps @ D_EL @ eps, rel=1e-10)


CASES = {
    "order 2": (_satellites(14, 31), None, 2),
    "order 1": (_satellites(8, 32), None, 1),
    "order 0": (_satellites(3, 33), None, 0),
    "fragment": (np.zeros((0, 2)), None, -1),
    "start 2 with 7 satellites": (_satellites(7, 34), 2, 2),
    "start 0 with 12 satellites": (_satellites(12, 35), 0, 0),
    "collinear through the node": (_line(12, 0.0), None, 0),
    "collinear off the node": (_line(12, 0.3 * H), None, 1),
    "nearly collinear through the node": (_line(12, 0.0, 1e-7), None, 0),
    "nearly collinear off the node": (_line(12, 0.3 * H, 1e-6), None, 1),
}


@pytest.mark.parametrize("case", list(CASES))
def test_compiled_kernel_equals_numpy(case):
    xy, start, order = CASES[case]
    n = len(xy)
    grain = _grain()
    fit = node_fit(CENTRE, H, 0, ids=np.arange(n) + 1, xy=xy, order=start)
    K = node_stiffness(fit, D_EL, T, triangles=grain)
    assert fit.order == order
    accepted, G, Kc = compiled_node(
        CENTRE, H, xy, order=start, triangles=grain, D=D_EL, thickness=T
    )
    assert accepted == order
    assert G.shape == fit.coefficients.shape
    g_scale = max(np.abs(fit.coefficients).max(initial=0.0), 1.0)
    np.testing.assert_allclose(G, fit.coefficients, rtol=1e-11, atol=1e-11 * g_scale)
    k_scale = max(np.abs(K).max(), 1e-300)
    np.testing.assert_allclose(Kc, K, rtol=1e-11, atol=1e-11 * k_scale)


def test_invalid_input_is_rejected():
    xy = _satellites(5, 40)
    with pytest.raises(ValueError, match="0 < r < h"):
        node_fit(CENTRE, H, 0, ids=np.arange(6), xy=np.vstack([xy, CENTRE]))
    with pytest.raises(ValueError, match="0 < r < h"):
        node_fit(CENTRE, H, 0, ids=np.arange(6), xy=np.vstack([xy, CENTRE + np.array([H, 0.0])]))
    with pytest.raises(ValueError, match="order"):
        node_fit(CENTRE, H, 0, ids=np.arange(5), xy=xy, order=3)
    with pytest.raises(ValueError, match="order"):
        compiled_node(CENTRE, H, xy, order=-2, triangles=_grain(), D=D_EL, thickness=T)
