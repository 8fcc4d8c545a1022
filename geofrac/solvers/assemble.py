"""Assembly of compiled DOLFINx forms into PETSc matrices and vectors.

Thin wrappers over :mod:`dolfinx.fem.petsc`: the matrix is assembled (``MatAssembly``
done), the vector has its ghost contributions summed into the owners. The caller
destroys what is returned.
"""

from __future__ import annotations

import dolfinx_solver  # noqa: F401  (orders MPI before the DOLFINx bindings)

import dolfinx
import dolfinx.fem.petsc
from petsc4py import PETSc

from geofrac.solvers.vectors import accumulate_ghosts

__all__ = ["assemble_matrix", "assemble_vector", "set_bc"]


def assemble_matrix(
    a: dolfinx.fem.Form, bcs: list[dolfinx.fem.DirichletBC] | None = None
) -> PETSc.Mat:
    """The assembled matrix of the bilinear form ``a``.

    Rows and columns of the Dirichlet DOFs of ``bcs`` are zeroed with 1 on the diagonal
    (DOLFINx's assembly with conditions).
    """
    A = dolfinx.fem.petsc.assemble_matrix(a, bcs=bcs)
    A.assemble()
    return A


def assemble_vector(
    L: dolfinx.fem.Form,
    lifting: tuple[dolfinx.fem.Form, list[dolfinx.fem.DirichletBC]] | None = None,
) -> PETSc.Vec:
    """The load vector of the linear form ``L``, ghost contributions summed into owners.

    Args:
        L: the compiled linear form.
        lifting: (bilinear form a, its Dirichlet conditions): b -= A g of the prescribed
            values g is applied before the ghosts are summed (:func:`set_bc` then sets
            the Dirichlet entries).
    """
    b = dolfinx.fem.petsc.assemble_vector(L)
    if lifting is not None:
        a, bcs = lifting
        dolfinx.fem.petsc.apply_lifting(b, [a], bcs=[bcs])
    accumulate_ghosts(b)
    return b


def set_bc(b: PETSc.Vec, bcs: list[dolfinx.fem.DirichletBC]) -> None:
    """Set the owned Dirichlet entries of ``b`` to the conditions' values."""
    dolfinx.fem.petsc.set_bc(b, bcs)
