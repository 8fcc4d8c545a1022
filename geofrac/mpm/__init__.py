"""Material Point Method (Edo (2016), chapter 4, App. D): the engine.

- :mod:`~geofrac.mpm.grid`: the regular background (Euler) grid;
- :mod:`~geofrac.mpm.shapes`: particle–node weights φ_ip and gradients, one
  :class:`~geofrac.mpm.shapes.Shape` per kind in its registry: linear hat (``mpm``, eqs.
  4.28-4.29), GIMP (``ugimp``, ``cpgimp``, eqs. 4.30-4.31, 4.69-4.71) and the quadratic
  B-spline (``bspline2``), tensor products in 2D and 3D (4.32);
- :mod:`~geofrac.mpm.particles`: particle state;
- :mod:`~geofrac.mpm.schemes`: one explicit step of MUSL (D.1-D.9), USF (D.10-D.17) or
  USAVG (D.18-D.29), with the transfers particle → grid → particle (numpy reference or
  compiled);
- :mod:`~geofrac.mpm.kernels`: the compiled (numba) loops of a step, imported only by
  a step that uses them;
- :mod:`~geofrac.mpm.parallel`: slab decomposition over MPI ranks (mpi4py only, imported
  when called).

Nothing here imports DOLFINx; importing the package imports neither numba nor MPI.
"""

__all__: list[str] = []
