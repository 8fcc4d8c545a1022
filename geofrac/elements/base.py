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
        space: the DOLFINx function space the displacement lives in.
        degree: polynomial degree of the displacement field.
    """

    name: str
    space: Any
    degree: int

    @property
    def num_dofs(self) -> int:
        """Global number of degrees of freedom."""
        imap = self.space.dofmap.index_map
        return int(imap.size_global * self.space.dofmap.index_map_bs)
