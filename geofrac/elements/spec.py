"""What every part of geofrac may ask of an element, in one object per element name.

Pure data (no DOLFINx): the scene loader, the effects and the crack driver read an
:class:`ElementSpec`; only :meth:`ElementSpec.build` and :meth:`ElementSpec.problem_class`
import the DOLFINx plumbing, lazily.
"""

from __future__ import annotations

import importlib
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Literal

if TYPE_CHECKING:
    import dolfinx.mesh

    from geofrac.elements.base import Element


__all__ = ["ElementSpec"]


@dataclass(frozen=True)
class ElementSpec:
    """One element: its data and where its code lives.

    Attributes:
        name: the scene name (``discretization.element``).
        description: one line for docs and errors.
        dims: the geometric dimensions it supports.
        vertex_dofs: unknowns per mesh vertex, by dimension (``{2: 3}`` for RGNT).
        factory: ``"module:function"`` building the DOLFINx element,
            ``function(mesh) -> geofrac.elements.base.Element``.
        problem: ``"module:Class"`` of the elastic problem that assembles and solves it.
        options: ``[discretization]`` keys it accepts besides ``element``.
        zero_mode_penalty: default α of ``discretization.zero_mode_penalty`` (None: the
            element has no zero-energy modes to pin and refuses the key).
        kinematics: key of :data:`geofrac.elements.kinematics.KINDS` for the vertex-DOF
            elements whose displacement is P2 fixed by vertex DOFs (None otherwise).
        cracking: how the effect ``cracking`` cracks it: ``"edges"`` (MLS-cracked cells on
            element edges, Edo (2016) ch. 2), ``"grains"`` (EFMM grain interfaces, ch. 3)
            or None (not supported).
        locking_nu: Poisson's ratio above which it locks volumetrically in plane strain and
            3D (a warning at load time), or None when it does not lock.
        hold: how a Dirichlet boundary holds it: ``"components"`` (displacement DOFs),
            ``"gradient"`` (displacement DOFs, and the gradient DOFs per
            ``discretization.gradient_bc``), ``"nodes"`` (node displacements of the patch
            method).
        degree: polynomial degree of a Lagrange displacement that carries DOFs on edges
            and faces too (about degree^dim nodes per vertex); 1 for elements whose
            unknowns all sit at the vertices.
        curved: represents cells of a second-order (curved) gmsh geometry: an
            isoparametric or higher Lagrange displacement. Others are refused on curved
            geometry at load time (they would fail the patch test there).
    """

    name: str
    description: str
    dims: tuple[int, ...]
    vertex_dofs: dict[int, int]
    factory: str
    problem: str
    options: frozenset[str] = frozenset({"quadrature_degree"})
    zero_mode_penalty: float | None = None
    kinematics: str | None = None
    cracking: Literal["edges", "grains"] | None = None
    locking_nu: float | None = None
    hold: Literal["components", "gradient", "nodes"] = "components"
    degree: int = 1
    curved: bool = False

    def build(self, mesh: dolfinx.mesh.Mesh) -> Element:
        """The DOLFINx element on ``mesh`` (imports its module)."""
        return _resolve(self.factory)(mesh)

    def problem_class(self) -> type:
        """The elastic problem class (imports its module)."""
        return _resolve(self.problem)


def _resolve(path: str) -> Any:
    module, name = path.split(":")
    return getattr(importlib.import_module(module), name)
