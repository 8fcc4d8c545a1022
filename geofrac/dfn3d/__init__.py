"""Three-dimensional discrete fracture networks: pure numpy; no MPI, no gmsh.

A network is a set of planar fractures (discs or regular polygons) in a 3D rock mass:
fracture sets with a Fisher-distributed pole (mean trend and plunge, concentration κ),
truncated power-law radii and uniform random centres, the intensity given as P32 (fracture
area per unit volume) or a count; or a network read from a file. Coordinates: x east,
y north, z up; a pole's trend is clockwise from north (+y), its plunge positive downwards.
"""

__all__: list[str] = []
