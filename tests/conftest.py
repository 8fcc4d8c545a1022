"""Shared fixtures.

MPI tests are marked ``@pytest.mark.mpi`` and also run as
``mpiexec -n 2 python -m mpi4py -m pytest --only-mpi`` (see the Makefile).
"""

import json
import subprocess
import sys
from pathlib import Path

import dolfinx_solver  # noqa: F401  (orders MPI before the DOLFINx bindings)

import pytest

REPO = Path(__file__).resolve().parents[1]
JOBS = REPO / "jobs"
BROKEN = Path(__file__).resolve().parent / "scenes" / "broken"


def subprocess_env() -> dict[str, str]:
    """This environment without the MPI launcher's variables, for a child process.

    A child started from a test running under ``mpiexec`` would otherwise try to join
    the parent's job and fail in ``PMI_Init``.
    """
    import os

    launcher = ("PMI_", "PMIX_", "HYDRA_", "MPIR_", "MPI_LOCALNRANKS", "MPI_LOCALRANKID")
    return {k: v for k, v in os.environ.items() if not k.startswith(launcher)}


@pytest.fixture
def cli(capsys):
    """Run ``geofrac`` in-process; return (exit code, stdout, stderr)."""
    from geofrac.cli import main

    def call(*argv: str) -> tuple[int, str, str]:
        code = main([str(a) for a in argv])
        out = capsys.readouterr()
        return code, out.out, out.err

    return call


PROBE = """
import json, sys
from geofrac.cli import main
sets = [arg for override in sys.argv[3:] for arg in ("--set", override)]
code = main(["run", sys.argv[1], "--out", sys.argv[2], "-q", *sets])
print(json.dumps({"code": code, "modules": sorted(sys.modules)}))
"""


def run_and_list_modules(tmp_path: Path, scene: Path, *overrides: str) -> set[str]:
    """Run ``scene`` in a fresh interpreter; return the names of the modules it imported."""
    proc = subprocess.run(
        [sys.executable, "-c", PROBE, str(scene), str(tmp_path / "out"), *overrides],
        capture_output=True,
        text=True,
        cwd=REPO,
        check=True,
    )
    result = json.loads(proc.stdout.strip().splitlines()[-1])
    assert result["code"] == 0, proc.stderr
    return set(result["modules"])
