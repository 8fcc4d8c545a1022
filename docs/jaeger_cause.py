"""Why the joint of Jaeger's specimen slips early (docs/cracking.md, "Crack faces in contact").

Run from the repository root: ``PYTHONPATH=$PWD .venv/bin/python docs/jaeger_cause.py``
(1 rank, about 20 s). It prints three measurements on jobs/jaeger_joint.toml:

1. *joint*: the specimen with its joint held bonded (cohesion 10⁶) under the unit load;
   per β the faces' stress (:func:`~geofrac.fracture.contact.pair_operator`) on each pair
   relative to the uniform field's σn = σ1 cos²β, τ = σ1 sin β cos β (σ1 = reaction / W t),
   the pairs' spring tractions k g, k s averaged along the joint, and the σ1 at which the
   first pair would slip (c = 1, μ = 0.5) relative to Jaeger's law;
2. *band*: the specimen uncracked, without contact, with a band of MLS cells across it
   (``mls_region``, y = 38-42): the stress σ_yy of the MLS cells relative to the uniform
   −E δ / H, and of the element cells within 5 mm of the band;
3. with ``--consistent``, both again with ``cracking.mls_gradient = "consistent"``
   (docs/cracking.md, "Integration-consistent MLS cells"): the joint's faces read the
   uniform field and the band carries it to round-off.

``--set KEY=VALUE`` (repeatable) passes further overrides, e.g.
``--set geometry.parameters.h=1.25`` or ``--set geometry.algorithm=delaunay``.
"""

from __future__ import annotations

import argparse
import math
import re
import tempfile
from pathlib import Path
from typing import Any

import numpy as np
from mpi4py import MPI

from geofrac.effects.cracking import scene_driver
from geofrac.scene import load_scene_collective

ROOT = Path(__file__).resolve().parent.parent
JOB = ROOT / "jobs" / "jaeger_joint.toml"
W, H, E, DELTA, C, MU = 40.0, 80.0, 10000.0, 0.01, 1.0, 0.5
__all__ = ["band", "joint", "main"]


def _driver(job: Path, overrides: list[str]) -> tuple[Any, dict[str, Any]]:
    """The crack driver after its run, and the run's results."""
    scene = load_scene_collective(MPI.COMM_SELF, job, overrides)
    driver = scene_driver(scene, MPI.COMM_SELF)
    try:
        res = driver.run()
    finally:
        driver.problem.destroy()
    return driver, res


def joint(beta: float, overrides: list[str]) -> str:
    """The faces' stress along the bonded joint at ``beta``, one line of text."""
    d, res = _driver(
        JOB,
        [
            f"geometry.parameters.beta={beta}",
            "cracking.joints.joint.cohesion=1e6",
            "cracking.max_events=1",
            *overrides,
        ],
    )
    pairs = d.contact.pairs
    act = pairs.active()
    b = math.radians(beta)
    s1 = abs(float(res["unit_load"]["reaction"])) / W
    pn, tau = s1 * math.cos(b) ** 2, s1 * math.sin(b) * math.cos(b)
    p, t = pairs.pressure[act] / pn, np.abs(pairs.shear[act]) / tau
    length = pairs.length[act]
    kg = -np.sum(length * pairs.k[act] * pairs.gap[act]) / length.sum() / pn
    ks = np.sum(length * pairs.k[act] * pairs.slip[act]) / length.sum() / tau
    drive = t * tau - MU * p * pn  # per unit σ1 of the unit load, as the slip check
    law = tau - MU * pn
    first = law / float(drive.max())
    return (
        f"| {beta:g} | {p.min():.3f}-{p.max():.3f} | {t.min():.3f}-{t.max():.3f} | "
        f"{kg:.4f}, {abs(ks):.4f} | {first - 1:+.2%} |"
    )


def band(overrides: list[str]) -> str:
    """σ_yy of an MLS band in the uncracked specimen, one line of text."""
    text = re.sub(r"\[cracking\.joints\.joint\][^\[]*", "", JOB.read_text())
    text = text.replace("contact = true", "contact = false")
    text = text.replace('precracked = ["joint"]', "mls_region = [0.0, 38.0, 40.0, 42.0]")
    text = text.replace('"../meshes/', f'"{ROOT / "meshes"}/')
    with tempfile.TemporaryDirectory() as tmp:
        job = Path(tmp) / "band.toml"
        job.write_text(text)
        d, _ = _driver(job, ["geometry.parameters.beta=0", "cracking.max_events=0", *overrides])
    units = d.units
    uniform = -E * DELTA / H
    mls = units.state.mls_cells
    s_mls = units.midpoint_stress[mls, 0, 1] / uniform
    cells = units.state.mesh.cells
    y = units.state.mesh.coords[cells, 1].mean(axis=1)
    near = ~units.state.is_mls() & (np.abs(y - 40.0) < 7.0)
    s_fe = units.midpoint_stress[near, :, 1].mean(axis=1) / uniform
    return (
        f"| {len(mls)} | {s_mls.min():.3f}-{s_mls.max():.3f} (mean {s_mls.mean():.3f}) | "
        f"{s_fe.min():.3f}-{s_fe.max():.3f} |"
    )


def main() -> None:
    """Print the two tables (with ``--consistent``: of the prototype)."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--set", action="append", default=[], dest="overrides")
    parser.add_argument("--consistent", action="store_true")
    parser.add_argument("--betas", default="30,45,60")
    args = parser.parse_args()
    if args.consistent:
        args.overrides.append("cracking.mls_gradient=consistent")
    print("| β (°) | faces' p / σn | faces' \\|τ\\| / τ | springs' mean k g, k s | first slip |")
    print("|---:|---|---|---|---:|")
    for beta in (float(b) for b in args.betas.split(",")):
        print(joint(beta, args.overrides), flush=True)
    print()
    print("| MLS cells | their σ_yy / uniform | element cells within 5 mm of the band |")
    print("|---:|---|---|")
    print(band(args.overrides))


if __name__ == "__main__":
    main()
