"""Run a ``method = "mpm"`` scene: particles → grid → time loop → output.

The thin MPI layer of the MPM: it builds the grid, walls and particles from the
validated :class:`~geofrac.model.scene.Scene`, decomposes them over the communicator
(:mod:`geofrac.mpm.parallel`, on more than one rank), steps to ``t_end`` and writes

- ``particles.xdmf`` / ``.h5``: ``frames`` + 1 frames of particle position and the
  fields of ``output.fields`` (rank 0 gathers them, in particle-id order, so 1 and N
  ranks write the same files);
- ``energies.csv``: per step, kinetic, strain, gravitational potential (relative to the
  start), total (their sum) and dissipated (initial total minus total), then the energy
  budget of :mod:`~geofrac.mpm.energy` (columns :data:`~geofrac.mpm.energy.CSV_COLUMNS`:
  the stored energy as stress work, the cumulative wall, friction, smoothing, plastic and
  numerical terms, their total and the budget's closure);
- ``summary.json`` (by :func:`geofrac.pipeline.run_scene`): ``results`` with ``runout_m`` (the
  largest particle x at the end minus at the start), ``friction_angle_deg`` (with
  ``plasticity``), ``energy_drift_max`` (max |E(t) − E₀| / E₀ with E the total above;
  None when E₀ = 0, a body starting at rest), ``energy_drift_work_max`` (the same with
  the stored energy as stress work), ``energy_balance_error`` (the energy no physical
  term explains over the run's energy scale; defined for bodies starting at rest),
  ``energy_budget_closure``, with friction the contact's invariant (``contact_work_max``,
  ``numerical_over_gravity_work``, ``energy_invariant`` …: :meth:`~geofrac.mpm.energy.
  EnergyLog.invariant`, docs/mpm_energy.md), front and probe histories, and ``bodies`` (per body of
  ``[[mpm.bodies]]``, or one ``"body"``: particles, first id, mass).

Particles come from ``[mpm.particles]`` or from the bodies of ``[[mpm.bodies]]``, ids
numbered body after body before the decomposition; initial velocities may be expressions
of the position (:mod:`geofrac.model.expr`); ``[gravity] ramp`` scales gravity per step
(the gravitational potential is then the work of each step's own gravity,
:meth:`~geofrac.mpm.energy.EnergyLog.potential`).

With a :class:`~geofrac.io.checkpoint.RunControl` the loop checkpoints (every rank's
particles in their local order and the loop's state) and stops cleanly on a signal;
``--resume`` continues from the newest checkpoint (docs/mpm.md, "Checkpoints and
resume").

Effects: ``gravity`` sets the body force, ``mls_smoothing`` the strain-increment
smoothing (4.50-4.58), ``plasticity`` the Drucker-Prager material (4.39-4.43),
``friction`` the frictional boundaries (4.44-4.47); an undeclared effect's code is never
imported.
"""

from __future__ import annotations

import dataclasses
import math
import time
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from mpi4py import MPI

from geofrac.errors import RunError
from geofrac.io.checkpoint import RunControl
from geofrac.log import format_seconds, sayer
from geofrac.model.scene import Scene
from geofrac.mpm import shapes
from geofrac.mpm.boundaries import boundary_rows, scene_grid
from geofrac.mpm.constitutive import ConstitutiveModel
from geofrac.mpm.energy import CSV_COLUMNS, EnergyLog, StepBudget
from geofrac.mpm.grid import Grid
from geofrac.mpm.particles import Particles, concat, take
from geofrac.mpm.schemes import StepSettings, particle_strain_energy, step, time_step
from geofrac.timing import Timings

__all__ = ["MPM", "OUTPUT_FILES", "MpmMethod", "MpmRun", "advance", "prepare", "simulate"]

#: Files an MPM run writes into its output directory.
OUTPUT_FILES = ("particles.xdmf", "particles.h5", "energies.csv", "particles.png", "summary.json")
#: Seconds between progress lines (rank 0).
PROGRESS_EVERY_S = 10.0


@dataclass
class MpmRun:
    """Everything a prepared MPM scene needs to step.

    Attributes:
        grid: the global background grid.
        local: this rank's grid (``grid`` on one rank).
        particles: this rank's particles.
        material: the particles' constitutive model (:mod:`~geofrac.mpm.constitutive`).
        settings: the step settings.
        steps: number of steps to ``t_end``.
        domain: the decomposition, or None on one rank.
        probes: probe name -> particle id (the particle nearest the point at t = 0).
        total: number of particles over all ranks.
        ramp: seconds over which gravity rises from 0 to ``settings.gravity``
            (``[gravity] ramp``; 0: full gravity from the start).
        bodies: body name -> {"particles", "first_id", "mass"} (ids of a body are
            ``first_id`` ... ``first_id + particles - 1``).
    """

    grid: Grid
    local: Grid
    particles: Particles
    material: ConstitutiveModel
    settings: StepSettings
    steps: int
    domain: Any = None
    probes: dict[str, int] = field(default_factory=dict)
    total: int = 0
    ramp: float = 0.0
    bodies: dict[str, dict[str, Any]] = field(default_factory=dict)


def _all_particles(
    scene: Scene, comm: MPI.Comm
) -> tuple[Particles, tuple[tuple[float, float], ...], dict[str, dict[str, Any]]]:
    """The scene's particles, bed and bodies, built on rank 0's mesh (every rank has all).

    Particle ids are numbered body after body in the scene's order (``[[mpm.bodies]]``),
    so they are the same on any number of ranks.

    Returns:
        (particles, bed polyline, body name -> {"particles", "first_id", "mass"}).
    """
    from geofrac.mpm.seeding import from_cells, from_lattice

    spec, mat = scene.mpm, scene.material
    assert spec is not None and mat is not None and mat.density is not None
    src = spec.particles
    bed = spec.bed
    if src.kind == "bodies":
        groups = [b.group for b in spec.bodies if b.kind == "group"]
        meshed, polyline = _meshed(scene, comm, groups)
        parts = []
        for b in spec.bodies:
            density = mat.density if b.density is None else b.density
            if b.kind == "lattice":
                part = from_lattice(b.lower, b.counts, b.spacing, density=density)
            else:
                points, cells = meshed[b.group]  # type: ignore[index]
                part = from_cells(points, cells, np.full(len(cells), density))
            key = f"{b.key}.velocity" if b.velocity is not None else "mpm.velocity"
            part.v[:] = _velocity(b.velocity or spec.velocity, part.x, key)
            parts.append(part)
        p = concat(parts, spec.dim)
        p.ids = np.arange(p.n, dtype=np.int64)
        first = np.cumsum([0, *(q.n for q in parts)])
        bodies = {
            b.name: {
                "particles": q.n,
                "first_id": int(first[i]),
                "mass": float(np.sum(q.mass)),
            }
            for i, (b, q) in enumerate(zip(spec.bodies, parts, strict=True))
        }
    elif src.kind == "lattice":
        p = from_lattice(src.lower, src.counts, src.spacing, density=mat.density)
        p.v[:] = _velocity(spec.velocity, p.x, "mpm.velocity")
        polyline = None
    else:
        meshed, polyline = _meshed(scene, comm, None)
        # a cell in several groups is seeded once, with a density its groups name
        named = sorted(meshed, key=lambda n: n not in src.densities)
        points = next(xyz for xyz, _ in meshed.values())
        cells = np.concatenate([meshed[n][1] for n in named])
        cell_density = np.concatenate(
            [np.full(len(meshed[n][1]), src.densities.get(n, mat.density)) for n in named]
        )
        _, first_cell = np.unique(np.sort(cells, axis=1), axis=0, return_index=True)
        first_cell = np.sort(first_cell)
        p = from_cells(points, cells[first_cell], cell_density[first_cell])
        p.v[:] = _velocity(spec.velocity, p.x, "mpm.velocity")
    if src.kind != "bodies":
        bodies = {"body": {"particles": p.n, "first_id": 0, "mass": float(np.sum(p.mass))}}
    if polyline is not None:
        bed = tuple((float(x), float(y)) for x, y in polyline)
    return p, bed, bodies


def _meshed(
    scene: Scene, comm: MPI.Comm, groups: list[str | None] | None
) -> tuple[dict[str, tuple[np.ndarray, np.ndarray]], np.ndarray | None]:
    """The geometry's cells per top-dimensional group and the bed curve, meshed on rank 0.

    ``groups``: the groups needed (None: all). Nothing is meshed when no group and no
    bed group is needed. Collective; the result is broadcast.

    Raises:
        RunError: on every rank, when gmsh fails.
    """
    from geofrac.mpm.seeding import mesh_cells

    spec, geometry = scene.mpm, scene.geometry
    assert spec is not None
    if groups == [] and spec.bed_group is None:
        return {}, None
    assert geometry is not None and geometry.file is not None
    result: Any = None
    if comm.rank == 0:
        try:
            result = mesh_cells(
                geometry.file,
                geometry.parameters,
                geometry.mesh_size,
                dim=geometry.dim,
                curve=spec.bed_group,
                time_limit=geometry.time_limit,
                trusted=geometry.trusted,
                algorithm=geometry.algorithm,
            )
            missing = [g for g in groups or () if g not in result[0]]
            if missing:
                result = f"physical group(s) {missing} have no meshed {geometry.dim}D cells"
        except (RuntimeError, ValueError) as exc:
            result = str(exc)
        if isinstance(result, str):
            result = f"seeding particles from {geometry.file.name} failed: {result}"
    result = comm.bcast(result, root=0)
    if isinstance(result, str):
        raise RunError(result)
    return result


def _velocity(components: tuple[float | str, ...], x: np.ndarray, key: str) -> np.ndarray:
    """Initial velocities at positions ``x`` (shape=(n, dim)): numbers or expressions.

    Raises:
        RunError: an expression is not finite at some particle (the message names ``key``).
    """
    from geofrac.model.expr import ExpressionError, evaluate, parse

    v = np.empty_like(x)
    names = ("x", "y", "z")[: x.shape[1]]
    for a, c in enumerate(components):
        if isinstance(c, str):
            try:
                v[:, a] = evaluate(parse(c, names), x)
            except ExpressionError as exc:
                raise RunError(f"{key}: entry {a}: expression {c!r} {exc}") from None
        else:
            v[:, a] = c
    return v


def _material(scene: Scene) -> ConstitutiveModel:
    """The particle material: the model the scene's effects select, from the registry."""
    from geofrac.mpm import constitutive

    name = constitutive.select(scene.effect_names)
    config = _config(scene, name)
    assert scene.material is not None  # an mpm scene has a material
    return constitutive.load(name).from_scene(scene.material.E, scene.material.nu, config)


def _config(scene: Scene, name: str) -> Any:
    return next((e.config for e in scene.effects if e.name == name), None)


def prepare(scene: Scene, comm: MPI.Comm) -> MpmRun:
    """Grid, particles, material, walls and time step of an MPM scene on ``comm``.

    Raises:
        RunError: on every rank, when the particles cannot be built or start outside
            the grid.
    """
    spec = scene.mpm
    assert spec is not None
    g = scene_grid(spec.lower, spec.upper, spec.spacing, padding=spec.padding)
    p, bed, bodies = _all_particles(scene, comm)
    margin = shapes.get(spec.shape).margin(spec.spacing, p.lp)
    if np.any(g.outside(p.x, margin)):
        raise RunError(
            f"mpm.grid: {int(np.sum(g.outside(p.x, margin)))} particle(s) start outside the "
            "grid; enlarge mpm.grid or its padding"
        )
    material = _material(scene)
    gravity = _config(scene, "gravity")
    if spec.initial_stress == "geostatic":
        from geofrac.mpm.seeding import geostatic

        assert scene.material is not None  # an mpm scene has a material
        geostatic(p, np.asarray(gravity.acceleration), scene.material.nu, width=spec.spacing)
    density = float(np.min(p.density))  # the fastest wave: the lightest particle
    if spec.dt is not None:
        dt = spec.dt
    else:
        dt = time_step(spec.courant, spec.spacing, material, density=density, dim=spec.dim)  # type: ignore[arg-type]
    steps = max(1, math.ceil(spec.t_end / dt - 1e-9))
    dt = spec.t_end / steps  # end exactly at t_end (never a larger step)
    probes = {}
    for name, point in scene.output.probes.items():
        probes[name] = int(np.argmin(np.sum((p.x - np.asarray(point)) ** 2, axis=1)))
    domain = None
    local = g
    if comm.size > 1:
        from geofrac.mpm.parallel import decompose

        domain = decompose(g, comm)
        local = domain.local
        p = domain.distribute(p)
    total = comm.allreduce(p.n)
    smoothing = _config(scene, "mls_smoothing")
    fric = _config(scene, "friction")
    fixed, f_nodes, f_normals, f_planes, f_which = boundary_rows(
        local,
        spec.lower,
        spec.upper,
        walls=spec.walls,
        bed=bed,
        frictional=fric.boundaries if fric else (),
        bed_representation=spec.bed_representation,
    )
    friction = None
    if fric is not None and len(f_nodes):
        from geofrac.mpm.friction import friction as make_friction

        mus = np.asarray(fric.mus or (fric.mu,) * len(fric.boundaries))
        friction = make_friction(f_nodes, f_normals, mus[f_which], offsets=f_planes)
    settings = StepSettings(
        spec.scheme,
        shapes.get(spec.shape),
        dt,
        np.asarray(gravity.acceleration if gravity else (0.0,) * spec.dim),
        fixed,
        None if smoothing is None else smoothing.radius,
        friction,
        domain=domain,
        damping=spec.damping,
        smoothing_kind="standard" if smoothing is None else smoothing.kind,
    )
    ramp = gravity.ramp if gravity is not None else 0.0
    return MpmRun(g, local, p, material, settings, steps, domain, probes, total, ramp, bodies)


def _energies(
    run: MpmRun, comm: MPI.Comm, budget: StepBudget | None = None
) -> tuple[float, float, float, np.ndarray]:
    """Kinetic, strain, gravitational potential −Σ m b·x (full b) and the step's budget terms.

    The energies are exact sums of the per-particle terms
    (:func:`geofrac.mpm.fixedpoint.exact_sums`): the same on any number of ranks,
    whatever the particles' order. The budget terms (zeros without ``budget``) are
    summed over the ranks by a plain reduction (reporting only).
    """
    from geofrac.mpm.fixedpoint import exact_sums

    p = run.particles
    per = np.stack(
        [
            0.5 * p.mass * np.sum(p.v**2, axis=1),
            particle_strain_energy(p, run.material),
            -p.mass * (p.x @ run.settings.gravity),
        ],
        axis=1,
    )
    kin, strain, pot = (float(e) for e in exact_sums(per, comm))
    terms = budget.terms() if budget is not None else StepBudget().terms()
    if comm.size > 1:
        terms = comm.allreduce(terms)
    return kin, strain, pot, terms


def advance(run: MpmRun, comm: MPI.Comm, log: EnergyLog, *, k: int) -> list[float]:
    """Step ``k`` of ``run`` with its energy budget recorded in ``log`` (collective).

    The step uses :func:`_settings` (gravity ramped during ``[gravity] ramp``). The
    scene's time loop and the translating-bar bench (:func:`geofrac.bench.mpm.
    translating_bar`) both step through here, so they report the same energies.

    Args:
        run: the prepared run.
        comm: its communicator.
        log: the run's energy log (:func:`start_log`).
        k: the step, from 1 (from t = (k − 1) dt to k dt).

    Returns:
        The step's ``energies.csv`` row after ``step`` and ``t`` (kinetic first, strain
        second).
    """
    budget = StepBudget()
    step(run.local, run.particles, run.material, settings=_settings(run, k), budget=budget)
    kin, strain, pot, terms = _energies(run, comm, budget)
    return log.record(kin, strain, log.potential(pot, _gravity_factor(run, k)), terms=terms)


def start_log(run: MpmRun, comm: MPI.Comm) -> EnergyLog:
    """The energy log of a run at t = 0 (collective)."""
    k0, s0, u0, _ = _energies(run, comm)
    return EnergyLog(k0, s0, u0)


def _gather(run: MpmRun, comm: MPI.Comm) -> Particles | None:
    """All particles in id order on rank 0 (None elsewhere)."""
    if run.domain is None:
        return run.particles
    return run.domain.gather(run.particles)


def _fields(p: Particles, x0: np.ndarray, wanted: tuple[str, ...]) -> dict[str, np.ndarray]:
    """Output fields of gathered particles (stress as 3×3 with σ_zz in 2D)."""
    out: dict[str, np.ndarray] = {}
    if "displacement" in wanted:
        out["displacement"] = p.x - x0
    if "velocity" in wanted:
        out["velocity"] = p.v
    if "stress" in wanted:
        s = np.zeros((p.n, 3, 3))
        s[:, : p.dim, : p.dim] = p.stress
        if p.dim == 2:
            s[:, 2, 2] = p.stress_zz
        out["stress"] = s
    if "plastic_strain" in wanted:
        out["plastic_strain"] = p.plastic
    if "density" in wanted:
        out["density"] = p.density
    if "mass" in wanted:
        out["mass"] = p.mass
    if "volume" in wanted:
        out["volume"] = p.volume
    return out


def simulate(
    scene: Scene,
    comm: MPI.Comm,
    *,
    timings: Timings | None = None,
    verbose: bool = True,
    write: bool = False,
    control: RunControl | None = None,
) -> dict[str, Any]:
    """Prepare and step ``scene`` to its end time; return the JSON-ready results.

    ``write``: write ``particles.xdmf`` and ``energies.csv`` into ``output.dir`` (which
    must exist); ``energies.csv`` gets a line per step as it completes.

    ``control``: after each step the loop asks ``control.poll`` whether to write a
    checkpoint (this rank's particles in their local order, and the loop's state) or to
    stop on a signal; with ``control.resume`` it continues from that checkpoint. On the
    same number of ranks that gives the uninterrupted run's particle state bit for bit;
    on another number the particles are redistributed by position and the run agrees
    with an uninterrupted one to round-off (docs/mpm.md). None: no checkpoints, no
    polling.

    Raises:
        RunError: collectively, when the run cannot continue (a particle left the grid,
            a non-finite state, a checkpoint of another scene, output files that cannot
            be continued);
            :class:`~geofrac.interrupt.Interrupted` after a signal, once the
            checkpoint is written.
    """
    timings = timings or Timings()
    say = sayer(comm, verbose=verbose)
    spec = scene.mpm
    assert spec is not None
    with timings.phase("setup"):
        run = prepare(scene, comm)
    say(
        f"mpm: {run.total} particles, grid {'x'.join(map(str, run.grid.cells))} cells of "
        f"{run.grid.spacing:g}, {spec.scheme}/{spec.shape}, dt = {run.settings.dt:.4g}, "
        f"{run.steps} steps to t = {spec.t_end:g} on {comm.size} rank(s)"
    )
    resume = control.resume if control is not None else None
    loop = _begin(run, comm, control, say)
    series, csv = _open_output(run, scene, loop, comm, write=write, resumed=resume is not None)
    out = scene.output
    t_wall = time.perf_counter()
    try:
        with timings.phase("steps"):
            _time_loop(
                run, comm, loop, say=say, series=series, csv=csv, control=control,
                every=max(1, run.steps // spec.frames), fields=out.fields, t_wall=t_wall,
            )  # fmt: skip
    finally:
        if csv is not None:
            csv.close()
    seconds = time.perf_counter() - t_wall
    if write:
        with timings.phase("output"):
            _picture(run, comm, loop, scene)
    results = _results(run, comm, loop, seconds, scene)
    if resume is not None:
        results["resumed_at_step"] = resume.k
    results.update(run.material.results())
    return results


def _begin(run: MpmRun, comm: MPI.Comm, control: RunControl | None, say: Any) -> dict[str, Any]:
    """The loop's state: at t = 0, or restored from ``control.resume`` (collective)."""
    resume = control.resume if control is not None else None
    if resume is None:
        return _start(run, comm)
    assert control is not None
    control.check_resume(ranks_must_match=False)
    loop = _restore(run, resume, comm)
    moved = (
        f"; written on {resume.ranks()} rank(s), its particles are redistributed over "
        f"{comm.size} (the result agrees with an uninterrupted run to round-off only)"
        if resume.ranks() != comm.size
        else ""
    )
    say(
        f"mpm: resuming from step {loop['k']} (t = {loop['k'] * run.settings.dt:.6g}) of "
        f"checkpoint {resume.path}{moved}"
    )
    return loop


def _open_output(
    run: MpmRun,
    scene: Scene,
    loop: dict[str, Any],
    comm: MPI.Comm,
    *,
    write: bool,
    resumed: bool,
) -> tuple[Any, Any]:
    """``particles.xdmf`` and ``energies.csv`` on rank 0 with ``write`` (else None, None).

    Raises:
        RunError: on every rank, when rank 0 cannot write or continue them.
    """
    out = scene.output
    series = csv = None
    error = None
    if write and comm.rank == 0:
        try:
            series, csv = _open_logs(run, out, loop, resumed)
        except (OSError, ValueError) as exc:  # e.g. an unreadable particles.h5 on --resume
            error = f"cannot {'continue' if resumed else 'write'} the output in {out.dir}: {exc}"
    error = comm.bcast(error, root=0)
    if error is not None:
        raise RunError(error)
    return series, csv


def _time_loop(
    run: MpmRun,
    comm: MPI.Comm,
    loop: dict[str, Any],
    *,
    say: Any,
    series: Any,
    csv: Any,
    control: RunControl | None,
    every: int,
    fields: tuple[str, ...],
    t_wall: float,
) -> None:
    """Steps ``loop["k"] + 1`` … ``run.steps``: energies, frames, progress, checkpoints.

    A frame every ``every`` steps and at the end (``fields``: ``output.fields``); progress
    lines timed from ``t_wall``.
    """
    s, log = run.settings, loop["log"]
    last_say = t_wall
    first_step = loop["k"] + 1
    for k in range(first_step, run.steps + 1):
        row = advance(run, comm, log, k=k)
        if csv is not None:
            csv.write(",".join([str(k), repr(k * s.dt), *map(repr, row)]) + "\n")
            csv.flush()  # a killed run keeps every completed step
        if k % every == 0 or k == run.steps:
            _frame(run, comm, loop, k, series, fields)
        now = time.perf_counter()
        if now - last_say > PROGRESS_EVERY_S or k == run.steps:
            last_say = now
            done = k - first_step + 1
            rate = done * run.total / (now - t_wall)
            say(
                f"mpm [{k}/{run.steps}] t = {k * s.dt:.4g}: kinetic {row[0]:.4g}, "
                f"strain {row[1]:.4g}, front x {loop['history']['front_x'][-1]:.4g} "
                f"({rate:.3g} particle-steps/s, elapsed "
                f"{format_seconds(now - t_wall)}, left "
                f"~{format_seconds((run.steps - k) * (now - t_wall) / done)})"
            )
        if control is not None:
            _poll(run, loop, k, control, comm)


def _frame(
    run: MpmRun,
    comm: MPI.Comm,
    loop: dict[str, Any],
    k: int,
    series: Any,
    fields: tuple[str, ...],
) -> None:
    """Record step ``k``'s front and probes and write its particle frame (collective)."""
    t = k * run.settings.dt
    x0, history, probes = loop["x0"], loop["history"], loop["probes"]
    history["t"].append(t)
    history["front_x"].append(_front(run, comm))
    gathered = _gather(run, comm)
    if gathered is not None:
        for name, pid in run.probes.items():
            probes[name].append(_probe(gathered, pid, x0))
        if series is not None:
            series.write(t, gathered.x, _fields(gathered, x0, fields))


def _picture(run: MpmRun, comm: MPI.Comm, loop: dict[str, Any], scene: Scene) -> None:
    """``particles.png``: the particles at the end by |displacement|, the initial outline.

    Collective (the particles are gathered); rank 0 draws.
    """
    gathered = _gather(run, comm)
    if comm.rank != 0 or gathered is None or loop["x0"] is None:
        return
    from geofrac.io import pictures

    t = run.steps * run.settings.dt
    fig = pictures.particles_figure(
        x0=loop["x0"],
        x=gathered.x,
        cell=run.grid.spacing,
        title=f"{scene.name}: {run.total} particles at t = {t:.4g} {scene.units.time}".rstrip(),
        units=scene.units,
    )
    pictures.save(fig, scene.output.dir / "particles.png")


def _poll(run: MpmRun, loop: dict[str, Any], k: int, control: RunControl, comm: MPI.Comm) -> None:
    """After step ``k``: write a checkpoint, or stop on a signal, as ``control`` says."""
    save, stop = control.poll(k)
    if save and k < run.steps:
        state = {"k": k, "log": loop["log"].state()}
        state |= {"front0": loop["front0"], "history": loop["history"], "probes": loop["probes"]}
        x0 = loop["x0"]
        shared = None if x0 is None else {"x0": x0}
        held = _held_rows(run, comm)  # the contact's memory (friction.held_vn)
        if shared is not None and held is not None:
            shared |= {"held_keys": held[0], "held_vn": held[1], "held_stuck": held[2]}
        control.save(k, state, shared=shared, local=run.particles.state())
    if stop and k < run.steps:
        control.interrupt(f"step {k}")


def _node_offset(run: MpmRun) -> int:
    """The global id of this rank's local node 0 (0 without a domain)."""
    return 0 if run.domain is None else run.domain.node_offset


def _held_rows(run: MpmRun, comm: MPI.Comm) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
    """Every rank's held contact rows (friction.held_rows), on rank 0 (collective).

    None without friction, and on the other ranks.
    """
    fr = run.settings.friction
    if fr is None:
        return None
    from geofrac.mpm.friction import held_rows

    parts = comm.gather(held_rows(fr, _node_offset(run)), root=0)
    if parts is None:
        return None
    return tuple(np.concatenate([q[i] for q in parts]) for i in range(3))  # type: ignore[return-value]


def _results(
    run: MpmRun, comm: MPI.Comm, loop: dict[str, Any], seconds: float, scene: Scene
) -> dict[str, Any]:
    """The run's JSON-ready results (every rank returns the same)."""
    spec = scene.mpm
    assert spec is not None
    log, history = loop["log"], loop["history"]
    steps_done = run.steps - loop["k"]
    probes = comm.bcast(loop["probes"], root=0)  # rank 0 gathered them
    return {
        "particles": run.total,
        "steps": run.steps,
        "dt": run.settings.dt,
        "t_end": spec.t_end,
        "runout_m": history["front_x"][-1] - loop["front0"],
        "energy_drift_max": log.drift_max,
        "energy_drift_work_max": log.drift_work_max,
        "energy_balance_error": log.balance_error,
        "energy_budget_closure": log.closure / log.scale if log.scale > 0 else None,
        **_invariant(run, log),
        "particle_steps_per_s": run.total * steps_done / seconds if seconds > 0 else None,
        "history": history,
        "probes": probes,
        "bodies": run.bodies,
    }


def _invariant(run: MpmRun, log: EnergyLog) -> dict[str, Any]:
    """The contact's invariant (docs/mpm_energy.md): its measures, verdict and warnings.

    Judged for a run with a contact (friction); the gravity bound only with gravity too.
    """
    s = run.settings
    contact = s.friction is not None
    verdict, warnings = log.invariant(contact=contact, gravity=bool(np.any(s.gravity != 0)))
    return {
        "contact_work_max": log.contact_max if contact else None,
        "contact_work_total": log.contact_total if contact else None,
        "contact_work_relative_max": log.contact_relative_max if contact else None,
        "contact_work_positive_steps": log.contact_positive if contact else None,
        "numerical_over_gravity_work": log.gravity_ratio if contact else None,
        "numerical_over_gravity_work_max": log.gravity_ratio_max if contact else None,
        "energy_invariant": verdict,
        "energy_invariant_warnings": warnings,
    }


def _settings(run: MpmRun, k: int) -> StepSettings:
    """The settings of step ``k`` (from t = (k − 1) dt to k dt).

    During a gravity ramp (``[gravity] ramp``) gravity is multiplied by the ramp's mean
    factor over the step; afterwards the settings are ``run.settings`` themselves.
    """
    factor = _gravity_factor(run, k)
    if factor == 1.0:
        return run.settings
    return dataclasses.replace(run.settings, gravity=factor * run.settings.gravity)


def _gravity_factor(run: MpmRun, k: int) -> float:
    """Step ``k``'s gravity over the full one: the ramp's mean factor, 1.0 after it."""
    s = run.settings
    if run.ramp <= 0 or (k - 1) * s.dt >= run.ramp:
        return 1.0
    return float(ramp_factor(run.ramp, (k - 1) * s.dt, k * s.dt))


def ramp_factor(ramp: float, t0: float, t1: float) -> float:
    """The mean of the ramp's factor min(1, t / ramp) over the step [t0, t1].

    Used as gravity's factor for that step, so that the impulse m g ∫ min(1, t/ramp) dt
    a particle receives over the run is exact, whatever the step.
    """
    if ramp <= 0 or t0 >= ramp:
        return 1.0

    def integral(t: float) -> float:  # ∫_0^t min(1, s/ramp) ds
        return t * t / (2 * ramp) if t <= ramp else ramp / 2 + (t - ramp)

    return (integral(t1) - integral(t0)) / (t1 - t0)


def _start(run: MpmRun, comm: MPI.Comm) -> dict[str, Any]:
    """The loop's state at t = 0 (collective): initial energies, front, probes, x0."""
    first = _gather(run, comm)
    x0 = None if first is None else first.x.copy()
    log = start_log(run, comm)
    front0 = _front(run, comm)
    probes: dict[str, list[Any]] = {name: [] for name in run.probes}
    if first is not None:
        for name, pid in run.probes.items():
            probes[name].append(_probe(first, pid, x0))
    return {
        "k": 0,
        "log": log,
        "front0": front0,
        "history": {"t": [0.0], "front_x": [front0]},
        "probes": probes,
        "x0": x0,
        "first": first,
    }


def _restore(run: MpmRun, ck: Any, comm: MPI.Comm) -> dict[str, Any]:
    """Put checkpoint ``ck``'s particles into ``run`` and return the loop's saved state.

    On the checkpoint's number of ranks each rank takes back its own particles in their
    local order. On another number rank 0 reads every rank's particles, sorts them by id
    and broadcasts them, and each rank keeps those in its slab (as :func:`prepare`
    distributes the initial ones). Collective.

    Raises:
        RunError: on every rank, when the checkpoint's particles are incomplete or do not
            match the scene's.
    """
    error, particles = None, None
    same = ck.ranks() == comm.size
    try:
        if same:
            particles = Particles.from_state(ck.local(comm.rank))
        elif comm.rank == 0:
            parts = [Particles.from_state(ck.local(r)) for r in range(ck.ranks())]
            whole = concat(parts, run.grid.dim)
            particles = take(whole, np.argsort(whole.ids, kind="stable"))
    except (OSError, ValueError) as exc:
        error = f"--resume: the checkpoint {ck.path} holds unusable particles ({exc})"
    errors = comm.allgather(error)
    error = next((e for e in errors if e), None)
    if error is None and not same:
        particles = comm.bcast(particles, root=0)
        assert particles is not None
        if run.domain is not None:
            particles = run.domain.distribute(particles)
    if error is None:
        assert particles is not None
        loop = dict(ck.data)
        loop["log"] = EnergyLog.from_state(loop["log"])
        saved = ck.shared() if comm.rank == 0 else {}
        loop["x0"] = saved.get("x0")
        broken = comm.rank == 0 and (loop["x0"] is None or len(loop["x0"]) != run.total)
        count = comm.allreduce(particles.n)
        if comm.allreduce(int(broken)) or count != run.total:
            error = f"--resume: the checkpoint {ck.path} does not match this scene's particles"
    if error is not None:
        raise RunError(error)
    assert particles is not None
    run.particles = particles
    if run.settings.friction is not None:
        from geofrac.mpm.friction import restore_held

        names = ("held_keys", "held_vn", "held_stuck")
        held = comm.bcast(tuple(saved.get(n) for n in names), root=0)
        if held[0] is not None:  # older checkpoints: no memory (the next step rebuilds it)
            restore_held(
                run.settings.friction, _node_offset(run), held[0], vn=held[1], stuck=held[2]
            )
    return loop


_ENERGY_HEADER = ",".join(CSV_COLUMNS) + "\n"


def _open_logs(run: MpmRun, out: Any, loop: dict[str, Any], resumed: bool) -> tuple[Any, Any]:
    """``particles.xdmf`` and ``energies.csv`` (rank 0): new, or cut back to step ``k``.

    A resumed run drops what the interrupted one wrote after its checkpoint (a run
    killed by SIGKILL goes on writing after its last checkpoint), so every step and
    frame time appears once.
    """
    from geofrac.io.points import PointSeries

    path = out.dir / "energies.csv"
    series = None
    if resumed:
        k = loop["k"]
        if out.xdmf:
            series = PointSeries.reopen(out.dir / "particles.xdmf", run.total, k * run.settings.dt)
        rows = []
        if path.exists():
            with path.open() as f:
                rows = [line for line in f if (step := _csv_step(line)) is not None and step <= k]
        csv = path.open("w")
        csv.write(_ENERGY_HEADER)
        csv.writelines(rows)
        csv.flush()
        return series, csv
    first = loop["first"]
    if out.xdmf:
        series = PointSeries(out.dir / "particles.xdmf", first.n)
        series.write(0.0, first.x, _fields(first, loop["x0"], out.fields))
    csv = path.open("w")
    csv.write(_ENERGY_HEADER)
    csv.write(",".join(["0", "0.0", *map(repr, loop["log"].first_row())]) + "\n")
    csv.flush()
    return series, csv


def _csv_step(line: str) -> int | None:
    """The step of an ``energies.csv`` row; None for the header or a torn last line."""
    head = line.split(",", 1)[0]
    return int(head) if head.isdigit() and line.endswith("\n") else None


def _front(run: MpmRun, comm: MPI.Comm) -> float:
    """The largest particle x over all ranks (the front of a slide moving to +x)."""
    x = run.particles.x[:, 0]
    return comm.allreduce(float(x.max()) if len(x) else -math.inf, op=MPI.MAX)


def _probe(p: Particles | None, pid: int, x0: np.ndarray | None) -> dict[str, list[float]]:
    """Position, displacement, velocity and stress of particle ``pid``."""
    assert p is not None and x0 is not None
    return {
        "x": p.x[pid].tolist(),
        "u": (p.x[pid] - x0[pid]).tolist(),
        "v": p.v[pid].tolist(),
        "stress": p.stress[pid].ravel().tolist(),
    }


class MpmMethod:
    """The MPM method of the run pipeline (:class:`geofrac.pipeline.Method`)."""

    name = "mpm"
    output_files = OUTPUT_FILES

    def head(self, scene: Scene) -> dict[str, Any]:
        """No DOLFINx or PETSc versions: an MPM run imports neither."""
        return {"fem": False, "method": "mpm"}

    def run(
        self, scene: Scene, comm: MPI.Comm, timings: Timings, *, verbose: bool, control: RunControl
    ) -> dict[str, Any]:
        """:func:`simulate` with its output; the summary entries."""
        return {
            "results": simulate(
                scene, comm, timings=timings, verbose=verbose, write=True, control=control
            )
        }

    def report(self, summary: dict[str, Any]) -> list[str]:
        """The contact's invariant broken: one line per bound (older summaries have none)."""
        return list(summary["results"].get("energy_invariant_warnings", []))

    def result(self, scene: Scene, summary: dict[str, Any]) -> list[str]:
        """A bar under its own weight against the closed form, else the runout."""
        from geofrac.mpm.result import lines

        return lines(scene, summary["results"])


#: The MPM method (``method = "mpm"``).
MPM = MpmMethod()
