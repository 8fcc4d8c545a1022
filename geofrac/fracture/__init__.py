"""Crack propagation on element edges: sites, visibility, cell matrices, event driver.

Pure numpy modules: :mod:`~geofrac.fracture.topology`, :mod:`~geofrac.fracture.visibility`,
:mod:`~geofrac.fracture.cells`, :mod:`~geofrac.fracture.state`,
:mod:`~geofrac.fracture.criterion`, :mod:`~geofrac.fracture.woodbury`. The distributed
plumbing (PETSc assembly, solve, output) is :mod:`~geofrac.fracture.driver` and
:mod:`~geofrac.fracture.incremental`.
"""

__all__ = ["SOLVERS"]

#: Solvers of the event loop (``cracking.solver``), the default first.
SOLVERS = ("update", "reuse", "refactor")
