"""geofrac: MPI-parallel fracture and failure of rock and soil on FEniCSx/PETSc.

Importing :mod:`geofrac` is cheap: it loads neither MPI, DOLFINx nor PETSc. The
distributed plumbing lives in :mod:`geofrac.fem`, :mod:`geofrac.meshing` and
:mod:`geofrac.io`, which import ``dolfinx_solver`` before any binding.

Under a multi-rank ``mpiexec`` every rank already has a core, so importing geofrac
before numpy sets ``OPENBLAS_NUM_THREADS`` and ``OMP_NUM_THREADS`` to 1 unless the user
set them: threaded BLAS in each rank oversubscribes the cores (the crack driver's dense
updates ran 2-3 times slower with 2 ranks × 2 threads on 2 cores).

It also imports ``h5py`` before any DOLFINx or PETSc library loads: the PETSc wheel
brings an HDF5 of its own, and an h5py imported after it finds no deflate filter, so
the compressed output series could not be written (checked by tests/io/test_series.py).

numba's on-disk cache of the jitted kernels goes to the per-user cache
(:func:`geofrac.kernels.cache_root`, ``numba/``) unless ``NUMBA_CACHE_DIR`` is set: never
into the installed package, which may be read-only or shared.
"""

import os
from importlib.metadata import PackageNotFoundError, version


def _single_threaded_blas_under_mpi() -> None:
    """One BLAS/OpenMP thread per rank in multi-rank MPI jobs (MPICH, Open MPI, Slurm)."""
    size = 1
    for key in ("PMI_SIZE", "OMPI_COMM_WORLD_SIZE", "MPI_LOCALNRANKS"):
        value = os.environ.get(key, "")
        if value.isdigit():
            size = max(size, int(value))
    if size > 1:
        for key in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS"):
            os.environ.setdefault(key, "1")


_single_threaded_blas_under_mpi()


def _numba_cache_outside_the_package() -> None:
    """Point numba's cache at the per-user cache unless the user chose one."""
    import sys

    from geofrac.kernels import cache_root  # standard library only

    if os.environ.get("NUMBA_CACHE_DIR"):
        return
    where = str(cache_root() / "numba")
    os.environ["NUMBA_CACHE_DIR"] = where  # read when numba is imported
    numba = sys.modules.get("numba")
    if numba is not None:  # imported before geofrac: its config was read already
        numba.config.CACHE_DIR = where


_numba_cache_outside_the_package()

import h5py  # noqa: E402, F401  (before the PETSc wheel's HDF5: see the module docstring)

try:
    __version__ = version("geofrac")
except PackageNotFoundError:  # running from a source tree that was not installed
    __version__ = "0.0.0+unknown"

__all__ = ["__version__"]
