"""Plasticity laws shared by MPM and the finite-element solver (pure numpy).

One constitutive module for every engine: each law takes elastic trial stresses of shape
(n, 3, 3) (plane strain keeps σ_zz) and returns a :class:`~geofrac.plasticity.returns.Return`
(stress, multipliers, plastic strain increment, the return taken, the consistent tangent).
MPM's ``plasticity`` model (:mod:`geofrac.mpm.plasticity`) calls the Drucker-Prager return;
the finite-element Newton solver is to call ``return_map(trial, tangent=True)`` at its
quadrature points. See docs/plasticity.md.

- :mod:`~geofrac.plasticity.drucker_prager`: Drucker-Prager (Edo (2016), eq. 4.39-4.43);
- :mod:`~geofrac.plasticity.mohr_coulomb`: Mohr-Coulomb with a tension cut-off;
- :mod:`~geofrac.plasticity.invariants`, :mod:`~geofrac.plasticity.elasticity`,
  :mod:`~geofrac.plasticity.returns`: the shared pieces.
"""

from __future__ import annotations

from geofrac.plasticity.drucker_prager import DruckerPrager
from geofrac.plasticity.mohr_coulomb import MohrCoulomb
from geofrac.plasticity.returns import Return

__all__ = ["LAWS", "DruckerPrager", "MohrCoulomb", "Return"]

#: The laws by name (the key a scene would use).
LAWS: dict[str, type[DruckerPrager] | type[MohrCoulomb]] = {
    "drucker_prager": DruckerPrager,
    "mohr_coulomb": MohrCoulomb,
}
