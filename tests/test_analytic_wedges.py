"""The two-wedge limit equilibrium (geofrac/analytic_wedges.py) against the force polygons.

The references are the textbook method of wedges, derived independently of the module's
vector solve: each wedge's weight, base reaction (at φ_b = atan μ from the base normal,
against the motion) and interface reaction (at φ from the interface normal) close a
triangle, and the sine rule gives the interface force's normal component

    P_req = W₁ sin(α₁ − φ_b) cos φ / cos(α₁ − φ_b − φ − ω),
    P_cap = W₂ sin(α₂ + φ_b) cos φ / cos(α₂ + φ_b + φ + ω).
"""

import math

import pytest

from geofrac.analytic_wedges import threshold_angle, wedge_forces


def _polygon(w1, w2, a1, a2, mu, phi, omega):
    pb = math.atan(mu)
    a1, a2, f, om = (math.radians(v) for v in (a1, a2, phi, omega))
    req = w1 * math.sin(a1 - pb) * math.cos(f) / math.cos(a1 - pb - f - om)
    den = math.cos(a2 + pb + f + om)
    cap = w2 * math.sin(a2 + pb) * math.cos(f) / den if den > 0 else math.inf
    return req, cap


@pytest.mark.parametrize("omega", [-20.0, 0.0, 15.0])
@pytest.mark.parametrize("phi", [0.0, 12.0, 25.0, 40.0])
@pytest.mark.parametrize(
    ("a1", "a2", "mu"), [(12.3, 20.0, 0.1), (30.0, 5.0, 0.3), (20.0, 0.0, 0.0)]
)
def test_the_vector_solve_is_the_force_polygon(a1, a2, mu, phi, omega):
    got = wedge_forces(1607.0, 247.0, alpha_upper=a1, alpha_lower=a2, mu=mu, phi=phi, omega=omega)
    req, cap = _polygon(1607.0, 247.0, a1, a2, mu, phi, omega)
    assert got.required == pytest.approx(req, rel=1e-12)
    if math.isinf(cap):
        assert math.isinf(got.capacity)
    else:
        assert got.capacity == pytest.approx(cap, rel=1e-12)


def test_an_upper_wedge_on_a_plane_it_holds_needs_no_push():
    """μ = tan α₁: the upper wedge is at its own limit; the layer stands for any φ."""
    got = wedge_forces(
        10.0, 1.0, alpha_upper=20.0, alpha_lower=10.0, mu=math.tan(math.radians(20.0)), phi=0.0
    )
    assert got.required == pytest.approx(0.0, abs=1e-12)
    assert (
        threshold_angle(
            10.0, 1.0, alpha_upper=19.0, alpha_lower=10.0, mu=math.tan(math.radians(20.0))
        )
        == 0.0
    )


def test_the_threshold_balances_the_two_forces():
    kw = dict(alpha_upper=12.3, alpha_lower=20.0, mu=0.1)
    phi = threshold_angle(1607.0, 247.0, **kw)
    req, cap = _polygon(1607.0, 247.0, 12.3, 20.0, 0.1, phi, 0.0)
    assert req == pytest.approx(cap, rel=1e-5)
    assert not wedge_forces(1607.0, 247.0, phi=phi - 0.01, **kw).stable
    assert wedge_forces(1607.0, 247.0, phi=phi + 0.01, **kw).stable
    # a heavier lower wedge holds the layer with less soil friction
    assert threshold_angle(1607.0, 400.0, **kw) < phi


def test_bad_input_is_refused():
    with pytest.raises(ValueError, match="weights"):
        wedge_forces(0.0, 1.0, alpha_upper=10.0, alpha_lower=10.0, mu=0.1, phi=10.0)
    with pytest.raises(ValueError, match="angles"):
        wedge_forces(1.0, 1.0, alpha_upper=95.0, alpha_lower=10.0, mu=0.1, phi=10.0)
