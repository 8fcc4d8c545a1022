"""What an element provides to the elastic problem."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

__all__ = ["Element"]


@dataclass
class Element:
    """A displacement discretisation on a mesh.

    Attributes:
        name: registry name.
        space: the DOLFINx function space the displacement field lives in.
        degree: polynomial degree of the displacement field.
    """

    name: str
    space: Any
    degree: int

    @property
    def unknowns(self) -> Any:
        """The space of the unknowns (the displacement space for Lagrange elements)."""
        return self.space

    @property
    def num_dofs(self) -> int:
        """Global number of degrees of freedom (unknowns)."""
        dofmap = self.unknowns.dofmap
        return int(dofmap.index_map.size_global * dofmap.index_map_bs)

    def destroy(self) -> None:
        """Free PETSc objects the element owns (none for Lagrange elements)."""
