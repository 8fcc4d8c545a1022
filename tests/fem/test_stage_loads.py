"""Loads and supports switched on and off per construction stage (docs/insitu.md).

References are independent of the code under test:

- **Linearity** (elasticity is linear, the stages' solves superpose): a load switched on
  and later off returns the body to the state before it (to 1e-10 relative), and the
  state while it acts is the one-step elastic solution of all the loads acting then; a
  support removed in a later stage leaves the state of the analysis without it from the
  start, and the release it applies is minus its last reaction.
- **Uniaxial stress** (closed form, exact for P2: the field is linear): a unit square,
  rollers on x = 0 and y = 0, a traction σ on x = a: u_x(a) = σ a/E, u_y(a) = −ν σ a/E
  (plane stress), reactions ∓σ a t; a support installed on x = a with an increment δ
  holds u_x(a) = u_before + δ, so σxx = E u_x(a)/a.
- **Propped cantilever** (Euler–Bernoulli beam theory, Timoshenko and Gere (1972)): a
  beam of length L = 10 D clamped at x = 0, on a prop at x = L, under a uniform load q:
  the prop carries R = 3qL/8; removing the prop in a later stage puts the tip at the
  free cantilever's deflection qL⁴/(8EI) + qL²/(2κGA) (bending plus Timoshenko's shear
  deflection, κ = 5/6). The shear and the clamp's local flexibility, which beam theory
  leaves out, are below 1 % here (stated tolerance 1 %; measured 0.26 % on R and
  0.13 % on the tip).
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from mpi4py import MPI

from geofrac import interrupt
from geofrac.model.errors import SceneError
from geofrac.pipeline import run_scene
from geofrac.runner import solve_scene
from geofrac.scene import load_scene_collective
from tests.conftest import JOBS
from tests.fem.test_stage_resume import _shared, _stop_after

MESHES = JOBS.parent / "meshes"
BEAM_GEO = JOBS.parent / "tests" / "fem" / "point_beam.geo"
E, NU = 1000.0, 0.25

#: A cantilever L = 10, D = 1 clamped at x = 0 (tests/fem/point_beam.geo).
BEAM = f"""
name = "beam"
[geometry]
file = "{BEAM_GEO}"
parameters = {{ L = 10.0, D = 1.0, nx = 40, ny = 4 }}
[material]
E = {E}
nu = {NU}
plane = "stress"
[discretization]
element = "p2"
[[bc]]
group = "fixed"
value = [0.0, 0.0]
[output]
xdmf = false
probes = {{ middle = [5.0, 0.0], tip = [10.0, 0.0] }}
"""

#: Test 1: a weight always, an end traction and a point force at the end's middle from
#: stage 'on' until stage 'off'.
SWITCHED = (
    BEAM
    + """
[[load]]
type = "body_force"
value = [0.0, -0.02]
[[load]]
type = "traction"
group = "end"
value = [0.3, -0.1]
from = "on"
until = "off"
[[load]]
type = "point"
group = "tip"
value = [0.0, -0.05]
from = "on"
until = "off"
[[stages]]
name = "on"
[[stages]]
name = "off"
"""
)

Q = 0.01  # the propped beam's load per length (a traction on the bottom, thickness 1)
#: Test 2: a prop at the tip (the point 'tip', y held) until stage 'release'.
PROPPED = (
    BEAM
    + f"""
[[load]]
type = "traction"
group = "bottom"
value = [0.0, {-Q}]
[[bc]]
group = "tip"
value = [0.0]
components = ["y"]
until = "release"
[[stages]]
name = "release"
"""
)

SIGMA, DELTA = 5.0, 0.002
#: Test 3: a unit square on rollers, pulled by σ, then held and pushed by δ.
SQUARE = f"""
name = "square"
[geometry]
file = "{MESHES / "square.geo"}"
parameters = {{ a = 1.0, h = 0.5 }}
[material]
E = {E}
nu = {NU}
plane = "stress"
[discretization]
element = "p2"
[[bc]]
group = "left"
value = [0.0]
components = ["x"]
[[bc]]
group = "bottom"
value = [0.0]
components = ["y"]
[[bc]]
group = "right"
value = [{DELTA}]
components = ["x"]
from = "push"
[[load]]
type = "traction"
group = "right"
value = [{SIGMA}, 0.0]
from = "pull"
until = "push"
[[stages]]
name = "pull"
[[stages]]
name = "push"
[output]
xdmf = false
probes = {{ corner = [1.0, 1.0] }}
"""


def _scene(tmp_path: Path, text: str, name: str = "scene", comm: MPI.Comm = MPI.COMM_WORLD):
    directory = Path(comm.bcast(str(tmp_path) if comm.rank == 0 else None, root=0))
    path = directory / f"{name}.toml"
    if comm.rank == 0:
        path.write_text(text)
    comm.barrier()
    return path


def _results(path: Path, comm: MPI.Comm = MPI.COMM_WORLD) -> dict:
    scene = load_scene_collective(comm, path, ())
    solution = solve_scene(scene, comm, verbose=False)
    solution.problem.destroy()
    return solution.results


def _close(a: list[float], b: list[float], rel: float = 1e-10) -> None:
    scale = max(float(np.max(np.abs(b))), 1e-300)
    assert float(np.max(np.abs(np.subtract(a, b)))) <= rel * scale, (a, b)


def test_a_load_on_then_off_returns_and_equals_the_one_step_solution(tmp_path):
    stages = _results(_scene(tmp_path, SWITCHED))["stages"]
    assert [s["name"] for s in stages] == ["initial", "on", "off"]
    switched = ["load[1]", "load[2]"]
    assert stages[1]["loads_on"] == switched and stages[2]["loads_off"] == switched
    # both loads at once, no stages: the one-step elastic solution
    both = SWITCHED.replace('from = "on"\nuntil = "off"\n', "")
    assert "from" not in both
    both = both[: both.index("[[stages]]")]
    one = _results(_scene(tmp_path, both, "both"))
    for name in ("middle", "tip"):
        _close(stages[1]["probes"][name], one["probes"][name])
        _close(stages[2]["probes"][name], stages[0]["probes"][name])
        # the traction moved the body: the test can fail
        assert np.max(np.abs(np.subtract(stages[1]["probes"][name], stages[0]["probes"][name]))) > (
            0.1 * np.max(np.abs(stages[0]["probes"][name]))
        )
    _close(stages[2]["reactions"]["fixed"], stages[0]["reactions"]["fixed"])
    # the clamp carries the weight first, then the traction and the point force too
    _close(stages[0]["reactions"]["fixed"], [0.0, 0.02 * 10.0], rel=1e-10)
    _close(stages[1]["reactions"]["fixed"], [-0.3, 0.02 * 10.0 + 0.1 + 0.05], rel=1e-10)
    assert stages[2]["out_of_balance"] < 1e-10


def test_removing_the_prop_gives_the_cantilever_without_it(tmp_path):
    stages = _results(_scene(tmp_path, PROPPED))["stages"]
    free = PROPPED[: PROPPED.index('[[bc]]\ngroup = "tip"')]
    one = _results(_scene(tmp_path, free, "free"))
    for name in ("middle", "tip"):
        _close(stages[1]["probes"][name], one["probes"][name])
    prop = stages[0]["reactions"]["tip"]
    # the release applies minus the prop's last reaction
    _close(stages[1]["released_supports"]["tip"], [-x for x in prop])
    assert stages[1]["supports_off"] == ["bc[1]"]
    assert stages[1]["reactions"]["tip"] == [0.0, 0.0]  # gone (no initial stress)
    # beam theory: R = 3qL/8 (measured 0.26 % above: shear and the clamp)
    L, D = 10.0, 1.0
    assert prop[1] == pytest.approx(3 * Q * L / 8, rel=0.01)
    # the free cantilever's tip: bending qL⁴/(8EI) plus shear qL²/(2κGA), κ = 5/6
    shear = Q * L**2 / (2 * 5 / 6 * E / (2 * (1 + NU)) * D)
    bending = Q * L**4 / (8 * E * D**3 / 12)
    assert stages[1]["probes"]["tip"][1] == pytest.approx(-(bending + shear), rel=0.01)
    assert stages[1]["out_of_balance"] < 1e-8  # round-off of the solves (2e-10 measured)


def test_uniaxial_pull_then_an_installed_support_pushes_by_its_increment(tmp_path):
    stages = _results(_scene(tmp_path, SQUARE))["stages"]
    a = 1.0
    assert stages[0]["max_displacement"] == 0.0  # nothing acts in the initial step
    pulled = SIGMA * a / E
    _close(stages[1]["probes"]["corner"], [pulled, -NU * pulled], rel=1e-10)
    _close(stages[1]["reactions"]["left"], [-SIGMA * a, 0.0], rel=1e-10)
    assert stages[1]["reactions"]["right"] == [0.0, 0.0]  # not installed yet
    pushed = pulled + DELTA  # held where it was, plus the increment
    _close(stages[2]["probes"]["corner"], [pushed, -NU * pushed], rel=1e-10)
    stress = E * pushed / a
    _close(stages[2]["reactions"]["left"], [-stress * a, 0.0], rel=1e-10)
    _close(stages[2]["reactions"]["right"], [stress * a, 0.0], rel=1e-10)
    assert stages[2]["supports_on"] == ["bc[2]"] and stages[2]["loads_off"] == ["load[0]"]


LAYERS = JOBS.parent / "tests" / "fem" / "layers.toml"
G = 9.81  # the gravity effect's default


def _layers(stages: str) -> str:
    """tests/fem/layers.toml with its right roller removed at stage 'free', and ``stages``."""
    text = LAYERS.read_text()
    text = text.replace('file = "layers.geo"', f'file = "{LAYERS.parent / "layers.geo"}"')
    right = 'group = "right"\nvalue = [0.0]\ncomponents = ["x"]\n'
    assert right in text
    return text.replace(right, right + 'until = "free"\n') + stages


def test_a_support_removed_with_an_excavation_is_released_once_in_full(tmp_path):
    """The geostatic two-layer column of test_insitu.py, its right roller removed.

    The roller carried the initial state's σxx0 = K0 σv on x = W: released, it applies
    −∫ σxx0 dy = g [K0_u (3·2000·3 + 2200·3²/2) + K0_l (2·(2000·3 + 2200·3) + 3000·2²/2)]
    (cover 3 m at 2000, upper 3 m at 2200 with K0 = ν/(1 − ν) = 1/3, lower 2 m at 3000
    with K0 = 0.6). Removed in the same stage as the upper layer, with a share 0.4 of
    the excavation's release and then the rest, the end state equals removing the roller
    first and the layer after (linear elasticity: the end state does not depend on the
    path); a double-counted release would move it.
    """
    together = _layers(
        '[[stages]]\nname = "free"\nremove = ["upper"]\nrelaxation = 0.4\n'
        '[[stages]]\nname = "rest"\n'
    )
    apart = _layers('[[stages]]\nname = "free"\n[[stages]]\nname = "cut"\nremove = ["upper"]\n')
    a = _results(_scene(tmp_path, together, "together"))["stages"]
    b = _results(_scene(tmp_path, apart, "apart"))["stages"]
    released = G * (1 / 3 * (2000.0 * 3 * 3 + 2200.0 * 9 / 2) + 0.6 * (2 * 12600.0 + 3000.0 * 2))
    for stages in (a, b):
        _close(stages[1]["released_supports"]["right"], [released, 0.0], rel=1e-10)
        # gone: 0 minus the force it carried in the initial state (−released)
        _close(stages[2]["reactions"]["right"], [released, 0.0], rel=1e-10)
    assert a[1]["share"] == pytest.approx(0.4)
    _close(a[2]["probes"]["low"], b[2]["probes"]["low"])  # ('high' is in the removed layer)
    _close(a[2]["reactions"]["bottom"], b[2]["reactions"]["bottom"])
    # the release moved the body: the lower layer expands to the right
    assert b[1]["probes"]["low"][0] > 1e-6


@pytest.mark.mpi(min_size=2)
@pytest.mark.parametrize("case", ["switched", "propped", "square", "together"])
def test_two_ranks_agree_with_one(tmp_path, case):
    comm = MPI.COMM_WORLD
    together = '[[stages]]\nname = "free"\nremove = ["upper"]\nrelaxation = 0.4\n'
    text = {
        "switched": SWITCHED,
        "propped": PROPPED,
        "square": SQUARE,
        "together": _layers(together + '[[stages]]\nname = "rest"\n'),
    }[case]
    many = _results(_scene(tmp_path, text, case), comm)["stages"]
    if comm.rank == 0:
        one = _results(_scene(tmp_path, text, case + "1", MPI.COMM_SELF), MPI.COMM_SELF)["stages"]
    else:
        one = None
    one = comm.bcast(one, root=0)
    worst = 0.0
    for key in ("probes", "reactions", "released_supports"):  # scale: the key's largest
        pairs = [
            (a[key][n], b[key][n]) for a, b in zip(many, one, strict=True) for n in b.get(key, {})
        ]
        if not pairs:
            continue
        x, y = (np.concatenate([np.ravel(p[i]) for p in pairs]) for i in (0, 1))
        worst = max(worst, float(np.max(np.abs(x - y))) / max(float(np.max(np.abs(y))), 1e-300))
    worst = comm.allreduce(worst, op=MPI.MAX)
    assert worst <= 1e-10


BAD = [
    (
        SWITCHED.replace('from = "on"', 'from = "onn"'),
        r"load\[1\]\.from.*unknown stage 'onn'.*did you mean 'on'",
    ),
    (SWITCHED.replace('until = "off"', 'until = "of"'), r"load\[1\]\.until.*unknown stage 'of'"),
    (
        SWITCHED.replace('from = "on"', 'from = "off"').replace('until = "off"', 'until = "on"'),
        r"load\[1\]\.until.*not after",
    ),
    (SWITCHED[: SWITCHED.index("[[stages]]")], r"load\[1\]\.from.*needs \[\[stages\]\]"),
    (
        PROPPED.replace('until = "release"', 'until = "release"\nfrom = "release"'),
        r"bc\[1\]\.until.*not after",
    ),
    (
        PROPPED.replace("value = [0.0, 0.0]\n", 'value = [0.0, 0.0]\nuntil = "release"\n', 1),
        r"bc:.*no \[\[bc\]\] is active in stage 'release'",
    ),
    (
        SQUARE.replace(
            'group = "left"\nvalue = [0.0]', 'group = "left"\nvalue = [0.0]\nfrom = "pull"'
        ).replace(
            'group = "bottom"\nvalue = [0.0]', 'group = "bottom"\nvalue = [0.0]\nfrom = "pull"'
        ),
        r"no \[\[bc\]\] is active in the initial step",
    ),
    (SWITCHED.replace('from = "on"', "from = 3"), r"load\[1\]\.from"),
]


@pytest.mark.parametrize("text, message", BAD)
def test_bad_switches_are_refused_naming_the_key(tmp_path, text, message):
    with pytest.raises(SceneError, match=message):
        load_scene_collective(MPI.COMM_SELF, _scene(tmp_path, text, comm=MPI.COMM_SELF), ())


def test_a_run_stopped_after_the_switch_resumes_to_the_whole_run(tmp_path, monkeypatch):
    _stop_and_resume(tmp_path, monkeypatch)


@pytest.mark.mpi(min_size=2)
def test_two_ranks_resume_across_the_switch(tmp_path, monkeypatch):
    _stop_and_resume(tmp_path, monkeypatch)


def _stop_and_resume(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """Stop the first case after stage 'on' (SIGTERM), resume: the whole run's numbers."""
    comm = MPI.COMM_WORLD
    path = _scene(tmp_path, SWITCHED.replace("xdmf = false", "xdmf = true"))
    root = _shared(tmp_path, comm)

    def run(out: Path, *, resume: bool = False) -> None:
        scene = load_scene_collective(comm, path, (), out=out)
        run_scene(scene, comm, verbose=False, resume=resume)

    run(root / "whole")
    _stop_after(monkeypatch, 1)  # after stage 'on': the traction acts
    try:
        with pytest.raises(interrupt.Interrupted, match="after stage 1"):
            run(root / "stopped")
    finally:
        interrupt.reset()
        monkeypatch.undo()
    comm.barrier()
    run(root / "stopped", resume=True)
    comm.barrier()  # rank 0 writes the summaries
    a = json.loads((root / "stopped" / "summary.json").read_text())["results"]["stages"]
    b = json.loads((root / "whole" / "summary.json").read_text())["results"]["stages"]
    assert [s["name"] for s in a] == ["initial", "on", "off"]
    # 2 ranks: MUMPS's parallel factorisation is not bitwise reproducible from run to
    # run, so each vector is compared on its own size (a probe's 1e-6 component of a
    # 0.1 displacement differed by 1.7e-17, 2e-11 of itself)
    for x, y in zip(a, b, strict=True):
        for key in ("probes", "reactions"):
            for name in y[key]:
                scale = 1e-13 * float(np.max(np.abs(y[key][name])))
                np.testing.assert_allclose(x[key][name], y[key][name], rtol=1e-13, atol=scale)
        assert x["max_displacement"] == pytest.approx(y["max_displacement"], rel=1e-13)
