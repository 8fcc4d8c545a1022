"""The PETSc types and dtypes the rest of geofrac names without importing petsc4py.

Annotate with :data:`Matrix`, :data:`Vector` and :data:`NullSpace`; build scalar arrays
and DOLFINx constants with :data:`SCALAR` and global index arrays with :data:`INDEX`.
"""

from __future__ import annotations

import dolfinx_solver  # noqa: F401  (orders MPI before the DOLFINx bindings; holds libpetsc)

import numpy as np
from petsc4py import PETSc

__all__ = ["INDEX", "SCALAR", "Matrix", "NullSpace", "Vector", "petsc_version"]

#: A distributed PETSc matrix (``Mat``).
Matrix = PETSc.Mat

#: A distributed PETSc vector (``Vec``), possibly ghosted.
Vector = PETSc.Vec

#: A PETSc null space (rigid body modes for GAMG).
NullSpace = PETSc.NullSpace

#: The scalar dtype of PETSc's matrices and vectors (float64 here).
SCALAR: type[np.floating] = PETSc.ScalarType

#: The dtype of PETSc's global indices (``PetscInt``).
INDEX: type[np.integer] = PETSc.IntType


def petsc_version() -> str:
    """The PETSc library's version, e.g. ``"3.24.0"``."""
    return ".".join(map(str, PETSc.Sys.getVersion()))
