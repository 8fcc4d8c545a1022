"""The README's five-minute tour, run as a new user would: it changes no tracked file.

The tour's commands are read from the README (the first ``sh`` block after "A five-minute
tour"), so the test follows the README as it is written. They run in a temporary copy of
the checkout made into a git repository (the tracked files as they are in the working
tree), with that copy's ``geofrac`` first on ``PYTHONPATH``, after what ``make quickstart``
runs; then ``git status`` of the copy must be clean: every run and the validation page
write under ``results/``, which is ignored.
"""

from __future__ import annotations

import os
import re
import shlex
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from tests.conftest import REPO, subprocess_env

README = (REPO / "README.md").read_text()
BIN = Path(sys.executable).parent


def tour_commands() -> list[list[str]]:
    """The tour's commands, split into words (``source`` lines and comments dropped)."""
    start = README.index("## A five-minute tour")
    block = re.search(r"```sh\n(.*?)```", README[start:], re.DOTALL)
    assert block is not None, "README: the tour has no sh block"
    commands = []
    for line in block.group(1).splitlines():
        words = shlex.split(line, comments=True)
        if words and words[0] != "source":
            commands.append(words)
    return commands


def _argv(words: list[str]) -> list[str]:
    """``geofrac ...`` and ``mpiexec -n N geofrac ...`` as this interpreter runs them."""
    python = [sys.executable, "-m", "geofrac"]
    if words[0] == "geofrac":
        return python + words[1:]
    assert words[0] == "mpiexec" and words[3] == "geofrac", words
    return [str(BIN / "mpiexec"), *words[1:3], *python, *words[4:]]


def _git(where: Path, *args: str) -> str:
    done = subprocess.run(
        ["git", *args], cwd=where, capture_output=True, text=True, check=True, timeout=120
    )
    return done.stdout


def _copy_of_the_checkout(target: Path) -> None:
    """The tracked files of the working tree, committed into a new repository."""
    files = _git(REPO, "ls-files", "-z").split("\0")
    for name in filter(None, files):
        source, copy = REPO / name, target / name
        if not source.exists() and not source.is_symlink():
            continue  # deleted in the working tree
        copy.parent.mkdir(parents=True, exist_ok=True)
        shutil.copy2(source, copy, follow_symlinks=False)
    _git(target, "init", "-q")
    _git(target, "add", "-A")
    identity = ["-c", "user.name=tour", "-c", "user.email=tour@localhost"]
    _git(target, *identity, "commit", "-q", "-m", "the checkout")


def test_the_tour_reads_as_documented():
    commands = tour_commands()
    assert len(commands) >= 5
    assert ["geofrac", "validate", "--quick"] in commands
    assert all(c[0] in ("geofrac", "mpiexec") for c in commands)


@pytest.mark.skipif(shutil.which("git") is None, reason="needs git")
def test_the_tour_leaves_the_checkout_clean_and_every_run_says_its_result(tmp_path):
    if not (REPO / ".git").exists():
        pytest.skip("not a git checkout")
    clone = tmp_path / "geofrac"
    _copy_of_the_checkout(clone)
    env = subprocess_env() | {"PYTHONPATH": str(clone)}
    env.pop("NUMBA_CACHE_DIR", None)  # the default: the user's cache, not the package
    quickstart = ["geofrac", "run", "jobs/quickstart.toml", "--overwrite"]  # make quickstart
    for words in [quickstart, *tour_commands()]:
        done = subprocess.run(
            _argv(words),
            cwd=clone,
            env=env,
            capture_output=True,
            text=True,
            timeout=900,
            check=False,
        )
        shown = " ".join(words)
        assert done.returncode == 0, f"{shown}:\n{done.stdout}\n{done.stderr}"
        if words[-3:-1] == ["geofrac", "run"] or words[:2] == ["geofrac", "run"]:
            assert "\nresult" in done.stdout, f"{shown} printed no result block:\n{done.stdout}"
    status = _git(clone, "status", "--porcelain", "--ignored=no")
    assert status == "", f"the tour changed tracked files:\n{status}"
    assert (clone / "results" / "validation" / "validation.md").is_file()
    assert not list((clone / "geofrac").rglob("*.nbc"))  # numba's cache is elsewhere
    assert os.path.exists(clone / "results" / "notched_beam" / "cracks.png")


def test_the_readme_the_guide_and_help_quote_the_measured_validation_time():
    from geofrac.cli import quick_time

    said = quick_time()
    assert said.startswith("about ") and "measured 20" in said  # measured and dated
    assert f"({said})" in README
    assert said in (REPO / "docs" / "guide.md").read_text()
