"""Effect ``plasticity``: perfect plasticity of MPM particles and of the finite-element solve.

MPM (Edo (2016), §4.3.2): Drucker-Prager of the particles. FEM: an elasto-plastic static
solve (Mohr-Coulomb with tension cut-off or Drucker-Prager, plane strain or 3D, P2 or P3)
that replaces the single elastic solve: :func:`driver` runs :mod:`geofrac.fem.plastic`
(docs/plasticity.md).

Yield function f = β I₁ + √J₂ − k (eqs. 4.39-4.43) with return mapping, the Jaumann rate
(D.30-D.31) applied before each increment: the model :mod:`geofrac.mpm.plasticity` (registry
:data:`geofrac.mpm.constitutive.MODELS`) built from this table. MPM scenes
in 2D (plane strain) and 3D only; the plasticity code is imported only when a scene
declares this effect.

Scene table ``[plasticity]``:

- ``friction_angle``: internal friction angle φ in degrees, required (the landslide of
  Edo (2016) sweeps 8 ... 25);
- ``cohesion``: c >= 0 (default 0, the rain-softened landslide of Edo (2016));
- ``dilatancy_angle``: ψ in degrees, 0 <= ψ <= φ (default 0: no plastic volume change).

FEM scenes only (refused in MPM scenes, whose law is Drucker-Prager with the plane-strain
match):

- ``law``: ``"mohr_coulomb"`` (default) or ``"drucker_prager"``;
- ``match``: Drucker-Prager's match to Mohr-Coulomb, ``plane_strain`` (default),
  ``outer`` or ``inner``;
- ``tension_cutoff``: Mohr-Coulomb's tension cut-off T, 0 <= T <= c cot φ (default: none);
- ``load_steps``: equal increments of the load factor 0 → 1 (default 10);
- ``max_cuts``: halvings of a diverged increment before the run ends (default 4);
- ``max_iterations``: Newton iterations per increment (default 25);
- ``davis``: true: solve with Davis's (1968) associated equivalent of the non-associated
  material (c* = β c, tan φ* = β tan φ, ψ* = φ*, β = cos φ cos ψ / (1 − sin φ sin ψ);
  :mod:`geofrac.plasticity.davis`), in strength reduction with the factored angles
  (default false: the given ψ);
- ``joints``: ``[plasticity.joints.NAME]`` tables with ``friction`` (μ, required) and
  ``cohesion`` (c, default 0), the keys of ``[cracking.joints.NAME]``, and optionally
  ``normal_stiffness`` and ``shear_stiffness`` (kₙ, kₛ in stress per length, as a
  3DEC user's jkn, jks; default ``contact_penalty`` · E / facet size): the curve (2D) or
  surface (3D) group NAME is a joint (cut along when meshed,
  :mod:`geofrac.meshing.split`, unless drawn twice in the geometry), its faces tied by
  Coulomb springs with no tensile strength (:mod:`geofrac.fem.joints`; c and μ divided by
  the trial factor in strength reduction; 3D joints need the P2 element);
- ``contact_penalty``: the joints' spring stiffness in units of E / facet length
  (default 100, as ``cracking.contact_penalty``; needs ``joints``);
- ``strength_reduction``: true: the factor of safety by shear strength reduction
  (:mod:`geofrac.fem.strength_reduction`) instead of one solve at full strength
  (default false); then also
- ``reduction_tolerance``: the bracket width [stable, failed] to stop at, 0 < tol <= 1
  (default 0.01);
- ``reduction_bracket``: [low, high], the first stable and failed trial factors,
  0 < low < high (default [1.0, 2.0]; moved down/up when they are not);
- ``reduction_monitor``: [x, y], the point whose |u| is the second failure indicator
  (default: the largest nodal |u|);
- ``ground_reaction``: a table ``{ probe, group, centre, outer_radius }`` (not with
  ``strength_reduction``): the ground reaction curve of a circular opening, the wall's
  radial displacement at the ``output.probes`` point ``probe`` against the internal
  pressure on ``group`` at every converged load step, beside Salençon's closed form
  (:mod:`geofrac.fem.plastic_outputs`);
- ``gravity_phase``: true: a gravity-loading phase first (the effects' terms, gravity,
  ramped from a stress-free start with the ``[[load]]`` entries off and the ``[[bc]]``
  values held at 0), then the displacements reset (u = 0, the strains' reference 0,
  the stress and plastic strain kept), then the analysis (gravity held, the loads and
  ``[[bc]]`` values ramped); in strength reduction every trial does both (default
  false; not with ``[initial_stress]``, the K0 start being the alternative, nor with
  ``ground_reaction``; the joints keep their jump through the reset);
- ``gravity_steps``: the gravity phase's increments (default ``load_steps``; needs
  ``gravity_phase``).

With ``[[stages]]`` that remove cell groups the stages follow the analysis, each
releasing its share in ``load_steps`` increments (:mod:`geofrac.fem.plastic_stages`);
not with ``strength_reduction``, ``joints`` or ``ground_reaction`` (:func:`check_scene`).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from geofrac.effects import ConfigureContext
from geofrac.model.errors import SceneError, did_you_mean
from geofrac.model.table import Table

__all__ = [
    "END_SENTENCES",
    "FEM_ELEMENTS",
    "FEM_KEYS",
    "GROUND_REACTION_KEYS",
    "JOINT_KEYS",
    "KEYS",
    "LAWS",
    "MATCHES",
    "MAX_COHESION",
    "METHODS",
    "REDUCTION_KEYS",
    "GroundReactionConfig",
    "JointConfig",
    "PlasticityConfig",
    "StrengthReductionConfig",
    "check_scene",
    "configure",
    "driver",
    "joint_tables",
    "make_law",
    "result",
]

#: Methods this effect serves.
METHODS = ("mpm", "fem")
#: Keys of ``[plasticity]`` (the last six for FEM scenes only).
KEYS = (
    "friction_angle",
    "cohesion",
    "dilatancy_angle",
    "law",
    "match",
    "tension_cutoff",
    "load_steps",
    "max_cuts",
    "max_iterations",
    "davis",
    "joints",
    "contact_penalty",
    "strength_reduction",
    "reduction_tolerance",
    "reduction_bracket",
    "reduction_monitor",
    "ground_reaction",
    "gravity_phase",
    "gravity_steps",
)
#: The FEM-only keys.
FEM_KEYS = KEYS[3:]
#: The keys that need ``strength_reduction = true``.
REDUCTION_KEYS = ("reduction_tolerance", "reduction_bracket", "reduction_monitor")
#: Keys of ``[plasticity].ground_reaction``.
GROUND_REACTION_KEYS = ("probe", "group", "centre", "outer_radius")
#: Laws a FEM scene may name.
LAWS = ("mohr_coulomb", "drucker_prager")
#: Drucker-Prager matches.
MATCHES = ("plane_strain", "outer", "inner")
#: Elements the FEM solver is valid for (P1 locks under plastic flow at psi = 0; the
#: enriched and gradient elements have no quadrature-point stress update; P2 and P3
#: reach Prandtl's footing load within 3 %, docs/plasticity.md).
FEM_ELEMENTS = ("p2", "p3")
#: Largest cohesion (stress units; the bound of ``material.E``).
MAX_COHESION = 1e15
#: Keys of a ``[plasticity.joints.NAME]`` table (those of ``[cracking.joints.NAME]``).
JOINT_KEYS = ("friction", "cohesion", "normal_stiffness", "shear_stiffness")


@dataclass(frozen=True)
class JointConfig:
    """One joint group of ``[plasticity.joints.NAME]``.

    Attributes:
        name: the curve (2D) or surface (3D) group (split in the geometry).
        friction: μ = tan φ of the joint.
        cohesion: c of the joint.
        normal_stiffness: kₙ (stress per length), None: the penalty's.
        shear_stiffness: kₛ (stress per length), None: the penalty's.
    """

    name: str
    friction: float
    cohesion: float
    normal_stiffness: float | None = None
    shear_stiffness: float | None = None


@dataclass(frozen=True)
class StrengthReductionConfig:
    """Validated strength-reduction settings.

    Attributes:
        tolerance: the bracket width to stop at.
        low: the first trial factor expected stable.
        high: the first trial factor expected failed.
        monitor: the monitor point (x, y), or None for the largest nodal |u|.
    """

    tolerance: float = 0.01
    low: float = 1.0
    high: float = 2.0
    monitor: tuple[float, ...] | None = None


@dataclass(frozen=True)
class GroundReactionConfig:
    """Validated ground reaction curve settings (docs/scenes.md, ``[plasticity]``).

    Attributes:
        probe: the ``output.probes`` point on the opening's wall.
        group: the wall's boundary group, loaded by ``pressure`` entries only.
        pressure: the sum of the group's ``pressure`` values: the internal pressure
            changes by ``pressure`` times the load factor.
        centre: the opening's centre (x, y): u_r = u·(x − centre)/|x − centre|.
        outer_radius: where the in-situ pressure is held (inf: an infinite medium), for
            the closed form.
    """

    probe: str
    group: str
    pressure: float
    centre: tuple[float, ...] = (0.0, 0.0)
    outer_radius: float = math.inf


@dataclass(frozen=True)
class PlasticityConfig:
    """Validated Drucker-Prager settings.

    Attributes:
        friction_angle: φ in degrees.
        cohesion: c.
        dilatancy_angle: ψ in degrees.
        law: ``mohr_coulomb`` or ``drucker_prager`` (MPM: always the latter).
        match: Drucker-Prager's match (FEM).
        tension_cutoff: Mohr-Coulomb's T, or None (FEM).
        load_steps: load increments (FEM).
        max_cuts: halvings of a diverged increment (FEM).
        max_iterations: Newton iterations per increment (FEM).
        davis: Davis's associated equivalent instead of the given ψ (FEM).
        strength_reduction: the factor of safety's settings, or None (FEM).
        ground_reaction: the ground reaction curve's settings, or None (FEM).
        joints: the split joints' strengths (FEM).
        contact_penalty: the joints' springs in units of E / facet length (FEM).
        gravity_steps: the gravity phase's increments, 0 without a gravity phase (FEM).
    """

    friction_angle: float
    cohesion: float
    dilatancy_angle: float
    law: str = "drucker_prager"
    match: str = "plane_strain"
    tension_cutoff: float | None = None
    load_steps: int = 10
    max_cuts: int = 4
    max_iterations: int = 25
    strength_reduction: StrengthReductionConfig | None = None
    ground_reaction: GroundReactionConfig | None = None
    davis: bool = False
    joints: tuple[JointConfig, ...] = ()
    contact_penalty: float = 100.0
    gravity_steps: int = 0


def configure(table: dict[str, Any], ctx: ConfigureContext) -> PlasticityConfig:
    """Validate ``[plasticity]``."""
    if ctx.gdim == 1:
        raise SceneError(ctx.file, "effects", "'plasticity' needs a 2D or 3D scene")
    t = Table(ctx.file, "plasticity", table, allowed=KEYS)
    phi = float(t.number("friction_angle", required=True))  # type: ignore[arg-type]
    if not 0 <= phi < 90:
        raise t.error("friction_angle", f"must lie in [0, 90) degrees, got {phi}")
    c = float(t.number("cohesion", default=0.0, minimum=0.0, maximum=MAX_COHESION))
    psi = float(t.number("dilatancy_angle", default=0.0))
    if not 0 <= psi <= phi:
        raise t.error("dilatancy_angle", f"must lie in [0, friction_angle = {phi}], got {psi}")
    if ctx.method == "mpm":
        for key in FEM_KEYS:
            if t.has(key):
                raise t.error(key, "applies to FEM scenes only (MPM's law is Drucker-Prager)")
        return PlasticityConfig(phi, c, psi)
    return _fem(t, ctx, phi, c, psi)


def _fem(t: Table, ctx: ConfigureContext, phi: float, c: float, psi: float) -> PlasticityConfig:
    """The FEM keys, and what the elasto-plastic solver needs of the scene."""
    if ctx.gdim == 2 and ctx.material.plane != "strain":
        raise SceneError(ctx.file, "material.plane", 'plasticity needs plane = "strain" in 2D')
    if ctx.element not in FEM_ELEMENTS:
        raise SceneError(
            ctx.file,
            "discretization.element",
            f"plasticity needs one of {', '.join(FEM_ELEMENTS)}: '{ctx.element}' has no "
            "quadrature-point stress update (P1/cst locks under plastic flow at psi = 0)",
        )
    if ctx.gdim == 2 and ctx.material.thickness != 1.0:
        raise SceneError(ctx.file, "material.thickness", "plasticity solves per unit thickness (1)")
    if any(load.type == "point" for load in ctx.loads):
        raise SceneError(ctx.file, "load", "plasticity does not take point loads")
    law = t.string("law", choices=LAWS, default="mohr_coulomb")
    match = t.string("match", choices=MATCHES, default="plane_strain")
    if law == "mohr_coulomb" and t.has("match"):
        raise t.error("match", 'is Drucker-Prager\'s (law = "drucker_prager")')
    if law == "mohr_coulomb" and phi == 0 and c == 0:
        raise t.error("cohesion", "must be > 0 when friction_angle = 0")
    cutoff = None
    if t.has("tension_cutoff"):
        if law != "mohr_coulomb":
            raise t.error("tension_cutoff", 'is Mohr-Coulomb\'s (law = "mohr_coulomb")')
        cutoff = float(t.number("tension_cutoff", minimum=0.0))  # type: ignore[arg-type]
        limit = math.inf if phi == 0 else c / math.tan(math.radians(phi))
        if cutoff > limit:
            raise t.error("tension_cutoff", f"must be <= c cot(phi) = {limit:.6g}, got {cutoff}")
    steps = int(t.number("load_steps", default=10, integer=True, minimum=1, maximum=100_000))
    cuts = int(t.number("max_cuts", default=4, integer=True, minimum=0, maximum=30))
    its = int(t.number("max_iterations", default=25, integer=True, minimum=1, maximum=1000))
    reduction = _reduction(t, ctx)
    ground = _ground_reaction(t, ctx) if t.has("ground_reaction") else None
    if ground is not None and reduction is not None:
        raise t.error("ground_reaction", "does not apply with strength_reduction = true")
    davis = t.boolean("davis", default=False)
    joints = _joints(t, ctx)
    if t.has("contact_penalty") and not joints:
        raise t.error("contact_penalty", "needs plasticity.joints")
    penalty = float(t.number("contact_penalty", default=100.0, positive=True, maximum=1e8))
    gravity = _gravity_phase(t, steps=steps)
    if gravity and ground is not None:
        raise t.error(
            "ground_reaction",
            "does not apply with gravity_phase = true (its closed form starts from an "
            "isotropic in-situ pressure, not from a gravity phase)",
        )
    return PlasticityConfig(
        phi,
        c,
        psi,
        law,
        match,
        cutoff,
        steps,
        cuts,
        its,
        reduction,
        ground,
        davis,
        joints,
        penalty,
        gravity,
    )


def _gravity_phase(t: Table, *, steps: int) -> int:
    """``gravity_phase`` and ``gravity_steps``: the gravity phase's increments, or 0."""
    if not t.boolean("gravity_phase", default=False):
        if t.has("gravity_steps"):
            raise t.error("gravity_steps", "needs gravity_phase = true")
        return 0
    return int(t.number("gravity_steps", default=steps, integer=True, minimum=1, maximum=100_000))


def _ground_reaction(t: Table, ctx: ConfigureContext) -> GroundReactionConfig:
    """``ground_reaction``: the group must carry numeric ``pressure`` loads only."""
    g = Table(
        ctx.file, t.path("ground_reaction"), t.data["ground_reaction"], allowed=GROUND_REACTION_KEYS
    )
    probe = g.string("probe")
    group = g.string("group")
    if ctx.groups.get(group) != ctx.gdim - 1:
        raise g.error("group", f"'{group}' is not a boundary group (dimension {ctx.gdim - 1})")
    mine = [load for load in ctx.loads if load.group == group]
    if not mine or any(load.type != "pressure" for load in mine):
        raise g.error("group", f"'{group}' must carry [[load]] entries of type 'pressure' only")
    values = [load.value[0] for load in mine]
    if not all(isinstance(v, int | float) for v in values):
        raise g.error("group", f"the pressure on '{group}' must be a number, not an expression")
    centre = g.vector("centre", ctx.gdim, g.data.get("centre", [0.0] * ctx.gdim))
    outer = float(g.number("outer_radius", default=math.inf, positive=True))
    return GroundReactionConfig(probe, group, float(sum(values)), centre, outer)  # type: ignore[arg-type]


def check_scene(
    config: PlasticityConfig,
    *,
    file: str,
    probes: dict[str, tuple[float, ...]],
    initial: Any,
    fields: tuple[str, ...] = (),
    effects: tuple[str, ...] = ("gravity",),
    staged: bool = False,
) -> None:
    """The checks that need the whole scene (FEM): output fields, the ground reaction curve.

    ``fields`` (``output.fields``) may not hold ``stress_nodal``: the stress lives at
    quadrature points, written as cell means (``stress``). ``initial``: the scene's
    :class:`~geofrac.model.scene.InitialStress`, or None. The ground reaction curve needs
    a constant initial stress that is isotropic in the plane (σxx = σyy, σxy = 0: the
    in-situ pressure p0 = −σxx) with the wall among its ``loaded`` sides, or none
    (p0 = 0). A gravity phase refuses an initial stress and needs the ``gravity`` effect
    among ``effects`` (the scene's declared effects). ``staged``: the scene has
    ``[[stages]]``, which strength reduction, joints and the ground reaction curve do
    not take yet. Raises SceneError naming the key.
    """
    if staged:
        for key, given in (
            ("strength_reduction", config.strength_reduction is not None),
            ("joints", bool(config.joints)),
            ("ground_reaction", config.ground_reaction is not None),
        ):
            if given:
                raise SceneError(
                    file,
                    f"plasticity.{key}",
                    "does not go with [[stages]] yet (the plastic stages run one analysis "
                    "of the body as excavated); drop one of them",
                )
    if config.gravity_steps and "gravity" not in effects:
        raise SceneError(
            file,
            "plasticity.gravity_phase",
            "needs the 'gravity' effect: without it the gravity phase would load nothing; "
            'add "gravity" to effects (with its [gravity] table) or drop gravity_phase',
        )
    if config.gravity_steps and initial is not None:
        raise SceneError(
            file,
            "plasticity.gravity_phase",
            "does not go with [initial_stress]: they are alternative starts (a K0 initial "
            "stress where the surface is level, or a gravity-loading phase); drop one",
        )
    if "stress_nodal" in fields:
        raise SceneError(
            file,
            "output.fields",
            "'stress_nodal' is not written with plasticity: the stress lives at quadrature "
            "points ('stress' writes its cell means)",
        )
    ground = config.ground_reaction
    if ground is None:
        return
    key = "plasticity.ground_reaction"
    if ground.probe not in probes:
        raise SceneError(
            file, f"{key}.probe", f"'{ground.probe}' is not in output.probes {sorted(probes)}"
        )
    a = math.dist(probes[ground.probe], ground.centre)
    if a <= 0.0:
        raise SceneError(file, f"{key}.centre", "the probe lies at the centre")
    if not ground.outer_radius > a:
        raise SceneError(file, f"{key}.outer_radius", f"must exceed the wall's radius {a:.6g}")
    if initial is None:
        return
    if initial.kind != "constant" or len(initial.stress) != 3:
        raise SceneError(file, key, "needs a constant 2D [initial_stress] (or none)")
    sxx, syy, sxy = initial.stress
    if sxx != syy or sxy != 0.0:
        raise SceneError(
            file,
            key,
            "needs an in-plane isotropic initial stress (xx = yy, xy = 0), got "
            f"{list(initial.stress)}",
        )
    if ground.group not in initial.loaded:
        raise SceneError(
            file, key, f"the wall '{ground.group}' must be in initial_stress.loaded (it carries p0)"
        )


def _joints(t: Table, ctx: ConfigureContext) -> tuple[JointConfig, ...]:
    """The ``[plasticity.joints.NAME]`` tables."""
    raw = t.data.get("joints", {})
    if not isinstance(raw, dict):
        raise t.error("joints", "must be a table of [plasticity.joints.NAME]")
    return joint_tables(raw, ctx, prefix="plasticity.joints")


def joint_tables(
    raw: dict[str, Any], ctx: ConfigureContext, *, prefix: str
) -> tuple[JointConfig, ...]:
    """Joint tables ``[PREFIX.NAME]``: curve (2D) or surface (3D) groups, μ, c, kₙ, kₛ.

    Shared with the ``joints`` effect (``prefix = "joints"``).

    Raises:
        SceneError: a NAME that is no group of dimension gdim − 1, or a bad value.
    """
    out = []
    curves = [g for g, d in ctx.groups.items() if d == ctx.gdim - 1]
    what = "curve" if ctx.gdim == 2 else "surface"
    for name, entry in raw.items():
        if ctx.groups and name not in curves:
            raise SceneError(
                ctx.file,
                f"{prefix}.{name}",
                f"names no {what} group of the geometry" + did_you_mean(name, curves),
            )
        j = Table(ctx.file, f"{prefix}.{name}", entry, allowed=JOINT_KEYS)
        mu = float(j.number("friction", required=True, minimum=0.0, maximum=10.0))  # type: ignore[arg-type]
        cj = float(j.number("cohesion", default=0.0, minimum=0.0, maximum=MAX_COHESION))
        kn, ks = (
            j.number(k, positive=True, maximum=MAX_COHESION) if j.has(k) else None
            for k in ("normal_stiffness", "shear_stiffness")
        )
        out.append(JointConfig(str(name), mu, cj, kn, ks))
    return tuple(out)


def _reduction(t: Table, ctx: ConfigureContext) -> StrengthReductionConfig | None:
    """The strength-reduction keys (only with ``strength_reduction = true``)."""
    if not t.boolean("strength_reduction", default=False):
        for key in REDUCTION_KEYS:
            if t.has(key):
                raise t.error(key, "needs strength_reduction = true")
        return None
    tol = float(t.number("reduction_tolerance", default=0.01, positive=True, maximum=1.0))
    low, high = t.vector("reduction_bracket", 2, t.data.get("reduction_bracket", [1.0, 2.0]))
    if not 0 < low < high:
        raise t.error("reduction_bracket", f"needs 0 < low < high, got [{low}, {high}]")
    monitor = None
    if t.has("reduction_monitor"):
        monitor = t.vector("reduction_monitor", ctx.gdim)
    return StrengthReductionConfig(tol, low, high, monitor)


def driver(
    config: PlasticityConfig, solution: Any, say: Callable[[str], None], *, write: bool
) -> dict[str, Any]:
    """FEM scenes: the elasto-plastic load-stepped solve replaces the elastic one."""
    from geofrac.fem.plastic_driver import run

    mat = solution.scene.material
    law = make_law(config, E=mat.E, nu=mat.nu)
    if config.strength_reduction is not None:
        from geofrac.fem.plastic_driver import run_reduction

        return run_reduction(
            law,
            solution,
            say,
            config=config.strength_reduction,
            write=write,
            steps=config.load_steps,
            max_cuts=config.max_cuts,
            max_iterations=config.max_iterations,
            joints=config.joints,
            penalty=config.contact_penalty,
            gravity_steps=config.gravity_steps,
        )
    return run(
        law,
        solution,
        say,
        write=write,
        ground=config.ground_reaction,
        steps=config.load_steps,
        max_cuts=config.max_cuts,
        max_iterations=config.max_iterations,
        joints=config.joints,
        penalty=config.contact_penalty,
        gravity_steps=config.gravity_steps,
    )


def make_law(config: PlasticityConfig, *, E: float, nu: float) -> Any:
    """The :mod:`geofrac.plasticity` law of a validated FEM ``[plasticity]`` table."""
    from geofrac.plasticity import DruckerPrager, MohrCoulomb
    from geofrac.plasticity.davis import Davis

    common = {
        "E": E,
        "nu": nu,
        "cohesion": config.cohesion,
        "friction_angle": config.friction_angle,
        "dilatancy_angle": config.dilatancy_angle,
    }
    if config.davis:
        return Davis(**common, law=config.law, tension=config.tension_cutoff, match=config.match)
    if config.law == "mohr_coulomb":
        return MohrCoulomb(**common, tension=config.tension_cutoff)
    return DruckerPrager(**common, match=config.match)


#: The plastic analysis's end reasons (``plasticity.end_reason``) in words; ``{f}``: the
#: last converged factor.
END_SENTENCES: dict[str, str] = {
    "converged": "converged to load factor {f:.4g}",
    "step_too_small": "NOT CONVERGED: the increment beyond load factor {f:.4g} diverged "
    "(step_too_small)",
    "gravity_step_too_small": "NOT CONVERGED: the body cannot carry its own weight "
    "(gravity_step_too_small; the analysis was not run)",
    "stage_step_too_small": "NOT CONVERGED: a stage could not be applied in full "
    "(stage_step_too_small; the later stages were not run)",
}


def result(config: PlasticityConfig, scene: Any, results: dict[str, Any]) -> list[str]:
    """The result block's lines of an FEM plastic analysis (none for MPM).

    The factor of safety (strength reduction), or how far the load went, the plastic
    points and yielded area; the joints' states (pairs slipping and open, the largest
    slip and opening); the ground reaction against its closed form; each stage's.
    """
    from geofrac.headline import quantity, versus

    plastic = results.get("plasticity")
    if plastic is None:
        return []
    units = scene.units
    if "factor_of_safety" in plastic:
        last = plastic["last_stable"]
        return [
            f"factor of safety: {plastic['factor_of_safety']:.4g} (stable at "
            f"{plastic['stable']:.4g}, failed at {plastic['failed']:.4g}; tolerance "
            f"{plastic['tolerance']:g})",
            f"at the last stable factor: {last['plastic_points']} plastic points, yielded area "
            f"{quantity(last['yielded_area'], units.of('area'))}",
        ]
    reason = plastic["end_reason"]
    lines = [
        f"plasticity ({plastic['law']}): "
        + END_SENTENCES.get(reason, reason).format(f=plastic["factor"])
        + f"; {plastic['plastic_points']} plastic points, yielded area "
        f"{quantity(plastic['yielded_area'], units.of('area'))}"
    ]
    joints = plastic.get("joints")
    if joints is not None:
        length = units.of("length")
        lines.append(
            f"joints ({', '.join(joints['groups'])}): {joints['pairs']} node pairs, "
            f"{joints['slipping']} slipping, {joints['open']} open; largest slip "
            f"{quantity(joints['max_slip'], length)}, largest opening "
            f"{quantity(joints['max_opening'], length)}"
        )
    ground = plastic.get("ground_reaction")
    if ground is not None:
        final, length = ground["final"], units.of("length")
        text = (
            f"ground reaction at '{ground['probe']}': u_r {quantity(final['u_r'], length)} at "
            f"p_i {quantity(final['p_i'], units.of('stress'))}"
        )
        exact = final.get("u_r_closed_form")
        if exact is not None:
            text += (
                f" (closed form {quantity(exact, length)}, {versus(final['u_r'], exact, length)})"
            )
        lines.append(text)
    for stage in plastic.get("stages", []):
        state = "" if stage["converged"] else f", NOT CONVERGED at {stage['factor']:.4g} of it"
        lines.append(
            f"stage {stage['index']} '{stage['name']}': max |u| "
            f"{quantity(stage['max_displacement'], units.of('length'))}{state}"
        )
    return lines
