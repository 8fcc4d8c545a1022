"""Shared fixtures.

MPI tests are marked ``@pytest.mark.mpi`` and also run as
``mpiexec -n 2 python -m mpi4py -m pytest --only-mpi`` (see the Makefile).
"""

from pathlib import Path

import dolfinx_solver  # noqa: F401  (orders MPI before the DOLFINx bindings)

import pytest

REPO = Path(__file__).resolve().parents[1]
JOBS = REPO / "jobs"
BROKEN = Path(__file__).resolve().parent / "scenes" / "broken"


@pytest.fixture
def cli(capsys):
    """Run ``geofrac`` in-process; return (exit code, stdout, stderr)."""
    from geofrac.cli import main

    def call(*argv: str) -> tuple[int, str, str]:
        code = main([str(a) for a in argv])
        out = capsys.readouterr()
        return code, out.out, out.err

    return call
