"""The result block of an MPM run (:meth:`geofrac.mpm.driver.MpmMethod.result`).

A bar under its own weight (Edo (2016), §4.5.1) gives the displacement of its top
particle against the closed form at rest (:func:`geofrac.mpm.bar.self_weight_displacement`);
any other scene its runout, the largest particle x moved (``runout_m``), in the scene's
length unit.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from geofrac.headline import quantity, versus
from geofrac.model.scene import Scene

__all__ = ["SelfWeightBar", "lines", "self_weight_bar"]


@dataclass(frozen=True)
class SelfWeightBar:
    """What the closed form of a bar under its own weight needs.

    Attributes:
        E: Young's modulus.
        rho0: initial density.
        b: magnitude of the gravity along -x.
        L0: initial length.
        base: x of the fixed base.
    """

    E: float
    rho0: float
    b: float
    L0: float
    base: float


def self_weight_bar(scene: Scene) -> SelfWeightBar | None:
    """The bar of ``scene`` when it is one under its own weight, else None.

    That is: 1D, gravity (towards the base) its only effect, the one wall ``x_min``
    fixed, one elastic lattice body resting on it.
    """
    spec, material = scene.mpm, scene.material
    if spec is None or material is None or spec.dim != 1 or scene.effect_names != ("gravity",):
        return None
    if spec.walls != {"x_min": "fixed"} or spec.bodies or spec.particles.kind != "lattice":
        return None
    if spec.particles.lower[0] != spec.lower[0] or any(v != 0.0 for v in spec.velocity):
        return None
    gravity = scene.effects[0].config
    b = -float(gravity.acceleration[0])  # type: ignore[attr-defined]
    if b <= 0.0 or material.density is None:
        return None
    length = spec.particles.counts[0] * spec.particles.spacing
    return SelfWeightBar(material.E, material.density, b, length, spec.lower[0])


def lines(scene: Scene, results: dict[str, Any]) -> list[str]:
    """The result block's lines of an MPM run's ``results``."""
    from geofrac.mpm.bar import self_weight_displacement

    length = scene.units.of("length")
    bar = self_weight_bar(scene)
    t = quantity(results["t_end"], scene.units.of("time"))
    if bar is not None:
        top = results["history"]["front_x"][0] - bar.base  # the top particle's height
        exact = self_weight_displacement(top, E=bar.E, rho0=bar.rho0, b=bar.b, L0=bar.L0)
        u = results["runout_m"]
        return [
            f"bar under its own weight: top particle (x = {quantity(top, length)}) moved "
            f"{quantity(u, length)} at t = {t}",
            f"closed form at rest (Edo (2016), eq. 4.73-4.74): {quantity(exact, length)}; "
            + versus(u, exact, length),
        ]
    line = f"runout (front x moved): {quantity(results['runout_m'], length)} at t = {t}"
    if "friction_angle_deg" in results:
        line += f", friction angle {results['friction_angle_deg']:g} deg"
    if results["energy_drift_max"] is not None:
        line += f"; energy drift max {results['energy_drift_max']:.3g}"
    return [line]
