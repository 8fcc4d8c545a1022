"""geofrac: MPI-parallel fracture and failure of rock and soil on FEniCSx/PETSc.

Importing :mod:`geofrac` is cheap: it loads neither MPI, DOLFINx nor PETSc. The
distributed plumbing lives in :mod:`geofrac.fem`, :mod:`geofrac.meshing` and
:mod:`geofrac.io`, which import ``dolfinx_solver`` before any binding.
"""

from importlib.metadata import PackageNotFoundError, version

try:
    __version__ = version("geofrac")
except PackageNotFoundError:  # running from a source tree that was not installed
    __version__ = "0.0.0+unknown"

__all__ = ["__version__"]
