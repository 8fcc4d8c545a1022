"""Effect ``gravity``: self-weight ρ·g as a body force on the whole domain.

Scene table ``[gravity]`` (optional): ``acceleration`` = vector of length gdim,
default ``[-9.81]`` in 1D (MPM bars), ``[0, -9.81]`` in 2D and ``[0, 0, -9.81]`` in 3D;
MPM scenes only: ``ramp`` = seconds over which gravity rises linearly from 0 to
``acceleration`` (default 0: full gravity from the start), for quasi-static starts.
Needs ``material.density``.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from geofrac.effects import ConfigureContext
from geofrac.model.errors import SceneError, did_you_mean
from geofrac.model.table import finite, short

if TYPE_CHECKING:
    import ufl

    from geofrac.fem.elastic import FormContext

__all__ = [
    "KEYS",
    "MAX_ACCELERATION",
    "MAX_RAMP",
    "METHODS",
    "GravityConfig",
    "configure",
    "linear_form",
]

#: Gravity is a body force in FEM scenes and a nodal force per mass in MPM scenes.
METHODS = ("fem", "mpm")
#: Largest magnitude of an acceleration component (1e6 g: far beyond any planet).
MAX_ACCELERATION = 1e7
#: Longest gravity ramp (seconds, any unit system).
MAX_RAMP = 1e15
#: Keys of ``[gravity]``.
KEYS = ("acceleration", "ramp")


@dataclass(frozen=True)
class GravityConfig:
    """Validated gravity settings.

    Attributes:
        acceleration: gravitational acceleration, shape=(gdim,).
        density: mass density taken from the material.
        ramp: MPM: gravity rises linearly from 0 at t = 0 to ``acceleration`` at
            t = ``ramp`` (0: full gravity from the start).
    """

    acceleration: tuple[float, ...]
    density: float
    ramp: float = 0.0


def configure(table: dict[str, Any], ctx: ConfigureContext) -> GravityConfig:
    """Validate ``[gravity]``; requires ``material.density``."""
    for key in table:
        if key not in KEYS:
            raise SceneError(ctx.file, f"gravity.{key}", "unknown key" + did_you_mean(key, KEYS))
    density = getattr(ctx.material, "density", None)
    if density is None:
        raise SceneError(ctx.file, "material.density", "effect 'gravity' needs the mass density")
    default = [0.0] * (ctx.gdim - 1) + [-9.81]
    g = table.get("acceleration", default)
    if (
        not isinstance(g, list)
        or len(g) != ctx.gdim
        or not all(isinstance(c, int | float) and not isinstance(c, bool) for c in g)
    ):
        raise SceneError(
            ctx.file,
            "gravity.acceleration",
            f"must be a list of {ctx.gdim} numbers, got {short(g)}",
        )
    for i, c in enumerate(g):
        if not finite(c) or abs(c) > MAX_ACCELERATION:
            raise SceneError(
                ctx.file,
                "gravity.acceleration",
                f"entry {i} must be finite and at most {MAX_ACCELERATION:.0e} in magnitude, "
                f"got {short(c)}",
            )
    ramp = table.get("ramp", 0.0)
    if "ramp" in table:
        if ctx.method != "mpm":
            raise SceneError(
                ctx.file, "gravity.ramp", "applies to MPM scenes only (an FEM solve is static)"
            )
        if (
            not isinstance(ramp, int | float)
            or isinstance(ramp, bool)
            or not finite(ramp)
            or not 0 <= ramp <= MAX_RAMP
        ):
            raise SceneError(
                ctx.file,
                "gravity.ramp",
                f"must be a number of seconds in [0, {MAX_RAMP:g}], got {short(ramp)}",
            )
    return GravityConfig(
        acceleration=tuple(float(c) for c in g), density=float(density), ramp=float(ramp)
    )


def linear_form(config: GravityConfig, ctx: FormContext) -> ufl.Form:
    """Right-hand side t·∫ ρ g·v dx (``ctx`` is a :class:`geofrac.fem.elastic.FormContext`).

    ρ is ``material.density``, or the context's density field when it has one (a scene
    with an initial stress or stages: a density per cell group, zero in excavated cells).
    """
    from geofrac_forms.elasticity import body_force_form

    density = ctx.density if ctx.density is not None else ctx.constant(config.density)
    return body_force_form(ctx.v, density * ctx.vector(config.acceleration), ctx.thickness, ctx.dx)
