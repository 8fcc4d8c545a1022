"""Lagrange reference elements: CST/P1, P2 and P3, defined directly through UFL/basix."""

from __future__ import annotations

import dolfinx_solver  # noqa: F401  (orders MPI before the DOLFINx bindings)

import dolfinx

from geofrac.elements.base import Element

__all__ = ["cst", "p1", "p2", "p3"]


def _lagrange(name: str, degree: int, mesh: dolfinx.mesh.Mesh) -> Element:
    gdim = mesh.geometry.dim
    space = dolfinx.fem.functionspace(mesh, ("Lagrange", degree, (gdim,)))
    return Element(name=name, space=space, degree=degree)


def cst(mesh: dolfinx.mesh.Mesh) -> Element:
    """Linear Lagrange: the constant strain triangle ('FEM(CST)' in Edo (2016)) or linear tet."""
    return _lagrange("cst", 1, mesh)


def p1(mesh: dolfinx.mesh.Mesh) -> Element:
    """Linear Lagrange, named as usual in 3D (linear tetrahedron); the same as :func:`cst`."""
    return _lagrange("p1", 1, mesh)


def p2(mesh: dolfinx.mesh.Mesh) -> Element:
    """Quadratic Lagrange (6-node triangle / 10-node tetrahedron)."""
    return _lagrange("p2", 2, mesh)


def p3(mesh: dolfinx.mesh.Mesh) -> Element:
    """Cubic Lagrange; reproduces cubic fields such as the Timoshenko cantilever exactly."""
    return _lagrange("p3", 3, mesh)
