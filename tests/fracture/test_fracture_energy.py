"""Fracture energy: the saw-tooth softening of cohesive crack faces (docs/cracking.md).

References are closed forms, not the code under test:

- the saw-tooth (:func:`~geofrac.fracture.softening.saw_tooth`): the area between the
  consecutive secants of its teeth, ½ w_i² (k_i − k_{i+1}), summed over the teeth, is G_f;
  the teeth straddle the linear envelope σ(w) = f_t (1 − (w − w₀)/(w_c − w₀)),
  w_c = 2 G_f / f_t, within the band p f_t, and soften monotonically.
"""

from __future__ import annotations

import numpy as np
import pytest

from geofrac.fracture.softening import saw_tooth

#: Relative tolerance of the teeth's energy against G_f: the roots are found to 1e-15.
ENERGY_RTOL = 1e-12


def envelope(w: np.ndarray, w0: np.ndarray, ft: float, gf: float) -> np.ndarray:
    """The linear softening law after the elastic branch to (w₀, f_t); area ½ f_t w_c = G_f."""
    wc = 2.0 * gf / ft
    return ft * (1.0 - (w - w0) / (wc - w0))


@pytest.mark.parametrize("n", [2, 5, 10, 40])
@pytest.mark.parametrize("k0", [20.0, 1000.0, 1e5])
def test_saw_tooth_dissipates_gf_and_straddles_the_envelope(n, k0):
    ft, gf = 2.0, 0.5
    st = saw_tooth(np.array([k0]), ft=ft, gf=gf, n=n)
    k, w, f = st.k[0], st.w[0], st.f[0]
    k_next = np.r_[k[1:], 0.0]
    # closed form of the dissipated energy, written out here (not SawTooth.energy)
    energy = sum(0.5 * w[i] ** 2 * (k[i] - k_next[i]) for i in range(n))
    assert energy == pytest.approx(gf, rel=ENERGY_RTOL)
    assert st.energy.sum() == pytest.approx(gf, rel=ENERGY_RTOL)
    # the first tooth: the intact strength at the elastic opening f_t / k0
    assert f[0] == pytest.approx(ft, rel=1e-14)
    assert w[0] == pytest.approx(ft / k0, rel=1e-14)
    # monotone: stiffness falls, opening grows, strength never rises, last valley 0
    assert np.all(np.diff(k) < 0.0) and np.all(np.diff(w) > 0.0)
    assert np.all(np.diff(f) <= 1e-12 * ft) and np.all(f <= ft * (1 + 1e-14))
    # straddle: peaks on or above the envelope, valleys on or below, within p f_t
    sigma = envelope(w, w[0], ft, gf)
    valleys = k_next * w
    band = st.p[0] * ft * (1 + 1e-9)
    assert np.all(f >= sigma - 1e-12 * ft) and np.all(f - sigma <= band)
    assert np.all(valleys <= sigma + 1e-12 * ft) and np.all(sigma - valleys <= band)


def test_more_teeth_narrow_the_band():
    bands = [saw_tooth(np.array([1000.0]), ft=1.0, gf=1.0, n=n).p[0] for n in (5, 10, 20, 40)]
    assert np.all(np.diff(bands) < 0.0)


def test_saw_tooth_per_pair_and_refusals():
    st = saw_tooth(np.array([50.0, 500.0]), ft=1.0, gf=1.0, n=10)
    assert st.k.shape == (2, 10)
    assert np.allclose(st.energy.sum(axis=1), 1.0, rtol=ENERGY_RTOL, atol=0.0)
    with pytest.raises(ValueError, match="at least 2 teeth"):
        saw_tooth(np.array([50.0]), ft=1.0, gf=1.0, n=1)
    # ½ f_t² / k0 = 1 ≥ G_f: the elastic branch alone stores G_f
    with pytest.raises(ValueError, match="elastic energy"):
        saw_tooth(np.array([0.5]), ft=1.0, gf=1.0, n=10)
