"""Jaeger's single plane of weakness against geofrac (docs/cracking.md, "Crack faces in contact").

Run from the repository root: ``PYTHONPATH=$PWD .venv/bin/python docs/jaeger.py`` (1 rank,
under a minute). It runs jobs/jaeger_joint.toml (a 40 x 80 specimen in uniaxial
compression between smooth platens, one through-going joint of cohesion c = 1 and friction
μ = 0.5 whose normal makes β with the load) for β = 20°, 25°, ..., 80° and takes the
axial stress σ1 = reaction / (W t) of its first event, which must be the joint's slip
(``mode = "slip"``). Jaeger's law (Jaeger, Cook and Zimmerman, Fundamentals of Rock
Mechanics, 4th ed., 2007, §4.7):

    σ1 = 2c / ((1 − μ cot β) sin 2β)   for β > atan μ, no slip otherwise.

It prints a markdown table (β, law, geofrac, relative difference) and draws
``docs/img/jaeger.png``. ``--set KEY=VALUE`` (repeatable) passes further scene overrides,
e.g. ``--set geometry.parameters.h=1.25`` or ``--set discretization.element=rgnt``.
"""

from __future__ import annotations

import argparse
import math
from pathlib import Path

import numpy as np
from mpi4py import MPI

from geofrac.effects.cracking import scene_driver
from geofrac.scene import load_scene_collective

ROOT = Path(__file__).resolve().parent.parent
JOB = ROOT / "jobs" / "jaeger_joint.toml"
BETAS = tuple(range(20, 81, 5))
__all__ = ["BETAS", "jaeger_sigma1", "main", "slip_stress"]


def jaeger_sigma1(beta: float, c: float, mu: float) -> float:
    """σ1 at which the joint slips (Jaeger et al. 2007, §4.7); inf for β ≤ atan μ."""
    b = math.radians(beta)
    if math.tan(b) <= mu:
        return math.inf
    return 2.0 * c / ((1.0 - mu / math.tan(b)) * math.sin(2.0 * b))


def slip_stress(beta: float, overrides: list[str]) -> tuple[float | None, str]:
    """(σ1 = reaction / (W t) at the joint's slip or None, how the run ended) at ``beta``."""
    scene = load_scene_collective(
        MPI.COMM_SELF, JOB, [f"geometry.parameters.beta={beta}", *overrides]
    )
    driver = scene_driver(scene, MPI.COMM_SELF)
    try:
        res = driver.run()
    finally:
        driver.problem.destroy()
    width = scene.geometry.parameters["W"]
    thickness = scene.material.thickness
    slips = [r for r in driver.rows if r["mode"] == "slip"]
    if not slips:
        return None, str(res["end_reason"])
    if driver.rows[0]["mode"] != "slip":
        return None, f"first event {driver.rows[0]['mode']}"
    return slips[0]["reaction"] / (width * thickness), str(res["end_reason"])


def _joint(overrides: list[str]) -> tuple[float, float]:
    """(c, μ) of the scene's joint after ``overrides``."""
    scene = load_scene_collective(MPI.COMM_SELF, JOB, overrides)
    config = next(s.config for s in scene.effects if s.name == "cracking")
    props = dict(config.joints)["joint"]
    return props.cohesion, props.friction


def main() -> None:
    """Sweep β, print the table, draw the figure."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--set", action="append", default=[], dest="overrides")
    parser.add_argument("--out", type=Path, default=ROOT / "docs" / "img" / "jaeger.png")
    args = parser.parse_args()
    c, mu = _joint(args.overrides)

    rows = []
    print("| β (°) | Jaeger σ1 | geofrac σ1 | difference |")
    print("|---:|---:|---:|---:|")
    for beta in BETAS:
        law = jaeger_sigma1(beta, c, mu)
        got, end = slip_stress(beta, args.overrides)
        rows.append((beta, law, got))
        law_s = "no slip" if math.isinf(law) else f"{law:.4g}"
        got_s = f"no slip ({end})" if got is None else f"{got:.4g}"
        if got is not None and not math.isinf(law):
            diff = f"{(got - law) / law:+.2%}"
        else:
            diff = "agree" if (got is None) == math.isinf(law) else "DISAGREE"
        print(f"| {beta} | {law_s} | {got_s} | {diff} |", flush=True)
    _plot(rows, c, mu, args.out)


def _plot(rows: list[tuple[float, float, float | None]], c: float, mu: float, out: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    phi = math.degrees(math.atan(mu))
    fig, ax = plt.subplots(figsize=(6.4, 4.4))
    beta = np.linspace(phi + 0.3, 89.7, 600)
    ax.plot(beta, [jaeger_sigma1(b, c, mu) for b in beta], "k-", lw=1.2, label="Jaeger's law")
    ax.axvline(phi, color="0.6", ls=":", lw=1.0, label=f"atan μ = {phi:.1f}°: no slip below")
    hit = [(b, s) for b, _, s in rows if s is not None]
    none = [b for b, _, s in rows if s is None]
    if hit:
        ax.plot(*zip(*hit, strict=True), "o", ms=6, mfc="none", mec="C3", label="geofrac: slip")
    top = max([20.0 * c] + [1.15 * s for _, s in hit])
    if none:
        ax.plot(none, [0.95 * top] * len(none), "x", ms=7, color="C0", label="geofrac: no slip")
    ax.set_ylim(0.0, top * 1.05)
    ax.set_xlim(15.0, 90.0)
    ax.set_xlabel("β, angle between the joint normal and the load (°)")
    ax.set_ylabel("axial stress σ1 at slip (MPa)")
    ax.set_title(f"Single plane of weakness: c = {c:g} MPa, μ = {mu:g}")
    ax.legend(loc="upper center", fontsize=8)
    ax.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(out, dpi=150)
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
