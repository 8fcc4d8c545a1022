"""Distributed finite element plumbing on DOLFINx/PETSc (thin by design).

Every module in this package imports ``dolfinx_solver`` before DOLFINx; PETSc objects come
from :mod:`geofrac.solvers`.
"""

import dolfinx_solver  # noqa: F401  (orders MPI before the DOLFINx bindings)

__all__: list[str] = []
