"""Element registry: scene name -> module that builds the discretisation.

The runner never names an element; it asks this registry. An element joins by adding
one entry here and one module that provides a factory
``name(mesh) -> geofrac.elements.base.Element``.
"""

from __future__ import annotations

import importlib

__all__ = [
    "GRADIENT_DOF_DEFAULTS",
    "GRADIENT_DOF_ELEMENTS",
    "REGISTRY",
    "available",
    "describe",
    "make_element",
]

#: name -> (module, factory, dimensions it supports, one-line description)
REGISTRY: dict[str, tuple[str, str, tuple[int, ...], str]] = {
    "cst": (
        "geofrac.elements.lagrange",
        "cst",
        (2, 3),
        "linear Lagrange (CST in 2D, linear tet in 3D)",
    ),
    "p1": (
        "geofrac.elements.lagrange",
        "p1",
        (2, 3),
        "linear Lagrange under its 3D name (the same element as cst)",
    ),
    "p2": (
        "geofrac.elements.lagrange",
        "p2",
        (2, 3),
        "quadratic Lagrange (6-node triangle, 10-node tet)",
    ),
    "p3": (
        "geofrac.elements.lagrange",
        "p3",
        (2, 3),
        "cubic Lagrange (10-node triangle), a high-order reference",
    ),
    "rgnt": (
        "geofrac.elements.gradient",
        "rgnt",
        (2,),
        "triangle with a drilling DOF per vertex (u, v, θ), seed eq. 2.1",
    ),
    "gnt": (
        "geofrac.elements.gradient",
        "gnt",
        (2,),
        "triangle with drilling and strain DOFs (u, v, θ, εx, εy, γxy), seed eq. 2.29",
    ),
    "efmm": (
        "geofrac.elements.efmm",
        "efmm",
        (2,),
        "Enriched Free Mesh Method: CST displacement, a linear stress per node patch, seed eq. 3.6",
    ),
    "rgnq": (
        "geofrac.elements.gradient",
        "rgnq",
        (3,),
        "tetrahedron with three rotations per vertex (u, v, w, θx, θy, θz), seed eq. 2.5",
    ),
}

#: Elements whose unknowns are vertex DOFs with extra gradient DOFs (RGNT, GNT, RGNQ).
GRADIENT_DOF_ELEMENTS = ("rgnt", "gnt", "rgnq")

#: Default α of ``discretization.zero_mode_penalty`` per element, chosen from the
#: measurements in docs/elements.md. GNT reproduces every quadratic field and its penalty
#: is consistent there, so a small α (1e-3) is best; RGNT and RGNQ reproduce few
#: quadratics and their penalty pulls the rotations off the Galerkin solution, so α is kept
#: near the limit α → 0, where it only pins the spurious zero-energy modes.
GRADIENT_DOF_DEFAULTS: dict[str, float] = {"rgnt": 1e-6, "gnt": 1e-3, "rgnq": 1e-6}


def available() -> tuple[str, ...]:
    """Names of the registered elements, sorted."""
    return tuple(sorted(REGISTRY))


def describe(name: str) -> tuple[tuple[int, ...], str]:
    """Return (supported dimensions, description) of element ``name``."""
    _, _, dims, text = REGISTRY[name]
    return dims, text


def make_element(name: str, mesh: object) -> object:
    """Build element ``name`` on a DOLFINx ``mesh`` (imports the element module)."""
    module, factory, _, _ = REGISTRY[name]
    return getattr(importlib.import_module(module), factory)(mesh)
