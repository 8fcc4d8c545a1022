"""Particle–node weights φ_ip and their gradients (Edo (2016), eqs. 4.24-4.32, 4.69-4.71).

The registry of shape kinds, scene name (``mpm.shape``) -> :class:`~geofrac.mpm.shapes.
base.Shape`: the only source of shape facts. The step (:mod:`~geofrac.mpm.schemes`), the
driver and the scene loader ask the :class:`Shape` and never compare names. A shape joins
by one module (a :class:`Shape` subclass with its 1D weights; copy
:mod:`~geofrac.mpm.shapes.bspline2`) and one line in :data:`REGISTRY`.

- ``mpm`` (:mod:`~geofrac.mpm.shapes.hat`): point particles, the linear hat (4.28-4.29);
- ``ugimp``, ``cpgimp`` (:mod:`~geofrac.mpm.shapes.gimp`): the hat averaged over the
  particle's box of half-width l_p (4.30-4.31), l_p fixed (4.71) or following the
  deformation gradient (4.69-4.70);
- ``bspline2`` (:mod:`~geofrac.mpm.shapes.bspline2`): the quadratic B-spline.

In 2D and 3D the weights are tensor products of the 1D ones (eq. 4.32).
"""

from __future__ import annotations

from geofrac.mpm.shapes.base import Shape, Weights, compiled_weights, weights
from geofrac.mpm.shapes.bspline2 import BSPLINE2, bspline2_1d
from geofrac.mpm.shapes.gimp import CPGIMP, UGIMP, gimp_1d, gimp_nodes
from geofrac.mpm.shapes.hat import HAT, hat_1d

__all__ = [
    "BSPLINE2",
    "CPGIMP",
    "HAT",
    "REGISTRY",
    "SHAPES",
    "UGIMP",
    "Shape",
    "Weights",
    "bspline2_1d",
    "compiled_weights",
    "get",
    "gimp_1d",
    "gimp_nodes",
    "hat_1d",
    "weights",
]

#: scene name -> shape, in the order of the docs (the scene's default first).
REGISTRY: dict[str, Shape] = {s.name: s for s in (HAT, UGIMP, CPGIMP, BSPLINE2)}

#: The registered names (the scene's ``mpm.shape`` choices).
SHAPES = tuple(REGISTRY)


def get(name: str) -> Shape:
    """The shape called ``name``.

    Raises:
        ValueError: naming the registered shapes, when there is none of that name.
    """
    try:
        return REGISTRY[name]
    except KeyError:
        raise ValueError(f"shape {name!r} is not one of {', '.join(SHAPES)}") from None
