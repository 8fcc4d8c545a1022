"""Effect ``cracking``: sequentially linear crack propagation (Edo (2016), ch. 2 and §3.3).

Crack sites are the element edges (elements whose :class:`~geofrac.elements.spec.ElementSpec`
has ``cracking == "edges"``; chapter 2) or, for ``cracking == "grains"`` (``efmm``), the
grain interfaces: each mesh edge ij owns the interface between the
integration domains (grains) of nodes i and j (§3.3, docs/granular.md).

Scene table ``[cracking]`` (all keys optional; docs/scenes.md has the reference):

- ``method``: ``"sequentially-linear"`` (the only one): Edo (2016), Fig. 2.6.
- ``max_events`` (100): the run ends after this many crack events; 0 solves once with
  the initial crack state (the patch test) and reports the displacement error (2.22)
  when the scene has an ``[exact]`` solution.
- ``energy_drop``: end when the strain energy falls below (1 - energy_drop) times its
  peak so far (Edo (2016): "until the strain energy of the whole body decreases"); off if absent.
- ``neighbours`` (10), ``margin`` (1.1), ``max_radius_factor`` (8): MLS neighbourhood
  (docs/cracking.md).
- ``mls_gradient`` (``"fit"``): the MLS cells' strain: ``"fit"``, the gradient of each
  cell's own fit (Edo (2016), eq. 2.19); ``"consistent"``, the gradient of the divergence
  theorem over the cell's edges, with one trace per edge shared by its two cells, which
  passes the patch test in stress (:mod:`geofrac.fracture.consistent`; docs/cracking.md,
  "Integration-consistent MLS cells"). CST (``p1``) only.
- ``precracked`` ([]): facet groups cracked before loading (a notch, DFN ``fractures``).
  With ``efmm`` a group is a straight line of edges (an embedded notch): the interfaces
  between its nodes and the nodes on its left side crack, so the grains on the two sides
  separate along it.
- ``precracked_fraction`` (0): a random fraction of the interior crack sites that do not
  touch a Dirichlet node, cracked before loading (Edo (2016), §3.6: 0.04 of the interfaces),
  drawn with ``precrack_seed`` (0).
- ``switch`` (``"patch"``; ``efmm`` only): which nodes a cracked interface switches to
  C-MultiMLSM: ``"patch"`` the vertices of the triangles it crosses, ``"grain"`` only
  the two nodes whose grains it separates (the thesis's literal rule, docs/granular.md).
- ``criterion`` (``"direction"``; ``"principal"``, the only one, for grain interfaces):
  which edge cracks.
  ``"direction"``: a crack tip grows, when the largest σ1 of the edges within
  ``averaging_radius`` of it (default: twice the mean length of its edges) reaches f_t,
  along the edge that follows the direction of the stress averaged over that radius;
  new cracks start where an edge's σ1 reaches f_t, on the edge there most nearly
  across σ1;
  ``"traction"``: n·σ·n on every edge; ``"principal"``: Edo (2016), §2.3.2, σ1 at the
  edge's midpoint (docs/cracking.md, "Mesh dependence").
- ``mls_region``: ``[x0, y0, x1, y1]``: cells whose centroid is inside use MLS from the
  start (the patch test's core).
- ``control``: the group whose load each event scales and whose displacement and force
  the event log reports: a ``[[bc]]`` group with a non-zero prescribed displacement
  (displacement control), or a ``[[load]]`` group of type traction, pressure or point
  (force control; a body force cannot). Default: the first ``[[bc]]`` with a non-zero
  value, else the first such ``[[load]]``. Every load and prescribed displacement of the
  scene scales with r either way, except those named in ``constant``
  (docs/cracking.md, "Loads that drive the events"). With ``[[stages]]``: ``"release"``,
  the default and only value: λ scales each stage's excavation release (docs/insitu.md,
  "Stages in a cracking scene").
- ``control_point``: ``[x, y]``, force control only: report the displacement of the
  mesh node nearest to this point along the control load's resultant instead of the
  load's work-conjugate displacement.
- ``edges_per_event`` (1), ``batch_tolerance`` (0): crack up to ``edges_per_event`` edges
  with r ≤ (1 + batch_tolerance) r_min in one event.
- ``solver`` (``"update"``): ``"update"`` keeps one factorisation and corrects its
  solution exactly for the cells changed since (Woodbury on the touched DOFs), and
  refactorises when more than ``update_dofs`` (2000) DOFs were touched or a piece is cut
  free; ``"reuse"`` keeps one factorisation as preconditioner of CG and refactorises when
  CG needs more than ``reuse_iterations`` (30); ``"refactor"`` factorises every event
  (the reference).
- ``output_every``: write a frame of the XDMF series every this many events (default
  max_events / 50).
- ``face``, ``face_origin`` (0): report where the crack first reaches the facet group
  ``face``, as x minus ``face_origin`` (the notched beam's ``crack_top_x_mm``); on
  ``efmm`` only the crack joined to the notch (or to the first event's interface) counts.
- ``face_band``: ``[low, high]`` (with ``face``): the range of that x a reference gives
  (an experiment's band); the result block says whether the crack reached the face
  inside it, or how far outside.
- ``contact`` (false): the two faces of every cracked edge are in contact when they
  close: no interpenetration, Coulomb friction, joint slip events (docs/cracking.md,
  "Crack faces in contact"). Element edges only.
- ``friction`` (0.6), ``cohesion`` (0): μ and c of the faces of new cracks, and of
  pre-existing ones without a ``joints`` entry.
- ``[cracking.joints.NAME]`` with ``friction``, ``cohesion``: the faces of the
  ``precracked`` group NAME or of the DFN fracture set NAME.
- ``contact_penalty`` (100): stiffness of closed faces in units of E / edge length.
- ``contact_iterations`` (30): active-set iterations per event; a state that has not
  settled by then ends the run (``end_reason = "contact"``).

Material ``cohesion`` (and ``friction_angle``, degrees) adds shear events: an intact edge
cracks in shear when the traction on it reaches |τ| = c − σn tan φ (σn > 0 in tension).

Material ``fracture_energy`` (G_f > 0, force/length: energy per unit crack area, e.g.
N/mm) makes cracks quasi-brittle: an edge cracked in tension keeps cohesive springs
across its faces that soften over a saw-tooth dissipating G_f per unit area, one
``"soften"`` event per tooth (docs/cracking.md, "Fracture energy"). Element edges only;
without it every run is brittle as before.

- ``teeth`` (10; with ``fracture_energy`` only): teeth N ≥ 2 of the saw-tooth.
- ``constant`` ([]): ``[[load]]`` groups (traction, pressure, point; ``"body_force"``
  for the body-force loads) and ``[[bc]]`` groups whose loads and prescribed
  displacements stay at their full value through the run while the others (the
  control group's among them) scale with the event's factor λ (DeJong, Hendriks and
  Rots (2008); docs/cracking.md, "Loads that do not scale together"). Not the control
  group; element edges only; not with ``contact`` or ``fracture_energy``.

The event loop is :class:`geofrac.fracture.driver.CrackDriver`, composed of the edge or
grain variant by the element's ``cracking`` mode; this module only validates, words the
run's result block (:func:`result`, the end reasons in :data:`END_SENTENCES`), and is
cheap to import.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING, Any

from geofrac import elements
from geofrac.effects import ConfigureContext
from geofrac.elements.kinematics import KINDS
from geofrac.fracture import CRITERION_NAMES, SOLVERS
from geofrac.fracture.config import CrackingConfig, JointProperties
from geofrac.fracture.consistent import GRADIENTS
from geofrac.fracture.control import FORCE_LOADS, RELEASE
from geofrac.model.errors import SceneError, did_you_mean
from geofrac.model.table import finite, short

if TYPE_CHECKING:
    from mpi4py import MPI

    from geofrac.fem.solution import Solution
    from geofrac.fracture.context import JsonValue
    from geofrac.fracture.driver import CrackDriver
    from geofrac.model.scene import Scene

__all__ = [
    "CONTACT_KEYS",
    "END_SENTENCES",
    "FORCE_LOADS",
    "KEYS",
    "LIMITS",
    "STRAIGHT_CELLS",
    "CrackingConfig",
    "configure",
    "driver",
    "end_sentence",
    "make_driver",
    "result",
    "scene_driver",
]

#: MLS-cracked cells and the crack geometry assume straight cell edges: the loader refuses
#: this effect on curved (second-order) geometry.
STRAIGHT_CELLS = True
#: Keys of ``[cracking]`` that apply with ``contact = true`` only.
CONTACT_KEYS = ("friction", "cohesion", "joints", "contact_penalty", "contact_iterations")
#: Keys of the ``[cracking]`` table.
KEYS = (
    "method",
    "max_events",
    "energy_drop",
    "neighbours",
    "margin",
    "max_radius_factor",
    "mls_gradient",
    "precracked",
    "mls_region",
    "control",
    "control_point",
    "edges_per_event",
    "batch_tolerance",
    "solver",
    "reuse_iterations",
    "update_dofs",
    "output_every",
    "face",
    "face_origin",
    "face_band",
    "precracked_fraction",
    "precrack_seed",
    "switch",
    "criterion",
    "averaging_radius",
    "contact",
    *CONTACT_KEYS,
    "teeth",
    "constant",
)

#: Keys of a ``[cracking.joints.NAME]`` table.
JOINT_KEYS = ("friction", "cohesion")


#: Upper limits of the open-ended keys (``max_events``: the size cap of
#: :mod:`geofrac.scene.size`, 1e6, applies first unless ``--allow-large``).
LIMITS: dict[str, float] = {
    "max_events": 1e9,
    "neighbours": 1000,
    "margin": 10.0,
    "max_radius_factor": 1000.0,
    "edges_per_event": 1e6,
    "batch_tolerance": 1.0,
    "reuse_iterations": 1e5,
    "output_every": 1e9,
    "precrack_seed": 2**63 - 1,
    "face_origin": 1e12,
    "friction": 10.0,
    "cohesion": 1e15,
    "contact_penalty": 1e8,
    "contact_iterations": 1000,
    "teeth": 10000,
}


def _number(
    table: dict[str, Any],
    file: str,
    key: str,
    default: Any,
    kind: type,
    lo: float,
    hi: float = float("inf"),
    closed: bool = True,
    prefix: str = "",
) -> Any:
    value = table.get(key, default)
    if value is None:
        return None
    hi = min(hi, LIMITS.get(key, hi))
    ok = isinstance(value, int | float) and not isinstance(value, bool) and finite(value)
    if kind is int:
        ok = ok and isinstance(value, int)
    if not ok or not (lo <= value if closed else lo < value) or not value <= hi:
        low = f"{'≥' if closed else '>'} {lo:g}" if lo != -float("inf") else ""
        high = f"≤ {hi:g}" if hi != float("inf") else ""
        span = " and ".join(s for s in (low, high) if s)
        what = "an integer" if kind is int else "a finite number"
        raise SceneError(
            file, f"cracking.{prefix}{key}", f"must be {what} {span}, got {short(value)}"
        )
    return kind(value)


def _face_band(table: dict[str, Any], file: str, face: str | None) -> tuple[float, float] | None:
    """``cracking.face_band``: ``[low, high]`` of the x where the crack reaches ``face``."""
    band = table.get("face_band")
    if band is None:
        return None
    if face is None:
        raise SceneError(file, "cracking.face_band", "needs cracking.face (the group it is of)")
    if (
        not isinstance(band, list)
        or len(band) != 2
        or not all(isinstance(v, int | float) and not isinstance(v, bool) for v in band)
        or not all(finite(v) for v in band)
        or band[0] > band[1]
    ):
        raise SceneError(
            file, "cracking.face_band", f"must be [low, high] with low <= high, got {short(band)}"
        )
    return float(band[0]), float(band[1])


def _joint(file: str, prefix: str, table: Any, default: JointProperties) -> JointProperties:
    """μ and c of one face table (``[cracking]`` itself or a ``joints`` entry)."""
    return JointProperties(
        _number(table, file, "friction", default.friction, float, 0.0, prefix=prefix),
        _number(table, file, "cohesion", default.cohesion, float, 0.0, prefix=prefix),
    )


def _contact(table: dict[str, Any], ctx: ConfigureContext, precracked: list[str]) -> dict[str, Any]:
    """The contact settings of ``[cracking]`` (the keys of :data:`KEYS` after ``switch``)."""
    file = ctx.file
    contact = table.get("contact", False)
    if not isinstance(contact, bool):
        raise SceneError(file, "cracking.contact", f"must be true or false, got {short(contact)}")
    faces = _joint(file, "", table, JointProperties(0.6, 0.0))
    raw = table.get("joints", {})
    if not isinstance(raw, dict):
        raise SceneError(file, "cracking.joints", "must be a table of [cracking.joints.NAME]")
    dfn = ctx.previous.get("dfn")
    sets = [s.name for s in getattr(dfn, "sets", ())]
    network = getattr(dfn, "network", None)
    if network is not None:  # a network read from dfn.file: its sets
        sets += list(network.set_names)
    joints = []
    for name, entry in raw.items():
        if name not in precracked and name not in sets:
            raise SceneError(
                file,
                f"cracking.joints.{name}",
                "names no 'precracked' group or DFN fracture set"
                + did_you_mean(name, [*precracked, *sets]),
            )
        if not isinstance(entry, dict):
            raise SceneError(file, f"cracking.joints.{name}", "must be a table")
        for key in entry:
            if key not in JOINT_KEYS:
                raise SceneError(
                    file,
                    f"cracking.joints.{name}.{key}",
                    "unknown key" + did_you_mean(key, JOINT_KEYS),
                )
        joints.append((name, _joint(file, f"joints.{name}.", entry, faces)))
    used = [k for k in CONTACT_KEYS if k in table]
    if used and not contact:
        raise SceneError(file, f"cracking.{used[0]}", "applies with cracking.contact = true only")
    return {
        "contact": contact,
        "crack_faces": faces,
        "joints": tuple(joints),
        "contact_penalty": _number(table, file, "contact_penalty", 100.0, float, 0.0, closed=False),
        "contact_iterations": _number(table, file, "contact_iterations", 30, int, 1),
    }


def _control(table: dict[str, Any], ctx: ConfigureContext) -> tuple[str, str]:
    """The group whose load each event scales, and its kind: "displacement" or "force".

    A ``[[bc]]`` group with a non-zero (or ``exact``) prescribed displacement, else a
    ``[[load]]`` group of a type in :data:`FORCE_LOADS` with a non-zero value. Default:
    the first non-zero ``[[bc]]``, else the first such ``[[load]]``. A scene with
    ``[[stages]]`` is driven by the stages' release: ``"release"`` (the default and the
    only value; the stages' validation refuses its loads and moving conditions).
    """
    file = ctx.file
    if ctx.staged:
        control = table.get("control", RELEASE)
        if control != RELEASE:
            raise SceneError(
                file,
                "cracking.control",
                f"with [[stages]] the events are driven by the stages' release: "
                f"'{RELEASE}' (the default), not {short(control)}",
            )
        return RELEASE, RELEASE
    bc_groups = [bc.group for bc in ctx.bcs]
    nonzero = [bc.group for bc in ctx.bcs if bc.value != "exact" and any(v != 0 for v in bc.value)]
    moving = [*nonzero, *(bc.group for bc in ctx.bcs if bc.value == "exact")]
    forces = [ld.group for ld in ctx.loads if ld.type in FORCE_LOADS]
    default = nonzero[0] if nonzero else (forces[0] if forces else None)
    control = table.get("control", default)
    either = (
        "a [[bc]] group with a non-zero displacement or a traction, pressure or point "
        "[[load]] group"
    )
    if control is None:
        raise SceneError(
            file,
            "cracking.control",
            "no [[bc]] prescribes a non-zero displacement and no [[load]] is a traction, "
            f"pressure or point load, so nothing drives the events; name {either}",
        )
    if not isinstance(control, str):
        raise SceneError(file, "cracking.control", f"must be a group name, got {short(control)}")
    if control in moving:
        return control, "displacement"
    if control in forces:
        load = next(ld for ld in ctx.loads if ld.group == control and ld.type in FORCE_LOADS)
        if load.value != "exact" and all(v == 0 for v in load.value):
            raise SceneError(
                file,
                "cracking.control",
                f"the {load.type} [[load]] on '{control}' is zero: the unit load that each "
                "event scales must push the control group",
            )
        return control, "force"
    if control in ("body_force", "gravity"):
        raise SceneError(
            file,
            "cracking.control",
            f"'{control}': a body force cannot drive the events (it acts on no group, so "
            f"no force or displacement of a group can be reported); name {either}",
        )
    if control in bc_groups:
        raise SceneError(
            file,
            "cracking.control",
            f"the [[bc]] group '{control}' prescribes no non-zero displacement: the unit load "
            "that each event scales must move or push the control group"
            + (f" (groups that do: {', '.join([*nonzero, *forces])})" if nonzero or forces else ""),
        )
    if control in ctx.groups:
        raise SceneError(
            file,
            "cracking.control",
            f"the group '{control}' has neither a [[bc]] nor a [[load]]; name {either}"
            + did_you_mean(control, [*moving, *forces]),
        )
    raise SceneError(
        file,
        "cracking.control",
        f"must name {either}" + did_you_mean(control, [*bc_groups, *forces]),
    )


def _constant(
    table: dict[str, Any], ctx: ConfigureContext, control: str, refused: str | None
) -> tuple[str, ...]:
    """``constant``: the groups whose loads and displacements stay at their full value.

    Each must be a ``[[bc]]`` group or the group of a traction, pressure or point
    ``[[load]]``, or ``"body_force"`` (the body-force loads); not the control group.
    ``refused``: why the scene cannot take constant loads (cohesive faces,
    grain interfaces), or None.
    """
    file = ctx.file
    groups = table.get("constant", [])
    if not isinstance(groups, list) or not all(isinstance(g, str) for g in groups):
        raise SceneError(
            file, "cracking.constant", f"must be a list of group names, got {short(groups)}"
        )
    if not groups:
        return ()
    if refused is not None:
        raise SceneError(file, "cracking.constant", refused)
    bc_groups = [bc.group for bc in ctx.bcs]
    load_groups = [ld.group for ld in ctx.loads if ld.type in FORCE_LOADS]
    known = [*bc_groups, *load_groups]
    if any(ld.type == "body_force" for ld in ctx.loads):
        known.append("body_force")
    for g in groups:
        if g == control:
            raise SceneError(
                file,
                "cracking.constant",
                f"'{g}' is the control group (cracking.control), whose load each event "
                "scales: it cannot be constant",
            )
        if g == "gravity":
            raise SceneError(
                file,
                "cracking.constant",
                "'gravity': the gravity effect's load cannot be held constant yet (it is "
                "not a [[load]]); use a body_force [[load]] and name 'body_force'",
            )
        if g not in known:
            raise SceneError(
                file,
                "cracking.constant",
                f"'{g}' has no [[bc]] and no traction, pressure, point or body_force "
                "[[load]]" + did_you_mean(g, known),
            )
    if len(set(groups)) != len(groups):
        raise SceneError(file, "cracking.constant", f"names a group twice: {short(groups)}")
    return tuple(groups)


def _control_point(table: dict[str, Any], file: str, kind: str) -> tuple[float, float] | None:
    """``control_point`` [x, y]: where a force control's displacement is read, or None."""
    point = table.get("control_point")
    if point is None:
        return None
    if kind != "force":
        raise SceneError(
            file,
            "cracking.control_point",
            "applies when cracking.control names a [[load]] group (force control) only",
        )
    if (
        not isinstance(point, list)
        or len(point) != 2
        or not all(isinstance(c, int | float) and not isinstance(c, bool) for c in point)
        or not all(finite(c) for c in point)
    ):
        raise SceneError(
            file,
            "cracking.control_point",
            f"must be [x, y], two finite numbers, got {short(point)}",
        )
    return float(point[0]), float(point[1])


def _check_basis(file: str, ctx: ConfigureContext) -> None:
    """Refuse conditions that give the vertex DOFs a change of basis (w = Q h).

    The crack driver assembles its cell matrices in the vertex DOFs w. With
    ``gradient_bc = "consistent"`` a constant-value condition on a line holds mixes of an
    element's extra DOFs when it has several (GNT: (G t)_c = 0 mixes θ, εx, εy, γxy)
    unless it is a symmetry condition (docs/elements.md, "Boundary DOFs"). One extra DOF
    (RGNT) never mixes.
    """
    name = elements.get(ctx.element).kinematics
    if name is None or len(KINDS[name].names) == 1 or ctx.gradient_bc != "consistent":
        return
    for i, bc in enumerate(ctx.bcs):
        if bc.value != "exact" and not bc.symmetry and ctx.groups.get(bc.group, 0) >= 1:
            raise SceneError(
                file,
                f"bc[{i}]",
                f"cracking with element '{ctx.element}' needs gradient_bc = 'fixed' or "
                f"symmetry conditions: a held line ('{bc.group}') mixes its vertex DOFs, "
                "which the crack driver cannot assemble",
            )


def configure(table: dict[str, Any], ctx: ConfigureContext) -> CrackingConfig:
    """Validate ``[cracking]`` against the material, element, groups and conditions."""
    file = ctx.file
    for key in table:
        if key not in KEYS:
            raise SceneError(file, f"cracking.{key}", "unknown key" + did_you_mean(key, KEYS))
    if ctx.gdim != 2:
        raise SceneError(file, "effects", "effect 'cracking' is 2D (triangles); the mesh is 3D")
    spec = elements.get(ctx.element)
    if spec.cracking is None:
        supported = [n for n in elements.available() if elements.get(n).cracking is not None]
        raise SceneError(
            file,
            "discretization.element",
            f"effect 'cracking' supports {', '.join(supported)}, not '{ctx.element}'",
        )
    _check_basis(file, ctx)
    ft = getattr(ctx.material, "tensile_strength", None)
    if ft is None:
        raise SceneError(
            file, "material.tensile_strength", "effect 'cracking' needs the tensile strength f_t"
        )
    method = table.get("method", "sequentially-linear")
    if method != "sequentially-linear":
        raise SceneError(
            file, "cracking.method", f"unknown method {short(method)}; use 'sequentially-linear'"
        )
    max_events = _number(table, file, "max_events", 100, int, 0)
    energy_drop = _number(table, file, "energy_drop", None, float, 0.0, 1.0, closed=False)
    precracked = table.get("precracked", [])
    if not isinstance(precracked, list) or not all(isinstance(g, str) for g in precracked):
        raise SceneError(
            file, "cracking.precracked", f"must be a list of group names, got {short(precracked)}"
        )
    for g in precracked:
        if ctx.groups.get(g) != 1:
            raise SceneError(
                file,
                "cracking.precracked",
                f"'{g}' is not a curve group of the geometry"
                + did_you_mean(g, [k for k, d in ctx.groups.items() if d == 1]),
            )
    region = table.get("mls_region")
    if region is not None:
        if (
            not isinstance(region, list)
            or len(region) != 4
            or not all(isinstance(c, int | float) and not isinstance(c, bool) for c in region)
        ):
            raise SceneError(
                file,
                "cracking.mls_region",
                f"must be [x0, y0, x1, y1] with x0 < x1, y0 < y1, got {short(region)}",
            )
        for i, c in enumerate(region):
            if not finite(c):
                raise SceneError(
                    file, "cracking.mls_region", f"entry {i} must be finite, got {short(c)}"
                )
        if region[0] >= region[2] or region[1] >= region[3]:
            raise SceneError(
                file,
                "cracking.mls_region",
                f"must be [x0, y0, x1, y1] with x0 < x1, y0 < y1, got {short(region)}",
            )
        region = tuple(float(c) for c in region)
    control, control_kind = _control(table, ctx)
    control_point = _control_point(table, file, control_kind)
    face = table.get("face")
    if face is not None and (not isinstance(face, str) or face not in ctx.groups):
        raise SceneError(
            file,
            "cracking.face",
            f"unknown group {face!r}" + did_you_mean(str(face), list(ctx.groups)),
        )
    band = _face_band(table, file, face)
    switch = table.get("switch", "patch")
    if switch not in ("patch", "grain"):
        raise SceneError(
            file, "cracking.switch", f"must be 'patch' or 'grain', got {short(switch)}"
        )
    if "switch" in table and spec.cracking != "grains":
        grains = [n for n in elements.available() if elements.get(n).cracking == "grains"]
        raise SceneError(
            file,
            "cracking.switch",
            f"applies to elements cracked at grain interfaces ({', '.join(grains)}) only",
        )
    gradient = table.get("mls_gradient", GRADIENTS[0])
    if not isinstance(gradient, str) or gradient not in GRADIENTS:
        raise SceneError(
            file,
            "cracking.mls_gradient",
            f"must be one of {', '.join(repr(g) for g in GRADIENTS)}, got {short(gradient)}",
        )
    if gradient != GRADIENTS[0] and (spec.cracking != "edges" or spec.kinematics is not None):
        raise SceneError(
            file,
            "cracking.mls_gradient",
            f"'{gradient}' takes the traces of linear element cells (p1, CST), not "
            f"'{ctx.element}': use mls_gradient = 'fit' or element = 'p1'",
        )
    solver = table.get("solver", "update")
    if not isinstance(solver, str) or solver not in SOLVERS:
        raise SceneError(
            file, "cracking.solver", f"must be one of {', '.join(SOLVERS)}, got {short(solver)}"
        )
    contact = _contact(table, ctx, precracked)
    if contact["contact"] and spec.cracking != "edges":
        raise SceneError(
            file, "cracking.contact", f"applies to elements cracked at edges, not '{ctx.element}'"
        )
    if contact["contact"] and solver == "reuse":
        raise SceneError(
            file,
            "cracking.solver",
            "'reuse' (CG) needs a symmetric system; friction on slipping faces makes it "
            "unsymmetric: use 'update' or 'refactor' with contact",
        )
    grains = spec.cracking != "edges"
    criterion = table.get("criterion", "principal" if grains else CRITERION_NAMES[0])
    if not isinstance(criterion, str) or criterion not in CRITERION_NAMES:
        raise SceneError(
            file,
            "cracking.criterion",
            f"must be one of {', '.join(CRITERION_NAMES)}, got {short(criterion)}"
            + did_you_mean(str(criterion), list(CRITERION_NAMES)),
        )
    if grains and (criterion != "principal" or "averaging_radius" in table):
        raise SceneError(
            file,
            "cracking.averaging_radius" if criterion == "principal" else "cracking.criterion",
            f"'{ctx.element}' cracks grain interfaces by the larger σ1 of the two grains "
            "(Edo (2016), eq. 3.8: criterion = 'principal', the only one it has)",
        )
    if "averaging_radius" in table and criterion != "direction":
        raise SceneError(
            file,
            "cracking.averaging_radius",
            f"applies to criterion = 'direction' only, not '{criterion}'",
        )
    shear_c = getattr(ctx.material, "cohesion", None)
    gf = getattr(ctx.material, "fracture_energy", None)
    if gf is not None and spec.cracking != "edges":
        raise SceneError(
            file,
            "material.fracture_energy",
            f"applies to elements cracked at edges, not '{ctx.element}'",
        )
    if "teeth" in table and gf is None:
        raise SceneError(file, "cracking.teeth", "applies with material.fracture_energy only")
    if gf is not None and solver == "reuse":
        raise SceneError(
            file,
            "cracking.solver",
            "'reuse' (CG) does not take the cohesive faces' springs (they use the "
            "contact machinery): use 'update' or 'refactor' with fracture_energy",
        )
    refused = None
    if gf is not None:
        refused = "cohesive faces (material.fracture_energy) do not take constant loads yet"
    elif spec.cracking != "edges":
        refused = f"applies to elements cracked at edges, not '{ctx.element}'"
    elif ctx.staged:
        refused = (
            "does not apply with [[stages]]: the initial stress and the applied part of "
            "the release are the constant load"
        )
    constant = _constant(table, ctx, control, refused)
    return CrackingConfig(
        method=method,
        max_events=max_events,
        energy_drop=energy_drop,
        neighbours=_number(table, file, "neighbours", 10, int, 3),
        margin=_number(table, file, "margin", 1.1, float, 1.0, closed=False),
        max_radius_factor=_number(table, file, "max_radius_factor", 8.0, float, 1.0),
        mls_gradient=gradient,
        precracked=tuple(precracked),
        mls_region=region,
        control=control,
        control_kind=control_kind,
        control_point=control_point,
        edges_per_event=_number(table, file, "edges_per_event", 1, int, 1),
        batch_tolerance=_number(table, file, "batch_tolerance", 0.0, float, 0.0),
        solver=solver,
        reuse_iterations=_number(table, file, "reuse_iterations", 30, int, 1),
        update_dofs=_number(table, file, "update_dofs", 2000, int, 1, 20000),
        output_every=_number(table, file, "output_every", max(1, max_events // 50), int, 1),
        face=face,
        face_origin=_number(table, file, "face_origin", 0.0, float, -float("inf")),
        face_band=band,
        tensile_strength=float(ft),
        precracked_fraction=_number(table, file, "precracked_fraction", 0.0, float, 0.0, 1.0),
        precrack_seed=_number(table, file, "precrack_seed", 0, int, 0),
        switch=switch,
        criterion=criterion,
        averaging_radius=_number(table, file, "averaging_radius", None, float, 0.0, closed=False),
        shear_cohesion=None if shear_c is None else float(shear_c),
        shear_friction_angle=float(getattr(ctx.material, "friction_angle", 0.0)),
        fracture_energy=None if gf is None else float(gf),
        teeth=_number(table, file, "teeth", 10, int, 2),
        constant=constant,
        **contact,
    )


def make_driver(
    config: CrackingConfig,
    solution: Solution,
    say: Callable[[str], None],
    *,
    write: bool = False,
) -> CrackDriver:
    """The event loop of a set-up problem, not yet run.

    The element's ``cracking`` mode (:class:`~geofrac.elements.spec.ElementSpec`) chooses
    the composition: ``"grains"`` the grain variant
    (:data:`~geofrac.fracture.grain_driver.GRAINS`, grain interfaces), ``"edges"`` the
    edge variant (:data:`~geofrac.fracture.driver.EDGES`, element edges).
    ``write``: write the event log, pictures and XDMF series into ``output.dir``.
    """
    from geofrac import elements
    from geofrac.fracture.driver import EDGES, CrackDriver, Variant

    spec = elements.get(solution.scene.discretization.element)
    variant: Variant = EDGES
    if spec.cracking == "grains":
        from geofrac.fracture.grain_driver import GRAINS

        variant = GRAINS
    elif spec.cracking != "edges":
        raise ValueError(f"element {spec.name!r} does not support cracking")
    elif solution.scene.stages:  # removed cells stay void (docs/insitu.md)
        from geofrac.fracture.staged_variant import STAGED_EDGES

        variant = STAGED_EDGES
    return CrackDriver(config, solution, say, write=write, variant=variant)


def driver(
    config: CrackingConfig, solution: Solution, say: Callable[[str], None], *, write: bool
) -> dict[str, JsonValue]:
    """Run the event loop on a set-up problem; return the results (see the driver)."""
    return make_driver(config, solution, say, write=write).run()


def scene_driver(
    scene: Scene, comm: MPI.Comm, say: Callable[[str], None] | None = None
) -> CrackDriver:
    """The driver of a loaded scene with ``cracking``: meshed, compiled, not run, no output.

    For tests and diagnostics that step the crack state themselves
    (docs/grain_tip_stress.py); ``say`` receives the driver's messages (default: none).
    The caller destroys the driver or its problem.
    """
    from geofrac.effects import linear_terms
    from geofrac.elements import make_element
    from geofrac.fem.elastic import make_problem
    from geofrac.fem.solution import Solution
    from geofrac.meshing.distribute import build_mesh

    config = scene.effect_config("cracking", CrackingConfig)
    if config is None:
        raise ValueError(f"scene {scene.name!r} does not declare the effect 'cracking'")
    tagged = build_mesh(scene.geometry, comm)
    element = make_element(scene.discretization.element, tagged.mesh)
    problem = make_problem(tagged, element, scene, terms=linear_terms(scene.effects))
    problem.compile()
    return make_driver(config, Solution(scene, tagged, problem), say or (lambda msg: None))


#: Each end reason of the event loop (:data:`geofrac.fracture.loop.END_REASONS`) in
#: words, for the result block; ``{n}``: the events run, ``{next}``: the event that
#: could not be.
END_SENTENCES: dict[str, str] = {
    "max_events": "max_events reached: {n} events (cracking.max_events)",
    "energy_drop": (
        "energy_drop: at event {n} the strain energy fell below (1 - cracking.energy_drop) "
        "times its peak"
    ),
    "no_tensile_edge": "no_tensile_edge: after event {n} no edge is in tension, the load cracks "
    "nothing more",
    "separated": "separated: the specimen broke into two pieces at event {n}",
    "singular": "singular: at event {next} the stiffness is singular (a piece is free to move)",
    "contact": "contact: at event {next} the crack faces' contact did not settle within "
    "cracking.contact_iterations",
    "stages_done": "stages_done: every stage was applied ({n} events)",
}


def end_sentence(reason: str, events: int, detail: str | None = None) -> str:
    """The end ``reason`` of a run of ``events`` events in words; an unknown one as is.

    ``detail``: the results' ``end_detail``. A ``separated`` run whose unit load still
    stores energy lost its load path another way (the next event would need a load
    beyond reason), and one without events carried nothing from the start: the sentence
    says so and gives the detail.
    """
    if reason == "separated" and events == 0:
        return "separated: the specimen carries no load before the first event" + (
            "" if detail is None else f" ({detail})"
        )
    if reason == "separated" and detail is not None and "strain energy" not in detail:
        return f"separated: after event {events} the specimen no longer carries the load ({detail})"
    return END_SENTENCES.get(reason, reason).format(n=events, next=events + 1)


def result(config: CrackingConfig, scene: Scene, results: dict[str, Any]) -> list[str]:
    """The result block's lines: events, the end, the peak load, where the crack reached.

    The peak load is the largest control force of the event log (``peak_reaction``) in
    the scene's force unit; with ``cracking.face`` the x where the crack reached it
    (``crack_face``), in its length unit, and against ``face_band`` when given.
    """
    from geofrac.headline import band, quantity

    crack = results.get("cracking")
    if crack is None:
        return []
    units, n = scene.units, int(crack["events"])
    modes = ", ".join(f"{k} {v}" for k, v in crack.get("events_by_mode", {}).items() if v)
    lines = [f"cracking: {n} events" + (f" ({modes})" if modes else "")]
    lines.append("end: " + end_sentence(crack["end_reason"], n, crack.get("end_detail")))
    if "peak_reaction" in crack:
        factor = crack.get("peak_load_factor")
        lines.append(
            f"peak load: {quantity(crack['peak_reaction'], units.of('force'))} at event "
            f"{crack['peak_event']}" + ("" if factor is None else f" (load factor {factor:.4g})")
        )
    contact = crack.get("contact")
    if contact:  # the crack faces' state at the end (cracking.contact)
        lines.append(
            f"contact: {contact['pairs']} face pairs at the end: {contact['stick']} stick, "
            f"{contact['slip']} slip, {contact['open']} open"
        )
    face = crack.get("crack_face")
    if face is not None:
        origin = "" if config.face_origin == 0.0 else f" - {config.face_origin:g}"
        if face["x_from_origin"] is None:
            lines.append(f"crack reached '{face['group']}': not in {n} events")
        else:
            length = units.of("length")
            x = quantity(face["x_from_origin"], length)
            lines.append(
                f"crack reached '{face['group']}' at x{origin} = {x} (event {face['event']})"
            )
            if config.face_band is not None:
                low, high = config.face_band
                where = band(face["x_from_origin"], low, high, unit=length)
                lines.append(f"  against the band {low:g} to {quantity(high, length)}: {where}")
    if "displacement_error_l2" in crack:
        lines.append(f"displacement error (2.22): {crack['displacement_error_l2']:.4e}")
    return lines
