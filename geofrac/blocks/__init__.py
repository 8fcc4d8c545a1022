"""Polygonal and polyhedral block models (Edo (2016), chapter 5): one block per mesh vertex.

- :mod:`~geofrac.blocks.model`: the :class:`~geofrac.blocks.model.Blocks` container,
  joining and welding block sets;
- :mod:`~geofrac.blocks.table`: block points named by the mesh entities they stand on;
- :mod:`~geofrac.blocks.dual2d`: polygons from triangles (§5.2.2(a), Fig. 5.6-5.8);
- :mod:`~geofrac.blocks.dual3d`: polyhedra from tetrahedra (§5.2.2(b), Fig. 5.9);
- :mod:`~geofrac.blocks.immobile`: the immobile part as one block (§5.3.2);
- :mod:`~geofrac.blocks.quality`: the checks (volumes, closure, Euler characteristic,
  planarity, face pairing, overlap sampling, pyvista's cell validator);
- :mod:`~geofrac.blocks.kernels`: the compiled (numba) sweep and prune of the exact
  self-intersection test, imported only by that test;
- :mod:`~geofrac.blocks.distributed`: the blocks of a distributed DOLFINx mesh;
- :mod:`~geofrac.blocks.output`: the VTU, block file and histogram writers;
- :mod:`~geofrac.blocks.driver`: a ``method = "blocks"`` run (mesh, blocks, checks,
  output).

``distributed`` and ``driver`` import DOLFINx and MPI; everything else is numpy (and
pyvista for the validator). The terrain's gmsh builder is
:mod:`geofrac.meshing.terrain`.
"""

__all__: list[str] = []
