"""MPM's Drucker-Prager is the shared return: the same stresses and multipliers, bit for bit."""

import numpy as np

from geofrac.mpm.plasticity import DruckerPrager as MPMDruckerPrager
from geofrac.plasticity import LAWS, DruckerPrager
from tests.plasticity.drivers import symmetric


def test_mpm_calls_the_shared_drucker_prager_return():
    mpm = MPMDruckerPrager(E=100.0, nu=0.25, friction_angle=25.0, cohesion=1.0, dilatancy_angle=5.0)
    shared = DruckerPrager(100.0, 0.25, 25.0, 1.0, 5.0)  # the plane-strain match
    start = -2.0 * np.eye(3) + symmetric(500, 1.0, seed=1)
    deps = symmetric(500, 0.05, seed=2)
    stress, dlam = mpm.update(start, deps)
    ret = shared.update(start, deps)
    np.testing.assert_array_equal(stress, ret.stress)
    np.testing.assert_array_equal(dlam, ret.multipliers[:, 0])
    assert (mpm.beta, mpm.k, mpm.beta_psi) == (shared.beta, shared.k, shared.beta_psi)
    assert {1, 4} <= set(np.unique(ret.kind).tolist())  # cone and apex both exercised


def test_the_registry_names_both_laws():
    assert set(LAWS) == {"drucker_prager", "mohr_coulomb"}
