"""Element registry: scene name -> :class:`~geofrac.elements.spec.ElementSpec`.

The only source of element facts: the scene loader, the effects, the elastic problem and
the crack driver ask :func:`get` and never name an element. An element joins by adding
one entry here and one module that provides a factory
``name(mesh) -> geofrac.elements.base.Element`` (docs/elements.md, "Adding an element").
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from geofrac.elements.spec import ElementSpec

if TYPE_CHECKING:
    import dolfinx.mesh

    from geofrac.elements.base import Element

__all__ = ["REGISTRY", "ElementSpec", "available", "get", "make_element"]

_LAGRANGE = "geofrac.fem.elastic:ElasticProblem"
_GRADIENT = "geofrac.fem.elastic:GradientDofProblem"
_GRADIENT_OPTIONS = frozenset({"quadrature_degree", "zero_mode_penalty", "gradient_bc"})

#: name -> element. The default zero-mode penalties α come from the measurements in
#: docs/elements.md: GNT reproduces every quadratic field and its penalty is consistent
#: there, so a small α (1e-3) is best; RGNT and RGNQ reproduce few quadratics and their
#: penalty pulls the rotations off the Galerkin solution, so α is kept near the limit
#: α → 0, where it only pins the spurious zero-energy modes. ``locking_nu`` is measured
#: (docs/stability.md, "Locking", ``docs/locking.py``): the smallest ν at which the
#: plane-strain cantilever's displacement error or Cook's membrane's tip error exceeds
#: 10 times its ν = 0.3 value and 5 %; None where neither does down to ν = 0.49999.
REGISTRY: dict[str, ElementSpec] = {
    spec.name: spec
    for spec in (
        ElementSpec(
            "cst",
            "linear Lagrange (CST in 2D, linear tet in 3D)",
            (2, 3),
            {2: 2, 3: 3},
            "geofrac.elements.lagrange:cst",
            _LAGRANGE,
            cracking="edges",
            locking_nu=0.499,
        ),
        ElementSpec(
            "p1",
            "linear Lagrange under its 3D name (the same element as cst)",
            (2, 3),
            {2: 2, 3: 3},
            "geofrac.elements.lagrange:p1",
            _LAGRANGE,
            cracking="edges",
            locking_nu=0.499,
        ),
        ElementSpec(
            "p2",
            "quadratic Lagrange (6-node triangle, 10-node tet)",
            (2, 3),
            {2: 2, 3: 3},
            "geofrac.elements.lagrange:p2",
            _LAGRANGE,
            degree=2,
            curved=True,
        ),
        ElementSpec(
            "p3",
            "cubic Lagrange (10-node triangle), a high-order reference",
            (2, 3),
            {2: 2, 3: 3},
            "geofrac.elements.lagrange:p3",
            _LAGRANGE,
            degree=3,
            curved=True,
        ),
        ElementSpec(
            "rgnt",
            "triangle with a drilling DOF per vertex (u, v, θ), Edo (2016) eq. 2.1",
            (2,),
            {2: 3},
            "geofrac.elements.gradient:rgnt",
            _GRADIENT,
            _GRADIENT_OPTIONS,
            zero_mode_penalty=1e-6,
            kinematics="rgnt",
            cracking="edges",
            locking_nu=0.49,
            hold="gradient",
        ),
        ElementSpec(
            "gnt",
            "triangle with drilling and strain DOFs (u, v, θ, εx, εy, γxy), Edo (2016) eq. 2.29",
            (2,),
            {2: 6},
            "geofrac.elements.gradient:gnt",
            _GRADIENT,
            _GRADIENT_OPTIONS,
            zero_mode_penalty=1e-3,
            kinematics="gnt",
            cracking="edges",
            locking_nu=0.49999,
            hold="gradient",
        ),
        ElementSpec(
            "efmm",
            "Enriched Free Mesh Method: CST displacement, a linear stress per node patch, "
            "Edo (2016) eq. 3.6",
            (2,),
            {2: 2},
            "geofrac.elements.efmm:efmm",
            "geofrac.fem.efmm:EfmmProblem",
            frozenset({"q_rand", "domain_seed"}),
            cracking="grains",
            locking_nu=0.495,
            hold="nodes",
        ),
        ElementSpec(
            "rgnq",
            "tetrahedron with three rotations per vertex (u, v, w, θx, θy, θz), Edo (2016) eq. 2.5",
            (3,),
            {3: 6},
            "geofrac.elements.gradient:rgnq",
            _GRADIENT,
            _GRADIENT_OPTIONS,
            zero_mode_penalty=1e-6,
            kinematics="rgnq",
            locking_nu=0.49,  # not measured (no 3D closed form shows locking): RGNT's value
            hold="gradient",
        ),
    )
}


def available() -> tuple[str, ...]:
    """Names of the registered elements, sorted."""
    return tuple(sorted(REGISTRY))


def get(name: str) -> ElementSpec:
    """The element called ``name``.

    Raises:
        KeyError: naming the registered elements, when there is none of that name.
    """
    try:
        return REGISTRY[name]
    except KeyError:
        raise KeyError(f"no element {name!r}; registered: {', '.join(available())}") from None


def make_element(name: str, mesh: dolfinx.mesh.Mesh) -> Element:
    """Build element ``name`` on a DOLFINx ``mesh`` (imports the element module)."""
    return get(name).build(mesh)
