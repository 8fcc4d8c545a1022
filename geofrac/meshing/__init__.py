"""Meshing: gmsh geometry files in, distributed DOLFINx meshes with named tags out."""

__all__: list[str] = []
