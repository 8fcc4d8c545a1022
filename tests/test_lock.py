"""The lock (scripts/constraints.txt) pins every dependency, and the venv holds exactly it.

scripts/bootstrap.sh installs geofrac with the lock as pip constraints, so that the
README's commands install what CI tested; ``make test-latest`` tries the newest releases
and ``make lock`` writes them into the lock.
"""

from __future__ import annotations

import sys
import sysconfig
import tomllib
from importlib import metadata
from pathlib import Path

import pytest
from packaging.requirements import Requirement
from packaging.utils import canonicalize_name

REPO = Path(__file__).resolve().parents[1]
LOCK = REPO / "scripts" / "constraints.txt"
#: What scripts/bootstrap.sh wrote into the venv's stamp: "locked" or "latest".
STAMP = Path(sys.prefix) / ".geofrac-installed"


def locked() -> dict[str, str]:
    """The lock's pins: canonical name -> version."""
    pins = {}
    for text in LOCK.read_text().splitlines():
        line = text.split("#", 1)[0].strip()
        if not line:
            continue
        name, sep, version = line.partition("==")
        assert sep and version, f"{LOCK.name}: '{line}' is not name==version"
        pins[canonicalize_name(name)] = version
    return pins


def declared() -> list[Requirement]:
    """pyproject.toml's dependencies, the test extra's and the build backend's."""
    project = tomllib.loads((REPO / "pyproject.toml").read_text())
    texts = [
        *project["project"]["dependencies"],
        *project["project"]["optional-dependencies"]["test"],
        *project["build-system"]["requires"],
    ]
    return [Requirement(t) for t in texts]


def test_every_dependency_is_pinned_within_its_range():
    pins = locked()
    for req in declared():
        name = canonicalize_name(req.name)
        assert name in pins, f"{req.name} is not in {LOCK.name}: run make test-latest, make lock"
        assert req.specifier.contains(pins[name], prereleases=True), (
            f"{LOCK.name} pins {req.name}=={pins[name]} outside pyproject.toml's {req}"
        )


def test_pip_itself_is_pinned():
    assert "pip" in locked()


@pytest.mark.skipif(
    not STAMP.is_file() or STAMP.read_text().strip() != "locked",
    reason="the venv was not installed from the lock (GEOFRAC_LATEST, or not by bootstrap.sh)",
)
def test_the_venv_holds_exactly_the_locked_versions():
    """The venv's packages are the lock's: each at its version, and nothing else."""
    # the venv's site-packages only: not the packages setuptools vendors and puts on
    # sys.path once it is imported (cffi's compiler does), which pip does not install
    where = sorted({sysconfig.get_paths()["purelib"], sysconfig.get_paths()["platlib"]})
    installed = {
        canonicalize_name(d.metadata["Name"]): d.version
        for d in metadata.distributions(path=where)
        if canonicalize_name(d.metadata["Name"]) != "geofrac"
    }
    pins = locked()
    wrong = {n: (v, pins.get(n)) for n, v in installed.items() if pins.get(n) != v}
    missing = sorted(set(pins) - set(installed))
    assert not wrong and not missing, (
        f"installed (version, locked): {wrong}; locked but not installed: {missing}"
    )
