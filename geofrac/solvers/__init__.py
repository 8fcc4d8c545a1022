"""The linear algebra of geofrac: the one place that creates and configures PETSc objects.

Matrices, vectors, index sets, scatters, KSPs, MUMPS factorisations and null spaces are
made here; the rest of geofrac asks for "a factorisation of this matrix", "solve these
right-hand sides", "selected inverse entries", "assemble this form", and annotates with
:data:`Matrix` and :data:`Vector`, without importing petsc4py or
:mod:`dolfinx.fem.petsc` (``tests/test_layers.py`` checks this).

Modules:

- :mod:`~geofrac.solvers.types`: the PETSc types and dtypes (:data:`SCALAR`, :data:`INDEX`);
- :mod:`~geofrac.solvers.linear`: :class:`LinearSolver` and its presets, CG preconditioned
  by a factorisation;
- :mod:`~geofrac.solvers.mumps`: selected entries of the inverse, sparse right-hand sides;
- :mod:`~geofrac.solvers.matrices`: creation (COO, CSR, block diagonal), Dirichlet
  elimination, transposes, sub-matrices, null spaces;
- :mod:`~geofrac.solvers.vectors`: ghost updates, copies on every rank, setting entries;
- :mod:`~geofrac.solvers.assemble`: DOLFINx forms into matrices and vectors.
"""

from geofrac.solvers.assemble import assemble_matrix, assemble_vector, set_bc
from geofrac.solvers.linear import (
    AUTO_DIRECT_MAX_DOFS,
    MAX_RELATIVE_RESIDUAL,
    LinearSolver,
    PreconditionedCG,
    preset_options,
)
from geofrac.solvers.matrices import (
    add_matrix,
    block_diagonal,
    coo_matrix,
    csr_matrix,
    dense_submatrix,
    diagonal_norm1,
    orthonormal_nullspace,
    rigid_body_modes,
    transposed,
    zero_rows_columns,
)
from geofrac.solvers.mumps import mumps_inverse_entries, mumps_sparse_solve
from geofrac.solvers.types import INDEX, SCALAR, Matrix, NullSpace, Vector, petsc_version
from geofrac.solvers.vectors import (
    Gather,
    accumulate_ghosts,
    add_values,
    function_vector,
    ghosted_vector,
    update_ghosts,
)

__all__ = [
    "AUTO_DIRECT_MAX_DOFS",
    "INDEX",
    "MAX_RELATIVE_RESIDUAL",
    "SCALAR",
    "Gather",
    "LinearSolver",
    "Matrix",
    "NullSpace",
    "PreconditionedCG",
    "Vector",
    "accumulate_ghosts",
    "add_matrix",
    "add_values",
    "assemble_matrix",
    "assemble_vector",
    "block_diagonal",
    "coo_matrix",
    "csr_matrix",
    "dense_submatrix",
    "diagonal_norm1",
    "function_vector",
    "ghosted_vector",
    "mumps_inverse_entries",
    "mumps_sparse_solve",
    "orthonormal_nullspace",
    "petsc_version",
    "preset_options",
    "rigid_body_modes",
    "set_bc",
    "transposed",
    "update_ghosts",
    "zero_rows_columns",
]
