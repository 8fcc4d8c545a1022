"""Validated scene: frozen dataclasses that the rest of geofrac reads.

A :class:`Scene` is what :func:`geofrac.scene.load_scene` returns after every check
has passed; nothing downstream re-validates user input. All paths are absolute.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from types import ModuleType
from typing import Any, Literal, Protocol

__all__ = [
    "BED_REPRESENTATIONS",
    "BlocksSpec",
    "Body",
    "BoundaryCondition",
    "Discretization",
    "EffectSpec",
    "ExactSpec",
    "Geometry",
    "GeometryBuilder",
    "InitialStress",
    "Line",
    "Load",
    "Material",
    "MpmSpec",
    "Output",
    "ParticleSource",
    "Scene",
    "Solver",
    "Stage",
    "Units",
    "acts",
    "effect_config",
]

#: Scene schema version this code reads.
SCHEMA_VERSION = 1


class GeometryBuilder(Protocol):
    """Makes the gmsh model of a scene on one rank (an effect's or the terrain's)."""

    @property
    def name(self) -> str:
        """Name used in messages."""
        ...

    def build(self, gmsh: ModuleType) -> tuple[dict[str, Any], object]:
        """Create and mesh the model in ``gmsh``; a JSON-ready report and a payload."""
        ...


@dataclass(frozen=True)
class Geometry:
    """Where the mesh comes from: a gmsh file, or a builder provided by an effect.

    Attributes:
        file: gmsh ``.geo`` (or ``.msh``) file, or None when ``builder`` makes the model.
        parameters: values for the ``DefineConstant`` entries of the ``.geo`` file.
        mesh_size: upper bound on the element size (gmsh ``Mesh.MeshSizeMax``), or None.
        algorithm: gmsh 2D algorithm (a key of :data:`geofrac.meshing.geo.ALGORITHMS`)
            overriding the ``.geo`` file's ``Mesh.Algorithm``, or None (the file's own).
        dim: topological dimension of the meshed domain (2 or 3), read from the file.
        groups: physical group name -> dimension, read from the file (or declared by the
            builder).
        builder: None, or a :class:`GeometryBuilder` (``name``, ``build(gmsh) -> (report,
            payload)``) that creates and meshes the gmsh model on one rank (the ``dfn`` effect's
            :class:`~geofrac.effects.dfn.DfnGeometry`): ``report`` is a JSON-ready dict,
            ``payload`` is broadcast to every rank as ``TaggedMesh.fractures``.
        trusted: skip the check that the ``.geo`` file only describes a geometry
            (:mod:`geofrac.meshing.geo_guard`).
        time_limit: seconds gmsh may take to read (check) or read and mesh (run) the
            ``.geo`` file; None: 60 s to read, 600 s to mesh.
        order: polynomial order of the cell geometry, read from the file: 1 straight
            cells, 2 curved (``Mesh.ElementOrder = 2`` in the ``.geo``, or second-order
            elements in a ``.msh``). Only elements with ``ElementSpec.curved`` and a
            degree of at least ``order`` accept ``order > 1`` (docs/elements.md).
        renumber: seed of a random renumbering of the mesh's nodes and cells before it
            is distributed (:func:`geofrac.meshing.distribute.renumber_model`), or None
            (gmsh's numbering); set from ``discretization.renumber``.
        split: curve groups along which the mesh is cut before it is distributed
            (:func:`geofrac.meshing.split.split_model`: each joint node gets one copy per
            side, tips stay whole); set from the ``[plasticity.joints.NAME]`` tables.
    """

    file: Path | None
    parameters: dict[str, float]
    mesh_size: float | None
    dim: int
    groups: dict[str, int]
    builder: GeometryBuilder | None = None
    trusted: bool = False
    time_limit: float | None = None
    order: int = 1
    renumber: int | None = None
    algorithm: str | None = None
    split: tuple[str, ...] = ()


@dataclass(frozen=True)
class Material:
    """Isotropic linear elastic material with optional strength and density.

    Attributes:
        E: Young's modulus.
        nu: Poisson's ratio in (-1, 0.5).
        plane: ``"stress"`` or ``"strain"`` (2D only; ignored in 3D).
        thickness: out-of-plane thickness t (2D), multiplies stiffness and loads.
        density: mass density, or None when the scene needs none.
        tensile_strength: f_t, or None when no effect needs it.
        cohesion: c of the Mohr-Coulomb shear strength c + σn tan φ of intact rock
            (``cracking``: edges crack in shear), or None (no shear events).
        friction_angle: φ in degrees, with ``cohesion`` (0 when absent).
        fracture_energy: G_f, energy per unit crack area (force/length), or None
            (``cracking``: cracked edges soften over a saw-tooth that dissipates G_f
            instead of losing their strength at once).
    """

    E: float
    nu: float
    plane: Literal["stress", "strain"] = "stress"
    thickness: float = 1.0
    density: float | None = None
    tensile_strength: float | None = None
    cohesion: float | None = None
    friction_angle: float = 0.0
    fracture_energy: float | None = None


@dataclass(frozen=True)
class Discretization:
    """Element choice.

    Attributes:
        element: registry name (see :mod:`geofrac.elements`).
        quadrature_degree: forced quadrature degree for the stiffness, or None (exact).
        zero_mode_penalty: α of the Hughes–Brezzi-type penalty α μ t ∫ (g - d(u))² that
            removes the zero-energy modes of RGNT, GNT and RGNQ (dimensionless; the
            per-element default is the element's ``ElementSpec.zero_mode_penalty``;
            0 for the other elements, which have none).
        gradient_bc: how a Dirichlet condition acts on the extra vertex DOFs of RGNT, GNT
            and RGNQ. ``"consistent"`` (default): only what the condition implies
            (docs/elements.md, "Boundary DOFs"). ``"fixed"``: they are fixed too, to the
            values that reproduce the exact field (½ its rotation/strain) for
            ``value = "exact"`` and to 0 for a constant value (on rollers this also holds
            what the condition does not imply: GNT's strains along the line).
            ``"free"``: only the translations are fixed; boundary edges may bulge between
            vertices (fails the patch test; kept for comparison, docs/elements.md).
        q_rand: ``efmm`` only: randomness of the integration domains' inner points in
            [0, 1] (Edo (2016), Fig. 3.13); 0 takes the incentres.
        domain_seed: ``efmm`` only: seed of those random points.
        renumber: seed of a random renumbering of the mesh's nodes and cells (the same
            mesh, numbered otherwise), or None: a check that results do not depend on
            the numbering (:attr:`Geometry.renumber`).
    """

    element: str
    quadrature_degree: int | None = None
    zero_mode_penalty: float = 0.0
    gradient_bc: Literal["consistent", "fixed", "free"] = "consistent"
    q_rand: float = 0.0
    domain_seed: int = 0
    renumber: int | None = None


@dataclass(frozen=True)
class ExactSpec:
    """A named analytical solution with its parameters.

    Attributes:
        name: registry name (see :mod:`geofrac.analytic`).
        parameters: its parameters (material constants come from the scene's material).
    """

    name: str
    parameters: dict[str, float]


@dataclass(frozen=True)
class BoundaryCondition:
    """Dirichlet condition on a physical group.

    Attributes:
        group: physical group name (dimension ``dim - 1`` or lower).
        value: prescribed values, one per component, or ``"exact"``.
        components: indices of the constrained components, shape=(len(value),).
        symmetry: the group is a mirror-symmetry line/plane: the one held component is
            its normal, and vertex-DOF elements (RGNT, GNT, RGNQ) also hold what mirror
            symmetry implies for their gradient DOFs (docs/elements.md).
        switch_on: the stage at whose start the support is installed (``from``),
            holding its DOFs at their current displacement plus ``value``; None: from
            the initial step (docs/insitu.md, "Loads and supports per stage").
        switch_off: the stage at whose start it is removed (``until``), or None.
    """

    group: str
    value: tuple[float, ...] | Literal["exact"]
    components: tuple[int, ...]
    symmetry: bool = False
    switch_on: str | None = None
    switch_off: str | None = None


@dataclass(frozen=True)
class Load:
    """A load term.

    Attributes:
        type: ``"traction"`` (force per area on a boundary group), ``"body_force"``
            (per volume), ``"pressure"`` (scalar normal pressure on a boundary group,
            positive pushing into the body: traction -p n) or ``"point"`` (a force on a
            physical point, dimension 0).
        value: components, shape=(gdim,) (traction, body force, point) or shape=(1,)
            (pressure); each a number or an expression text of x, y, z
            (:mod:`geofrac.model.expr`; not for ``point``); or ``"exact"`` (traction
            σ_exact·n, body force -div σ_exact).
        group: physical group (traction, pressure, point), or None (body force).
        switch_on: the stage at whose start the load is switched on (``from``); None:
            from the initial step (docs/insitu.md, "Loads and supports per stage").
        switch_off: the stage at whose start it is switched off (``until``), or None.
    """

    type: Literal["traction", "body_force", "pressure", "point"]
    value: tuple[float | str, ...] | Literal["exact"]
    group: str | None = None
    switch_on: str | None = None
    switch_off: str | None = None


@dataclass(frozen=True)
class InitialStress:
    """``[initial_stress]``: the stress state before any load or stage (docs/insitu.md).

    Tension positive. Displacements, strains and reactions are reported relative to this
    state; stresses are totals.

    Attributes:
        kind: ``"constant"`` or ``"geostatic"``.
        stress: constant: the tensor in Voigt order, 2D (xx, yy, xy), 3D (xx, yy, zz,
            xy, yz, xz).
        surface: geostatic: the ground level (y in 2D, z in 3D), or in 2D a polyline of
            (x, y) points with x strictly increasing.
        gravity: geostatic: g, the magnitude of the ``gravity`` effect's acceleration.
        density: default density (``material.density``).
        densities: cell group -> density.
        k0: default K0 (ν/(1 − ν)).
        k0s: cell group -> K0.
        tectonic: a tensor added to the field (Voigt order), or None.
        loaded: side groups carrying σ0·n as a constant traction through all stages.
    """

    kind: Literal["constant", "geostatic"]
    stress: tuple[float, ...] = ()
    surface: float | tuple[tuple[float, float], ...] = 0.0
    gravity: float = 0.0
    density: float = 0.0
    densities: dict[str, float] = field(default_factory=dict)
    k0: float = 0.0
    k0s: dict[str, float] = field(default_factory=dict)
    tectonic: tuple[float, ...] | None = None
    loaded: tuple[str, ...] = ()


@dataclass(frozen=True)
class Stage:
    """One ``[[stages]]`` entry: a construction stage (docs/insitu.md).

    Attributes:
        name: the stage's name (unique).
        remove: cell groups excavated at the start of the stage.
        relaxation: the share of the pending release applied in this stage (the
            release is the out-of-balance force of the remaining body, computed when
            cells are removed); None: all that remains of it.
        add: cell groups installed at the start of the stage (support, backfill), after
            ``remove``: stress-free in the current deformed state, with ``material``.
            A group added before any stage removed it is absent until then.
        material: the added groups' material (E, ν, density; the scene's plane).
    """

    name: str
    remove: tuple[str, ...] = ()
    relaxation: float | None = None
    add: tuple[str, ...] = ()
    material: Material | None = None


def acts(entry: BoundaryCondition | Load, step: int, names: Sequence[str]) -> bool:
    """Whether a support or load acts in ``step`` (0: the initial step, k: stage k).

    ``names``: the stages' names in order; ``entry.switch_on``/``switch_off`` name
    stages among them (docs/insitu.md, "Loads and supports per stage").
    """
    order = list(names)
    on = 0 if entry.switch_on is None else order.index(entry.switch_on) + 1
    off = len(order) + 1 if entry.switch_off is None else order.index(entry.switch_off) + 1
    return on <= step < off


@dataclass(frozen=True)
class Solver:
    """PETSc linear solver choice.

    Attributes:
        preset: ``"auto"``, ``"direct"`` (MUMPS LU) or ``"iterative"`` (CG + GAMG).
        options: extra PETSc options, applied under the solver's own prefix.
    """

    preset: Literal["auto", "direct", "iterative"] = "auto"
    options: dict[str, str] = field(default_factory=dict)


@dataclass(frozen=True)
class Line:
    """A segment along which fields are sampled into CSV and a PNG plot.

    Attributes:
        start: first end point, shape=(gdim,).
        end: second end point, shape=(gdim,).
        points: number of equally spaced sample points, ends included.
        fields: probe field names sampled (see ``geofrac.scene.load.PROBE_FIELDS``).
    """

    start: tuple[float, ...]
    end: tuple[float, ...]
    points: int = 101
    fields: tuple[str, ...] = ("displacement",)


@dataclass(frozen=True)
class Units:
    """The units a scene's numbers are in (``[units]``): labels for pictures only.

    geofrac computes in whatever consistent units a scene uses; these name them on the
    axes of the PNGs it writes. A unit the scene does not declare is empty, and a label
    of that quantity then carries no unit (nothing is assumed: a scene without
    ``[units]`` may be in any consistent system).

    Attributes:
        length: e.g. ``"m"``, ``"mm"``; empty: not declared.
        force: e.g. ``"N"``, ``"kN"``; empty: not declared.
        stress: e.g. ``"Pa"``, ``"MPa"``; empty: not declared.
        time: e.g. ``"s"``; empty: not declared.
    """

    length: str = ""
    force: str = ""
    stress: str = ""
    time: str = ""

    def of(self, quantity: str) -> str:
        """The unit of ``quantity``, empty when the scene does not declare it.

        ``quantity``: ``length``, ``force``, ``stress``, ``time``, or the derived
        ``area`` (length²), ``volume`` (length³) and ``velocity`` (length/time).
        """
        if quantity in ("area", "volume"):
            power = "²" if quantity == "area" else "³"
            return f"{self.length}{power}" if self.length else ""
        if quantity == "velocity":
            return f"{self.length}/{self.time}" if self.length and self.time else ""
        unit: str = getattr(self, quantity)
        return unit

    def label(self, text: str, quantity: str) -> str:
        """``"text (unit)"``, or ``text`` alone when the unit is not declared."""
        unit = self.of(quantity)
        return f"{text} ({unit})" if unit else text


@dataclass(frozen=True)
class Output:
    """What a run writes.

    Attributes:
        dir: output directory.
        fields: field names written to XDMF.
        xdmf: whether to write XDMF at all.
        probes: name -> point, shape=(gdim,), where the displacement is reported.
        checkpoint_every: events or steps between checkpoints of a long loop (0: off).
        checkpoint_minutes: wall-time minutes between checkpoints (0: off).
        probe_fields: fields reported at every probe (``geofrac.scene.load.PROBE_FIELDS``).
        lines: name -> segment sampled into ``lines/<name>.csv`` and ``.png``.
        nominal_stress: a stress the stress probes are divided by (a concentration
            factor is printed beside them), or None.
    """

    dir: Path
    fields: tuple[str, ...]
    xdmf: bool
    probes: dict[str, tuple[float, ...]]
    checkpoint_every: int = 0
    checkpoint_minutes: float = 10.0
    probe_fields: tuple[str, ...] = ("displacement",)
    lines: dict[str, Line] = field(default_factory=dict)
    nominal_stress: float | None = None


@dataclass(frozen=True)
class ParticleSource:
    """Where the MPM particles come from.

    Attributes:
        kind: ``"lattice"`` (a box filled on a regular lattice, one particle per lattice
            cell at its centre) or ``"geometry"`` (one particle per gmsh cell of the
            scene's geometry, at its centroid, with its area/volume).
        lower: lattice: the box's lowest corner, shape=(dim,).
        counts: lattice: particles per direction, shape=(dim,).
        spacing: lattice: the lattice spacing.
        densities: geometry: physical group -> initial density (groups not named take
            ``material.density``).

    ``kind = "bodies"``: the particles are those of :attr:`MpmSpec.bodies`.
    """

    kind: Literal["lattice", "geometry", "bodies"]
    lower: tuple[float, ...] = ()
    counts: tuple[int, ...] = ()
    spacing: float = 0.0
    densities: dict[str, float] = field(default_factory=dict)


@dataclass(frozen=True)
class Body:
    """One body of an MPM scene (an entry of ``[[mpm.bodies]]``).

    Attributes:
        name: the body's name (unique in the scene).
        kind: ``"lattice"`` (a box filled on a regular lattice) or ``"group"`` (one
            particle per gmsh cell of a top-dimensional physical group).
        lower: lattice: the box's lowest corner, shape=(dim,).
        counts: lattice: particles per direction, shape=(dim,).
        spacing: lattice: the lattice spacing.
        group: group: the physical group's name.
        density: initial density, or None for ``material.density``.
        velocity: initial velocity components (numbers, or expression texts of the
            position for :mod:`geofrac.model.expr`), shape=(dim,), or None for
            ``mpm.velocity``.
        key: the body's dotted key in the scene (``mpm.bodies[1]``), for messages.
    """

    name: str
    kind: Literal["lattice", "group"]
    lower: tuple[float, ...] = ()
    counts: tuple[int, ...] = ()
    spacing: float = 0.0
    group: str | None = None
    density: float | None = None
    velocity: tuple[float | str, ...] | None = None
    key: str = ""


#: How the bed's nodes constrain the material (``mpm.bed_representation``, read by
#: :func:`geofrac.mpm.boundaries.bed_nodes`); the first is the default.
BED_REPRESENTATIONS = ("plane", "staircase")


@dataclass(frozen=True)
class MpmSpec:
    """The ``[mpm]`` table of a ``method = "mpm"`` scene (Edo (2016), chapter 4).

    Attributes:
        dim: spatial dimension (1, 2 or 3).
        scheme: ``musl``, ``usf`` or ``usavg`` (App. D).
        shape: ``mpm``, ``ugimp`` or ``cpgimp`` (eqs. 4.28-4.37).
        lower: the domain box's lowest corner, shape=(dim,).
        upper: its highest corner, shape=(dim,).
        spacing: the grid cell size L.
        padding: grid cells added outside the box on every side (room for GIMP
            supports reaching past a wall).
        walls: box side (``x_min`` ... ``z_max``) -> ``"fixed"`` (all velocity
            components held) or ``"roller"`` (the normal one); nodes on or beyond a
            walled side are held.
        bed: 2D only: the immobile ground as a polyline y(x), shape=(k, 2) with x
            increasing, or empty; grid nodes below it are held (``fixed``) or, when the
            ``friction`` effect lists ``"bed"``, frictional (eqs. 4.44-4.47).
        bed_representation: which bed nodes are frictional: ``"plane"`` (every node on
            or below the bed, each with the plane of the bed over it) or ``"staircase"``
            (only the surface nodes of the fixed region below the bed; the deeper ones
            are held): :func:`geofrac.mpm.boundaries.bed_nodes`.
        bed_group: 2D only: a physical curve group of the geometry whose mesh nodes,
            sorted by x, form the bed polyline instead (None: ``bed`` is used).
        initial_stress: ``"none"`` (particles start stress-free) or ``"geostatic"`` (the
            at-rest stress of their own weight, K₀ = ν/(1 − ν); needs ``gravity``).
        courant: Courant number α of Δt = α L / c (eq. 4.72), or None when ``dt`` is set.
        dt: fixed time step, or None.
        t_end: end time.
        frames: particle output frames written over the run (plus the initial one).
        velocity: initial velocity of every particle (of every body that gives none),
            shape=(dim,): each component a number or an expression text of the position
            (:mod:`geofrac.model.expr`, names ``x``, ``y``, ``z``).
        particles: where the particles come from (``kind = "bodies"``: from ``bodies``).
        bodies: the bodies of ``[[mpm.bodies]]`` in order (particle ids are numbered
            body after body), or empty for the single ``[mpm.particles]`` form.
        damping: Cundall's local damping coefficient α in [0, 1) of ``mpm.damping``
            (0: none; :class:`geofrac.mpm.schemes.StepSettings`).
    """

    dim: int
    scheme: str
    shape: str
    lower: tuple[float, ...]
    upper: tuple[float, ...]
    spacing: float
    padding: int
    walls: dict[str, str]
    bed: tuple[tuple[float, float], ...]
    courant: float | None
    dt: float | None
    t_end: float
    frames: int
    velocity: tuple[float | str, ...]
    particles: ParticleSource
    bed_group: str | None = None
    initial_stress: str = "none"
    damping: float = 0.0
    bodies: tuple[Body, ...] = ()
    bed_representation: str = "plane"


@dataclass(frozen=True)
class EffectSpec[C]:
    """A declared effect and its validated configuration, of type ``C``.

    Attributes:
        name: registry name (see :mod:`geofrac.effects`).
        config: the effect's own validated settings object (its ``configure``'s result,
            e.g. :class:`~geofrac.fracture.config.CrackingConfig`).
    """

    name: str
    config: C


def effect_config[C](effects: Sequence[EffectSpec[object]], name: str, kind: type[C]) -> C | None:
    """The configuration of the declared effect ``name``, of class ``kind``; None if absent.

    ``kind`` is the class its ``configure`` returns: from here on a type checker knows the
    configuration's type (the registry finds effects by name, so it cannot).

    Raises:
        TypeError: the effect's configuration is not a ``kind``.
    """
    for spec in effects:
        if spec.name == name:
            if not isinstance(spec.config, kind):
                raise TypeError(f"effect {name!r}: configuration {spec.config!r} is not a {kind}")
            return spec.config
    return None


@dataclass(frozen=True)
class BlocksSpec:
    """``[blocks]`` of a ``method = "blocks"`` scene (Edo (2016), chapter 5).

    Attributes:
        source: ``"geometry"`` (the scene's ``[geometry]``) or ``"terrain"`` (Edo (2016), §5.4).
        dim: 2 or 3.
        inner_point: 2D, each triangle's inner point: ``"incentre"`` or ``"random"``.
        radius: 2D random points: the movable region's radius relative to the inradius.
        convex: 2D random points: keep every piece convex.
        seed: seed of the random points.
        immobile: terrain: add the immobile part as one block.
        validate: ``"all"``, ``"none"`` or a number of blocks to sample for pyvista's
            cell validator.
        histogram_bins: bins of the block volume histogram.
        terrain: keyword arguments of :class:`geofrac.meshing.terrain.TerrainSpec`, or
            None.
    """

    source: str
    dim: int
    inner_point: str = "incentre"
    radius: float = 1.0
    convex: bool = False
    seed: int = 0
    immobile: bool = False
    validate: str | int = "all"
    histogram_bins: int = 40
    terrain: dict[str, Any] | None = None


@dataclass(frozen=True)
class Scene:
    """A fully validated scene.

    Attributes:
        path: the scene file.
        sha256: hash of the file contents plus any ``--set`` overrides.
        name: scene name.
        description: free text; when ``--set`` changed the scene, followed by
            ``(modified by --set KEY=VALUE, ...)`` (the text no longer describes the
            scene alone).
        effects: declared effects in declaration order.
        geometry, material, discretization, bcs, loads, exact, solver, output: see the
            classes of the same names (``method = "mpm"``: ``geometry`` is None for
            lattice particles, ``discretization`` is None, no bcs, loads or solver;
            ``method = "blocks"``: no material either).
        method: ``"fem"`` (finite elements, the default), ``"mpm"`` (material points) or
            ``"blocks"`` (a block model, no simulation).
        mpm: the ``[mpm]`` settings of an MPM scene, else None.
        blocks: the ``[blocks]`` settings of a block scene, else None.
        raw: the input tables after overrides (for the run summary).
        overrides: the ``--set`` overrides applied, as given.
        warnings: valid but risky choices, each naming file and key (printed, recorded).
        allow_large: the scene's ``allow_large`` (or ``--allow-large``): run even when
            the size estimate is beyond the caps of :mod:`geofrac.scene.size`.
        size: the :class:`~geofrac.scene.size.SizeEstimate` of the scene's work (None
            only for a scene built by hand).
        units: the ``[units]`` of the scene's numbers, for the pictures' axes.
        initial_stress: the ``[initial_stress]`` of an FEM scene, or None (stress-free).
        stages: the ``[[stages]]`` of an FEM scene in order (empty: one solve).
    """

    path: Path
    sha256: str
    name: str
    description: str
    effects: tuple[EffectSpec[object], ...]
    geometry: Geometry | None
    material: Material | None
    discretization: Discretization | None
    bcs: tuple[BoundaryCondition, ...]
    loads: tuple[Load, ...]
    exact: ExactSpec | None
    solver: Solver
    output: Output
    raw: dict[str, Any]
    warnings: tuple[str, ...] = ()
    method: Literal["fem", "mpm", "blocks"] = "fem"
    mpm: MpmSpec | None = None
    blocks: BlocksSpec | None = None
    allow_large: bool = False
    size: Any = None
    overrides: tuple[str, ...] = ()
    units: Units = Units()
    initial_stress: InitialStress | None = None
    stages: tuple[Stage, ...] = ()

    def effect_config[C](self, name: str, kind: type[C]) -> C | None:
        """The configuration of effect ``name``, a ``kind``, or None (:func:`effect_config`)."""
        return effect_config(self.effects, name, kind)

    @property
    def effect_names(self) -> tuple[str, ...]:
        """Names of the declared effects, shape=(num_effects,)."""
        return tuple(e.name for e in self.effects)

    @property
    def gdim(self) -> int:
        """Geometric dimension of the problem (2 or 3; 1 to 3 for MPM)."""
        if self.mpm is not None:
            return self.mpm.dim
        if self.blocks is not None:
            return self.blocks.dim
        assert self.geometry is not None
        return self.geometry.dim
