"""Crack runs under the perturbations a different machine would cause (``make test-robust``).

Another BLAS kernel, another number of ranks or another numbering of the same mesh
changes the last bits of every computed number. The decisions of the event loop
(docs/cracking.md, "Decisions and their scales") must not follow those bits, so every
case here is rerun

- with E and ν changed by a relative 1e-12,
- with the prescribed displacements changed by a relative 1e-12,
- on a permuted copy of the same mesh (``discretization.renumber``: nodes and cells
  numbered at random, every node where it was),
- on 2 ranks (the MPI tests),

and must give the same events (crack sites within ``XY_RTOL`` of the domain, load factors
within ``R_RTOL``, the same modes), the same end and the same contact states: the stored
references of tests/fracture/reference for the crack paths, and the unperturbed run for
the contact cases (Jaeger's specimen, jobs/jaeger_joint.toml). To see the original
failure on a machine whose OpenBLAS picks another kernel, run
``OPENBLAS_CORETYPE=Haswell pytest tests/fracture/test_contact_mechanics.py``.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest
from mpi4py import MPI

from geofrac.effects.cracking import scene_driver
from geofrac.scene import load_scene, load_scene_collective
from tests.fracture.reference import (
    CASES,
    R_RTOL,
    REPO,
    XY_RTOL,
    differences,
    domain_size,
    load,
    run_case,
)
from tests.fracture.test_contact_mechanics import COARSE, FRICTIONAL, JOB, H, W, run

pytestmark = pytest.mark.robust

#: The relative change of the input a different machine's round-off stands for.
EPS = 1e-12
#: Seeds of the permuted copies of the mesh.
RENUMBER = (1, 2)

Perturb = Callable[[Path, list[str]], list[str]]


def _scaled(value: float) -> str:
    """``value`` changed by a relative :data:`EPS`, as an override's text."""
    return repr(float(value) * (1.0 + EPS))


def perturb_modulus(path: Path, overrides: list[str]) -> list[str]:
    """E × (1 + 1e-12)."""
    return [f"material.E={_scaled(load_scene(path, overrides).material.E)}"]


def perturb_poisson(path: Path, overrides: list[str]) -> list[str]:
    """ν × (1 + 1e-12)."""
    return [f"material.nu={_scaled(load_scene(path, overrides).material.nu)}"]


def perturb_load(path: Path, overrides: list[str]) -> list[str]:
    """Every non-zero prescribed displacement × (1 + 1e-12) (the exact field's strains)."""
    scene = load_scene(path, overrides)
    out = []
    for i, bc in enumerate(scene.raw.get("bc", [])):
        value = bc.get("value")
        if isinstance(value, list) and any(v != 0 for v in value):
            out.append(f"bc.{i}.value=[{', '.join(_scaled(v) for v in value)}]")
    if scene.exact is not None:
        exact = scene.raw["exact"]
        out += [f"exact.{k}={_scaled(v)}" for k, v in exact.items() if k != "name" and v != 0]
    assert out, f"{path.name} prescribes no displacement to perturb"
    return out


def renumbered(seed: int) -> Perturb:
    """A permuted copy of the same mesh (``discretization.renumber = seed``)."""

    def perturb(path: Path, overrides: list[str]) -> list[str]:
        return [f"discretization.renumber={seed}"]

    perturb.__name__ = f"renumber_{seed}"
    return perturb


#: Every perturbation of the serial tests, by name.
PERTURBATIONS: dict[str, Perturb] = {
    "E": perturb_modulus,
    "nu": perturb_poisson,
    "load": perturb_load,
    **{f"renumber{s}": renumbered(s) for s in RENUMBER},
}


# -- the crack paths of tests/fracture/reference -----------------------------------------
def check_reference(case: str, perturb: Perturb, comm: MPI.Comm) -> None:
    """Rerun reference ``case`` perturbed; it must give the stored events and end."""
    ref = load(case)
    base = list(ref["overrides"])
    extra = perturb(REPO / ref["scene"], base)
    events = run_case(ref["scene"], base + extra, comm)
    diff = differences(ref, events, XY_RTOL * domain_size(ref), R_RTOL)
    assert not diff, f"{case} with {extra} departs from its reference: " + "; ".join(diff)


@pytest.mark.parametrize("name", PERTURBATIONS)
@pytest.mark.parametrize("case", CASES)
def test_reference_path_survives_perturbation(case, name):
    check_reference(case, PERTURBATIONS[name], MPI.COMM_SELF)


@pytest.mark.mpi(min_size=2)
@pytest.mark.parametrize("case", CASES)
def test_reference_path_on_two_ranks_of_a_permuted_mesh(case):
    check_reference(case, renumbered(3), MPI.COMM_WORLD)


# -- ties: every edge equally stressed -----------------------------------------------------
UNIFORM = Path(__file__).resolve().parent / "scenes" / "uniform_strain.toml"
#: Jaeger's specimen with a joint (jobs/jaeger_joint.toml).
JAEGER = JOB


def first_site(overrides: list[str]) -> tuple[float, float, float, int]:
    """(x, y, r, number of candidate edges) of the uniform-strain square's first event."""
    scene = load_scene_collective(MPI.COMM_SELF, UNIFORM, overrides)
    driver = scene_driver(scene, MPI.COMM_SELF)
    try:
        driver.run()
        row = driver.rows[0]
        state = driver.state
        return row["x"], row["y"], row["load_factor"], int((state.crackable).sum())
    finally:
        driver.problem.destroy()


@pytest.mark.parametrize("name", PERTURBATIONS)
def test_tied_edges_crack_in_the_same_place_on_any_machine(name):
    """A uniform strain: σ1 is the same on every crackable edge, all tie within round-off.

    The tie goes to the edge that comes first by position, so neither the round-off
    of another machine nor a renumbered mesh moves the first crack.
    """
    x0, y0, r0, n = first_site([])
    assert n > 50  # many edges tie
    x, y, r, _ = first_site(PERTURBATIONS[name](UNIFORM, []))
    assert (x, y) == pytest.approx((x0, y0), abs=1e-12 * 5.0)
    assert r == pytest.approx(r0, rel=1e-9)


# -- crack faces in contact (Jaeger's specimen) -------------------------------------------
#: The specimen's size (diagonal of 40 x 80), the scale of the sites' positions.
JAEGER_SIZE = float(np.hypot(W, H))


def perturbed(perturb: Perturb, overrides: list[str]) -> list[str]:
    """The Jaeger case's overrides with a perturbation's on the coarse mesh."""
    return overrides + perturb(JAEGER, [*COARSE, *overrides])


def same_run(a: tuple[list, dict], b: tuple[list, dict]) -> list[str]:
    """How run b departs from run a (empty: the same events, states and end)."""
    (rows_a, res_a), (rows_b, res_b) = a, b
    out = []
    if res_a["end_reason"] != res_b["end_reason"] or len(rows_a) != len(rows_b):
        out.append(
            f"end {len(rows_b)} events {res_b['end_reason']!r}, "
            f"expected {len(rows_a)} {res_a['end_reason']!r}"
        )
    for ra, rb in zip(rows_a, rows_b, strict=False):
        same = (
            ra["mode"] == rb["mode"]
            and abs(ra["x"] - rb["x"]) <= XY_RTOL * JAEGER_SIZE
            and abs(ra["y"] - rb["y"]) <= XY_RTOL * JAEGER_SIZE
            and rb["load_factor"] == pytest.approx(ra["load_factor"], rel=R_RTOL)
            and all(ra.get(k) == rb.get(k) for k in ("open", "stick", "slip"))
        )
        if not same:
            out.append(f"event {ra['event']}: {rb} instead of {ra}")
            break
    for k in ("pairs", "open", "stick", "slip", "bonded"):
        if res_a["contact"][k] != res_b["contact"][k]:
            out.append(f"contact {k}: {res_b['contact'][k]} instead of {res_a['contact'][k]}")
    return out


#: The contact cases: a crack pulled open; the same crack pressed shut; an inclined crack
#: that sticks (μ 0.8 > tan 30°) or slips (μ 0.4); a bonded joint at 60° that slips first.
CONTACT_CASES: dict[str, list[str]] = {
    "pulled_open": [*FRICTIONAL, "geometry.parameters.beta=0", "bc.2.value=[0.01]"],
    "pressed_shut": [*FRICTIONAL, "geometry.parameters.beta=0", "cracking.max_events=1"],
    "sticks": [
        *FRICTIONAL,
        "geometry.parameters.beta=30",
        "cracking.joints.joint.friction=0.8",
        "cracking.max_events=1",
    ],
    "slides": [
        *FRICTIONAL,
        "geometry.parameters.beta=30",
        "cracking.joints.joint.friction=0.4",
        "cracking.max_events=1",
    ],
    "joint_slip": ["geometry.parameters.beta=60"],
}


def test_jaeger_specimen_pulled_in_tension_never_records_an_event():
    """The crack opens and carries nothing: no event at any perturbation, all pairs open.

    This is the run whose unit-load solution is round-off: on one OpenBLAS kernel the
    criterion once divided f_t by it and recorded an event at a load factor of 4e16.
    """
    base = CONTACT_CASES["pulled_open"]
    for name, perturb in PERTURBATIONS.items():
        rows, res = run(*perturbed(perturb, base))
        assert not rows, (name, rows[0])
        assert res["end_reason"] == "separated", (name, res["end_reason"])
        assert res["contact"]["open"] == res["contact"]["pairs"] > 0, (name, res["contact"])


@pytest.mark.parametrize("name", PERTURBATIONS)
@pytest.mark.parametrize("case", CONTACT_CASES)
def test_contact_states_survive_perturbation(case, name):
    base = CONTACT_CASES[case]
    reference = run(*base)
    other = run(*perturbed(PERTURBATIONS[name], base))
    diff = same_run(reference, other)
    assert not diff, f"{case} with {name}: " + "; ".join(diff)


@pytest.mark.mpi(min_size=2)
@pytest.mark.parametrize("case", CONTACT_CASES)
def test_contact_states_on_two_ranks_of_a_permuted_mesh(case):
    base = CONTACT_CASES[case]
    reference = run(*base, comm=MPI.COMM_SELF)
    parallel = run(*base, "discretization.renumber=3", comm=MPI.COMM_WORLD)
    diff = same_run(reference, parallel)
    assert not diff, f"{case} on {MPI.COMM_WORLD.size} ranks: " + "; ".join(diff)
    ends = MPI.COMM_WORLD.allgather((parallel[1]["end_reason"], len(parallel[0])))
    assert all(e == ends[0] for e in ends)
