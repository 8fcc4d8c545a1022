"""Crack propagation on element edges: sites, visibility, cell matrices, event driver.

Pure numpy modules: :mod:`~geofrac.fracture.topology`, :mod:`~geofrac.fracture.visibility`,
:mod:`~geofrac.fracture.cells`, :mod:`~geofrac.fracture.state`,
:mod:`~geofrac.fracture.criterion`. The distributed plumbing (PETSc assembly, solve,
output) is :mod:`~geofrac.fracture.driver`.
"""
