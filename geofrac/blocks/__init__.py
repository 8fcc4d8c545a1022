"""Polygonal and polyhedral block models (seed chapter 5): one block per mesh vertex.

- :mod:`~geofrac.blocks.model`: the :class:`~geofrac.blocks.model.Blocks` container;
- :mod:`~geofrac.blocks.table`: block points named by the mesh entities they stand on;
- :mod:`~geofrac.blocks.dual2d`: polygons from triangles (seed 5.2.2(a), Fig. 5.6-5.8);
- :mod:`~geofrac.blocks.dual3d`: polyhedra from tetrahedra (seed 5.2.2(b), Fig. 5.9);
- :mod:`~geofrac.blocks.distributed`: the same on a distributed DOLFINx mesh (the only
  module here that imports DOLFINx and MPI).

Everything but ``distributed`` is pure numpy.
"""

__all__: list[str] = []
