"""Checkpoints of a staged cracking run whose stage installs support (``add``).

The lined opening of scenes/lined_cracking.toml (tests/fracture/test_staged_support.py)
on a coarse mesh (h = 0.1a, L = 10a, meshed once: a run takes about 2.5 s) under an
anisotropic σ0 = (−2, −10, 0) (K = 0.2: the crown goes into tension as the release
grows, Kirsch), the rock's f_t = 1: the excavation (``relaxation`` 0.7) cracks the rock
beside the crown once (event 1, λ = 0.659), then the ring (E_l = 3·10⁴, f_s = 0.8) is
installed stress-free and the rest released: one more rock crack, then four edges of the
ring (events 3-6, judged with the support's own strength). A run stopped after event 1
(before the installation: the resumed run installs the ring itself) or after event 2, 3
or 4 (after it: the resume installs it again, at u_I = the first stage's stored end,
between the crack replay's events where the interrupted run did) must give the whole
run's events (the same edges in the same order, λ to 1e-12 relative, every logged number
to 1e-10), ``stages`` entries, ``results.xdmf`` steps (the output's support material and
reference included) and final displacement (1e-10 of its largest), on 1 and 2 ranks.
With the refactor solver checkpoint 4 restarts at event 4: the replay cracks ring edges
after the installation, whose MLS fits take the ring's D. With contact on the cracks
(the rock's pairs exist when the ring is installed) a checkpoint in the lined stage
resumes alike, the pairs' states included. A checkpoint whose ``add`` or support
``material`` differs from the scene's, or that kept no installations, is refused naming
the key.
"""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from mpi4py import MPI

from geofrac.errors import RunError
from geofrac.io import checkpoint
from geofrac.meshing.geo import meshed_model
from tests.fracture.test_resume import path_driver as driver
from tests.fracture.test_resume import read_log, shared_dir
from tests.fracture.test_staged_resume import resumed, saved, stop_at, stopped, whole
from tests.fracture.test_staged_support import ELASTIC, LINED

#: the ring's radii: a site with b < r < a is an edge of the installed support.
A, B = 1.0, 0.9
OVERRIDES = ("cracking.max_events=6", "cracking.solver=refactor", "output.xdmf=true")
#: λ of the resumed events against the whole run's, relative.
LAMBDA_RTOL = 1e-12


def scene(tmp: Path, comm: MPI.Comm, *, mesh: Path | None = None, edit: Any = None) -> Path:
    """The lined scene of the module docstring in rank 0's ``tmp`` (meshed once, ``.msh``).

    ``mesh``: a ``.msh`` already written; ``edit``: a change of the scene's text.
    """
    path = None
    if comm.rank == 0:
        tmp.mkdir(parents=True, exist_ok=True)
        text = LINED.read_text().replace("../../fem/lined.geo", str(ELASTIC.parent / "lined.geo"))
        text = text.replace("stress = [-10.0, -10.0, 0.0]", "stress = [-2.0, -10.0, 0.0]")
        text = text.replace("tensile_strength = 1.0e9\n", "tensile_strength = 1.0\n")
        text = text.replace("tensile_strength = 1.0e9 }", "tensile_strength = 0.8 }")
        text = text.replace("relaxation = 0.4", "relaxation = 0.7")
        text = text.replace("L = 20.0, h = 0.05", "L = 10.0, h = 0.1")
        found = re.search(r'file = "(.*)"\nparameters = \{(.*)\}', text)
        assert found is not None
        if mesh is None:
            mesh = tmp / "lined.msh"
            pairs = (kv.split("=") for kv in found.group(2).split(","))
            with meshed_model(
                Path(found.group(1)), {k.strip(): float(v) for k, v in pairs}, None, dim=2
            ) as gmsh:
                gmsh.write(str(mesh))
        text = text.replace(found.group(0), f'file = "{mesh}"')
        path = tmp / "lined.toml"
        path.write_text(edit(text) if edit else text)
    return Path(comm.bcast(str(path) if path else None, root=0))


def ring_sites(rows: list[dict[str, Any]]) -> list[int]:
    """The events whose site is an edge of the ring (b < r < a)."""
    return [r["event"] for r in rows if B < float(np.hypot(r["x"], r["y"])) < A]


def check_whole(ref: Any) -> None:
    """The whole run cracks the rock in the excavation, then the rock and the ring."""
    d, res = ref[0], ref[1]
    assert [s["events"] for s in res["stages"]] == [1, 5]
    assert [s["added"] for s in res["stages"]] == [[], ["ring"]]
    assert ring_sites(d.rows) == [3, 4, 5, 6]


def lambdas_match(base: Path) -> None:
    """λ of every event of the resumed run's log against the whole run's, to 1e-12."""
    a, b = (read_log(base / d / "events.csv") for d in ("whole", "stopped"))
    assert [r["edge"] for r in b] == [r["edge"] for r in a]
    x = np.array([float(r["load_factor"]) for r in b])
    y = np.array([float(r["load_factor"]) for r in a])
    np.testing.assert_allclose(x, y, rtol=LAMBDA_RTOL, atol=0)


def test_a_staged_run_with_support_resumes_before_and_after_the_installation(tmp_path, monkeypatch):
    """Checkpoints 1 (excavation running) and 2-4 (the lined stage running)."""
    monkeypatch.setattr(checkpoint, "KEEP", 4)
    comm = MPI.COMM_SELF
    path = scene(tmp_path / "scene", comm)
    ref = whole(tmp_path, path, OVERRIDES, comm)
    check_whole(ref)
    ck = stopped(tmp_path, path, OVERRIDES, 4, comm)
    for k, stage, replay_from in ((1, 0, 1), (2, 1, 2), (4, 1, 4)):
        ckpt = saved(ck, k)
        loop = ckpt.data["loop"]
        assert loop["stage"] == stage and ckpt.data["replay_from"] == replay_from
        assert loop["supports"][1][0] == ["ring"] and loop["supports"][1][1]["E"] == 3.0e4
        got = resumed(tmp_path, path, OVERRIDES, ckpt, ref, comm)
        lambdas_match(tmp_path)
        print(f"resumed after event {k} (replay from {replay_from}): {got}")


def test_a_staged_run_with_support_and_contact_resumes(tmp_path):
    """With contact on the cracks: the rock's pairs exist when the ring is installed.

    The excavation cracks three rock edges (a pair sticks and slips), the lined stage
    three of the ring; stopped after event 5, checkpoint 5 restarts at event 4, the
    lined stage's first (its installation refreshed the pairs beside the ring).
    """
    comm = MPI.COMM_SELF
    overrides = ("cracking.max_events=6", "cracking.contact=true", "output.xdmf=true")
    path = scene(tmp_path / "scene", comm)
    ref = whole(tmp_path, path, overrides, comm)
    assert [s["events"] for s in ref[1]["stages"]] == [3, 3]
    assert ring_sites(ref[0].rows) == [4, 5, 6] and ref[1]["contact"]["pairs"] > 0
    ck = stopped(tmp_path, path, overrides, 5, comm)
    ckpt = saved(ck, 5)
    assert ckpt.data["loop"]["stage"] == 1 and ckpt.data["replay_from"] == 4
    print(f"with contact: {resumed(tmp_path, path, overrides, ckpt, ref, comm)}")
    lambdas_match(tmp_path)
    whole_log, log = (
        read_log(d / "events.csv") for d in (tmp_path / "whole", tmp_path / "stopped")
    )
    for key in ("open", "stick", "slip", "contact_changes"):
        assert [r[key] for r in log] == [r[key] for r in whole_log], key


def test_a_checkpoint_with_other_installations_is_refused(tmp_path):
    """Another ``add``, another support material, or no installations kept: refused."""
    comm = MPI.COMM_SELF
    path = scene(tmp_path / "scene", comm)
    overrides = ("cracking.max_events=3", "cracking.solver=refactor")
    ck = stopped(tmp_path, path, overrides, 2, comm)
    ckpt = saved(ck, 2)
    mesh = tmp_path / "scene" / "lined.msh"

    def refused(edit: Any, match: str) -> None:
        other = scene(tmp_path / "other", comm, mesh=mesh, edit=edit)
        control = stop_at(ck, comm, -1, resume=ckpt)
        d = driver(other, overrides, tmp_path / "other", comm, control)
        try:
            with pytest.raises(RunError, match=match):
                d.run()
        finally:
            d.problem.destroy()

    backfill = 'add = ["core", "ring"]\nmaterial = { E = 30000.0, nu = 0.2 }'
    refused(
        lambda text: text.replace(
            'add = ["ring"]\nmaterial = { E = 30000.0, nu = 0.2, tensile_strength = 0.8 }',
            backfill,
        ),
        r"written with stages\[1\]\.add = \['ring'\]; this scene's stages\[1\]\.add is "
        r"\['core', 'ring'\]",
    )
    refused(
        lambda text: text.replace("E = 30000.0, nu = 0.2", "E = 20000.0, nu = 0.2"),
        r"another support material \(stages\[1\]\.material\.E = 30000\.0 there, 20000\.0 here\)",
    )
    refused(
        lambda text: text.replace(", tensile_strength = 0.8 }", " }"),
        r"stages\[1\]\.material\.tensile_strength = 0\.8 there, None here",
    )
    ckpt.meta["data"]["loop"].pop("supports")  # a checkpoint that kept no installations
    refused(lambda text: text, r"stages\[1\]\.add = \[\]; this scene's stages\[1\]\.add is")


@pytest.mark.mpi(min_size=2)
def test_a_staged_run_with_support_resumes_on_2_ranks(tmp_path, monkeypatch):
    """Checkpoints 1 and 4 of a 2-rank run: as the whole 2-rank run."""
    monkeypatch.setattr(checkpoint, "KEEP", 4)
    comm = MPI.COMM_WORLD
    base = shared_dir(tmp_path, comm)
    path = scene(base / "scene", comm)
    ref = whole(base, path, OVERRIDES, comm)
    check_whole(ref)
    ck = stopped(base, path, OVERRIDES, 4, comm)
    for k in (1, 4):
        ckpt = saved(ck, k)
        assert ckpt.data["loop"]["stage"] == (0 if k == 1 else 1)
        got = resumed(base, path, OVERRIDES, ckpt, ref, comm)
        failure = None
        if comm.rank == 0:
            try:
                lambdas_match(base)
            except AssertionError as exc:
                failure = str(exc) or "λ differ"
        assert comm.bcast(failure, root=0) is None
        print(f"on {comm.size} ranks, resumed after event {k}: {got}")
