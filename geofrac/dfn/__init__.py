"""Discrete fracture networks: pure numpy generation, I/O, statistics, cleaning; no MPI, no gmsh.

A network is a set of straight fracture traces in a 2D rock mass (Edo (2016), §2.4, Table 2.1):
fracture sets with a mean orientation and a spread, power-law lengths (eq. 2.28) and
uniform random centres. Angles are trace directions counter-clockwise from +x in degrees;
fractures are axial, so angles are reported folded to [0, 180).
"""

__all__: list[str] = []
