"""Hostile scenes: however malformed, a scene ends in one error line, exit 2 and no file.

Every ``tests/scenes/hostile/*.toml`` starts with ``# expect: <key>: <text>`` (the key
may be empty: ``# expect: : <text>``). ``geofrac check`` and ``geofrac run`` (with
``--out``, and from a fresh working directory without it) must exit with 2 and print
exactly one ``error:`` line naming the file, the key and the text, with no traceback,
and create no file: not in the scene's directory, the working directory, the output
directory, ``tmp_path``, nor (by the names a case could use) in the repository, its
``results/``, its parent, the system's temporary directory or the home directory.
The MPI variant does the same on every rank and checks that the ranks agree.
"""

from __future__ import annotations

import os
import tempfile
from pathlib import Path

import pytest

from tests.conftest import REPO

HOSTILE = Path(__file__).resolve().parents[1] / "scenes" / "hostile"
CASES = sorted(HOSTILE.glob("*.toml"))
#: Names a hostile case might write under, looked for in shared directories.
SUSPECT = ("hostile", "escaped")


def expectation(path: Path) -> tuple[str, str]:
    """(key, text) from the case's first line."""
    with path.open(errors="replace") as f:
        first = f.readline().strip()
    assert first.startswith("# expect:"), f"{path.name}: first line must be '# expect: ...'"
    key, _, text = first.removeprefix("# expect:").strip().partition(": ")
    if first.removeprefix("# expect:").strip().startswith(":"):
        key, text = "", first.removeprefix("# expect:").strip()[1:].strip()
    assert text, f"{path.name}: no expected text"
    return key, text


def _tree(root: Path) -> set[str]:
    """Every file and directory under ``root`` (relative), or an empty set."""
    if not root.exists():
        return set()
    return {str(p.relative_to(root)) for p in root.rglob("*")}


def _suspects(root: Path, stem: str) -> set[str]:
    """Entries of ``root`` (one level) whose names a hostile case could have made."""
    if not root.is_dir():
        return set()
    words = (*SUSPECT, stem)
    return {p.name for p in root.iterdir() if any(w in p.name for w in words)}


def _private(*dirs: Path) -> dict[Path, set[str]]:
    return {d: _tree(d) for d in dirs}


def _shared(stem: str) -> dict[Path, set[str]]:
    dirs = (
        REPO,
        REPO / "results",
        REPO.parent,
        HOSTILE.parent,
        Path(tempfile.gettempdir()),
        Path.home(),
    )
    return {d: _suspects(d, stem) for d in dirs}


def _shared_after(before: dict[Path, set[str]], stem: str) -> dict[Path, set[str]]:
    return {d: _suspects(d, stem) - names for d, names in before.items()}


def _check_output(path: Path, code: int, out: str, err: str) -> None:
    key, text = expectation(path)
    assert code == 2, (code, err)
    assert "Traceback" not in out + err
    assert out == ""
    lines = [line for line in err.splitlines() if line.strip()]
    assert len(lines) == 1, err
    line = lines[0]
    assert line.startswith(f"error: {path}: "), line
    assert key in line, (key, line)
    assert text in line, (text, line)


def _serial_only() -> None:
    """Skip under ``mpiexec``: the serial tests expect every message on this process."""
    from mpi4py import MPI

    if MPI.COMM_WORLD.size > 1:
        pytest.skip("serial test; the MPI variant covers several ranks")


def _run_case(path: Path, work: Path, call, chdir) -> list[tuple[int, str, str]]:
    """check, run --out, and run from a fresh working directory; their results."""
    out_dir = work / "out"
    cwd = work / "cwd"
    cwd.mkdir(parents=True, exist_ok=True)
    results = [call("check", path), call("run", path, "--out", out_dir)]
    chdir(cwd)
    try:
        results.append(call("run", path))
    finally:
        chdir(REPO)
    return results


def test_there_are_enough_hostile_scenes():
    ours = [p for p in CASES if not p.name.startswith("geo_")]
    assert len(ours) >= 32
    for path in CASES:
        expectation(path)


@pytest.mark.parametrize("path", CASES, ids=lambda p: p.stem)
def test_hostile_scene_is_refused_cleanly(path, tmp_path, cli, monkeypatch):
    _serial_only()
    monkeypatch.chdir(REPO)
    work = tmp_path / "work"
    work.mkdir()
    private = _private(HOSTILE, tmp_path)
    shared = _shared(path.stem)
    results = _run_case(path, work, cli, monkeypatch.chdir)
    for code, out, err in results:
        _check_output(path, code, out, err)
    # only the directories this test made itself
    assert _tree(tmp_path) == private[tmp_path] | {"work/cwd"}
    assert _tree(HOSTILE) == private[HOSTILE]
    assert not (work / "out").exists()
    assert _tree(work / "cwd") == set()
    assert all(not new for new in _shared_after(shared, path.stem).values())


def test_deep_set_chain_is_refused(cli, tmp_path):
    _serial_only()
    scene = HOSTILE / "name_empty.toml"
    code, out, err = cli("check", scene, "--set", "a." * 5000 + "b=1")
    assert code == 2 and out == ""
    assert len(err.strip().splitlines()) == 1 and "nested deeper than 16" in err
    deep = "[" * 5000 + "]" * 5000
    overrides = ("--set", f"output.probes.a={deep}")
    code, out, err = cli("run", scene, "--out", tmp_path / "out", *overrides)
    assert code == 2 and "Traceback" not in err and len(err.strip().splitlines()) == 1
    assert "nested too deeply" in err
    assert not (tmp_path / "out").exists()


def test_allow_large_lifts_a_cap_but_not_a_hard_limit():
    _serial_only()
    from geofrac.scene import SceneError, load_scene

    scene = load_scene(HOSTILE / "cracking_events_huge.toml", allow_large=True)
    assert scene.allow_large and scene.size.quantities["events"] == 1e8
    with pytest.raises(SceneError, match="beyond what any machine holds"):
        load_scene(HOSTILE / "mpm_grid_huge.toml", allow_large=True)
    with pytest.raises(SceneError, match="far beyond the cap"):
        load_scene(HOSTILE / "mpm_grid_large.toml", ranks=4)
    assert load_scene(HOSTILE / "mpm_grid_large.toml", ranks=32).size.quantities[
        "grid_nodes"
    ] == pytest.approx(1e8, rel=0.01)


@pytest.mark.mpi(min_size=2)
def test_hostile_scenes_fail_together_on_every_rank(tmp_path, capsys, monkeypatch):
    from mpi4py import MPI

    from geofrac.cli import main

    comm = MPI.COMM_WORLD
    root = Path(comm.bcast(str(tmp_path) if comm.rank == 0 else None, root=0))

    def call(*argv: object) -> tuple[int, str, str]:
        code = main([str(a) for a in argv])
        captured = capsys.readouterr()
        return code, captured.out, captured.err

    monkeypatch.chdir(REPO)
    for i, path in enumerate(CASES):
        work = root / f"case{i}"
        comm.Barrier()
        results = _run_case(path, work, call, monkeypatch.chdir)
        codes = comm.allgather([code for code, _, _ in results])
        assert all(c == codes[0] for c in codes), (path.name, codes)
        for code, out, err in results:
            if comm.rank == 0:
                _check_output(path, code, out, err)
            else:
                assert code == 2 and out == "" and err == "", (path.name, err)
        comm.Barrier()
        if comm.rank == 0:
            assert not (work / "out").exists(), path.name
            assert _tree(work / "cwd") == set(), path.name
    assert os.getcwd() == str(REPO)
