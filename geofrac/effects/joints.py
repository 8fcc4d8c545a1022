"""Effect ``joints``: elastic 3D rock with Coulomb joints, on P2 or RGNQ.

The joints of ``[plasticity.joints]`` without the rock's plasticity, for the elements
whose displacement is a P2 field: ``p2`` itself and ``rgnq`` (the tetrahedron with three
rotations per vertex, Edo (2016), eq. 2.5), solved in the element's own unknowns
(:mod:`geofrac.fem.joints_elastic`). Each ``[joints.NAME]`` table names a surface group
of the geometry (a ``.geo`` group or a ``dfn3d`` set or ``fractures``), cut along when
meshed (:mod:`geofrac.meshing.split`); its faces are tied by the springs of
:mod:`geofrac.fem.joints`: normal stiffness, no tensile strength, Coulomb friction with
cohesion, stick and slip in the joint's plane (docs/dfn3d.md).

Scene table ``[joints]``:

- ``[joints.NAME]``: ``friction`` (μ, required), ``cohesion`` (c, default 0),
  ``normal_stiffness`` and ``shear_stiffness`` (kₙ, kₛ in stress per length; default
  ``contact_penalty`` · E / edge length);
- ``contact_penalty`` (default 100), ``load_steps`` (default 10), ``max_iterations``
  (Newton iterations per step, default 25).

3D only; not with ``plasticity`` (which has the same joints with a plastic rock, on P2)
nor with ``[initial_stress]`` or ``[[stages]]``.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from geofrac.effects import ConfigureContext
from geofrac.effects.plasticity import JointConfig, joint_tables
from geofrac.model.errors import SceneError
from geofrac.model.table import Table

__all__ = ["ELEMENTS", "KEYS", "JointsConfig", "configure", "driver", "result"]

#: Scalar keys of ``[joints]``; every table in it is a joint (the keys of
#: :data:`geofrac.effects.plasticity.JOINT_KEYS`).
KEYS = ("contact_penalty", "load_steps", "max_iterations")
#: Elements whose displacement is a P2 field on tetrahedra.
ELEMENTS = ("p2", "rgnq")


@dataclass(frozen=True)
class JointsConfig:
    """Validated ``[joints]`` settings.

    Attributes:
        joints: the joint groups.
        contact_penalty: kₙ = kₛ = penalty · E / ℓ where a joint gives no stiffness.
        load_steps: equal load increments.
        max_iterations: Newton iterations per increment.
    """

    joints: tuple[JointConfig, ...]
    contact_penalty: float
    load_steps: int
    max_iterations: int


def configure(table: dict[str, Any], ctx: ConfigureContext) -> JointsConfig:
    """Validate ``[joints]`` against the geometry's surface groups and the element."""
    if ctx.gdim != 3:
        raise SceneError(ctx.file, "joints", "is 3D only (2D joints: [plasticity.joints])")
    if ctx.element not in ELEMENTS:
        raise SceneError(
            ctx.file,
            "discretization.element",
            f"joints need one of {', '.join(ELEMENTS)} (a P2 displacement), got {ctx.element!r}",
        )
    if "plasticity" in ctx.previous:
        raise SceneError(ctx.file, "joints", "not with plasticity: use [plasticity.joints]")
    scalars = {k: v for k, v in table.items() if not isinstance(v, dict)}
    tables = {k: v for k, v in table.items() if isinstance(v, dict)}
    t = Table(ctx.file, "joints", scalars, allowed=KEYS)
    if not tables:
        raise SceneError(ctx.file, "joints", "give at least one [joints.NAME] table")
    joints = joint_tables(tables, ctx, prefix="joints")
    return JointsConfig(
        joints,
        float(t.number("contact_penalty", default=100.0, positive=True, maximum=1e8)),
        int(t.number("load_steps", default=10, integer=True, minimum=1, maximum=10000)),
        int(t.number("max_iterations", default=25, integer=True, minimum=1, maximum=1000)),
    )


def driver(
    config: JointsConfig, solution: Any, say: Callable[[str], None], *, write: bool
) -> dict[str, Any]:
    """The joints' load-stepped Newton replaces the elastic solve; 3D outputs on rank 0."""
    from geofrac.errors import RunError
    from geofrac.fem.joints_elastic import run_elastic_joints

    scene = solution.scene
    if scene.initial_stress is not None or scene.stages:
        raise RunError("joints: [initial_stress] and [[stages]] need [plasticity.joints]")
    out = run_elastic_joints(
        solution,
        say,
        joints=config.joints,
        penalty=config.contact_penalty,
        steps=config.load_steps,
        max_iterations=config.max_iterations,
    )
    springs = out.pop("springs")
    if write and solution.tagged.mesh.comm.rank == 0:
        springs.write_outputs(scene.output.dir)
    return out


def result(config: JointsConfig, scene: Any, results: dict[str, Any]) -> list[str]:
    """The result block's lines: how far the load went and the joints' states."""
    from geofrac.headline import quantity

    got = results.get("joints")
    if got is None or "joints" not in got:
        return []
    state = (
        f"converged to load factor {got['factor']:.4g}"
        if got["converged"]
        else f"NOT CONVERGED beyond load factor {got['factor']:.4g}"
    )
    j, length = got["joints"], scene.units.of("length")
    return [
        f"joints ({', '.join(j['groups'])}): {state}; {j['pairs']} node pairs, "
        f"{j['slipping']} slipping, {j['open']} open; largest slip "
        f"{quantity(j['max_slip'], length)}, largest opening {quantity(j['max_opening'], length)}"
    ]
