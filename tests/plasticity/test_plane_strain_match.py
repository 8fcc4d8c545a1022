"""Drucker-Prager with the plane-strain match and Mohr-Coulomb: the same plane-strain limit.

Plane strain (ε_zz = 0), the lateral stress held at σ_yy = −p, ε_xx compressed: with
associated flow the limit is Mohr-Coulomb's in the xy plane,
σ_xx = −(p (1 + sin φ) + 2c cos φ)/(1 − sin φ) (σ_zz intermediate), for both laws (the
match of eq. 4.42-4.43 is built so: Drucker and Prager (1952)). Mohr-Coulomb reaches it
at first yield; the cone approaches it as the plastic ε_zz rate dies out.
"""

import numpy as np
import pytest

from geofrac.plasticity import DruckerPrager, MohrCoulomb
from geofrac.plasticity.returns import ELASTIC
from tests.plasticity.drivers import mixed_newton

E, NU, C, PHI, P = 1000.0, 0.3, 1.0, 30.0, 2.0


def _compress(law, steps: int, de: float) -> list[tuple[np.ndarray, int]]:
    """Load steps of Δε_xx = −de with σ_yy = −p, ε_zz = 0: the stress and kind of each."""
    stress, eps, out = np.zeros((3, 3)), np.zeros((3, 3)), []
    for k in range(1, steps + 1):
        target = eps.copy()
        target[0, 0] = -k * de
        stress, eps, history, kind = mixed_newton(
            law, target, free=[(1, 1)], target=np.array([-P]), stress0=stress, eps0=eps
        )
        assert history[-1] <= 1e-12
        out.append((stress, kind))
    return out


@pytest.mark.parametrize(
    "law",
    [MohrCoulomb(E, NU, PHI, C, PHI), DruckerPrager(E, NU, PHI, C, PHI)],
    ids=["mohr_coulomb", "drucker_prager_plane_strain"],
)
def test_both_laws_reach_the_plane_strain_limit(law):
    s, co = np.sin(np.radians(PHI)), np.cos(np.radians(PHI))
    limit = -(P * (1 + s) + 2 * C * co) / (1 - s)
    path = _compress(law, steps=160, de=0.5 * C / E)  # 80 times c/E
    final, kind = path[-1]
    assert kind != ELASTIC
    np.testing.assert_allclose(final[0, 0], limit, rtol=1e-9)
    assert final[0, 0] < final[2, 2] < final[1, 1]  # σ_zz intermediate
    # never beyond the limit on the way
    assert min(st[0, 0] for st, _ in path) >= limit * (1 + 1e-12)
