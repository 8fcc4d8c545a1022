"""The FEM method: scene → mesh → discretisation → solve (or an effect's loop) → fields.

Data flows one way. :func:`solve_scene` does the computation and returns everything a
caller may want (the benchmarks call it directly); :data:`FEM` is the method the run
pipeline (:func:`geofrac.pipeline.run_scene`) calls, adding the XDMF fields and the
network; the pipeline writes ``summary.json`` and publishes the directory.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, Protocol, cast

import dolfinx_solver  # noqa: F401  (orders MPI before the DOLFINx bindings)

import numpy as np
from mpi4py import MPI

from geofrac import effects as effect_registry
from geofrac.analytic import ExactSolution
from geofrac.elements import make_element
from geofrac.fem.elastic import ElasticProblem, make_problem
from geofrac.fem.post import (
    TENSOR_FIELDS,
    integrate,
    locate_line,
    locate_points,
    probe_fields,
)
from geofrac.fem.solution import Solution
from geofrac.headline import numbers, quantity, versus_vector
from geofrac.io.checkpoint import RunControl
from geofrac.io.lines import write_line
from geofrac.io.xdmf import write_fields, write_meshtags, write_steps
from geofrac.log import format_seconds, sayer
from geofrac.meshing.distribute import build_mesh, check_fracture_cover
from geofrac.model.fields import COMPONENT_INDEX, tensor_components
from geofrac.model.scene import Scene
from geofrac.timing import Timings
from geofrac_forms.elasticity import strain_energy_form

__all__ = ["FEM", "OUTPUT_FILES", "FemMethod", "initial_balance", "solve_scene"]

#: Files a run writes into its output directory.
OUTPUT_FILES = (
    "results.xdmf",
    "results.h5",
    "summary.json",
    "fractures.xdmf",
    "fractures.h5",
    "network.csv",
    "network.png",
    "events.csv",
    "load_displacement.png",
    "cracks.png",
    "cracks.xdmf",
    "cracks.h5",
    "damage.xdmf",
    "damage.h5",
    "grains.vtu",
    "grains.xdmf",
    "grains.h5",
    "load_steps.csv",
    "ground_reaction.csv",
    "ground_reaction.png",
    "plastic_shear_strain.png",
    "strength_reduction.csv",
    "strength_reduction.png",
    "failure_mechanism.png",
    "joints.csv",
    "fracture_faces.vtu",
)


class _DescribesReport(Protocol):
    """A geometry builder that reports (the dfn effect's): it words its report for the log."""

    def describe(self, report: dict[str, Any]) -> str:
        """One log line summarising ``report`` (what :meth:`build` returned)."""
        ...


def solve_scene(
    scene: Scene,
    comm: MPI.Comm,
    timings: Timings | None = None,
    *,
    verbose: bool = True,
    write: bool = False,
    control: RunControl | None = None,
) -> Solution:
    """Mesh, discretise, assemble and solve ``scene``; compute probes and error norms.

    ``write``: an effect's driver may write its own files into ``output.dir`` (the
    cracking event log and series); :func:`run_scene` sets it, benchmarks do not.
    ``control``: checkpoints, signal stop and resume data for an effect's loop.

    Raises:
        RunError: collectively, when the run cannot continue.
    """
    timings = timings or Timings()
    say = sayer(comm, verbose=verbose)
    with timings.phase("mesh"):
        geometry = scene.geometry
        assert geometry is not None  # a fem scene has one
        tagged = build_mesh(geometry, comm)
        geometry_report = dict(tagged.report)
        if tagged.fractures is not None:
            geometry_report |= check_fracture_cover(tagged)
    if geometry_report and geometry.builder is not None:
        say(cast(_DescribesReport, geometry.builder).describe(geometry_report))
    mesh = tagged.mesh
    names = list(scene.output.probes)
    points = np.zeros((len(names), 3))
    for i, name in enumerate(names):
        points[i, : scene.gdim] = scene.output.probes[name]
    with timings.phase("setup"):
        assert scene.discretization is not None  # a fem scene has one
        element = make_element(scene.discretization.element, mesh)
        cells = locate_points(mesh, points, [f"output.probes.{n}" for n in names])
        line_cells = {n: locate_line(mesh, n, ln) for n, ln in scene.output.lines.items()}
        problem = make_problem(
            tagged, element, scene, terms=effect_registry.linear_terms(scene.effects)
        )
    solution = Solution(scene, tagged, problem, timings=timings, control=control)
    counts = solution.mesh_counts()
    say(
        f"mesh: {counts['vertices']} vertices, {counts['cells']} cells; "
        f"element {element.name}: {element.num_dofs} DOFs on {comm.size} rank(s)"
    )
    driven = effect_registry.driven(scene.effects)
    staged: dict[str, Any] = {}
    try:
        if driven is not None:  # the effect's loop replaces the single solve (cracking)
            with timings.phase("compile"):
                problem.compile()
            with timings.phase("events"):
                loop = effect_registry.load(driven.name).driver(
                    driven.config, solution, say, write=write
                )
        elif problem.insitu is not None:  # an initial stress or stages (docs/insitu.md)
            from geofrac.fem.stages import run_stages

            probes = {"names": names, "points": points, "cells": cells}
            out = run_stages(problem, timings=timings, say=say, probes=probes, control=control)
            staged, solution.frames = out.results, out.frames
        else:
            _solve_phases(problem, timings, say)
    except BaseException:
        problem.destroy()
        raise
    uh = problem.uh
    with timings.phase("postprocess"):
        # probes and lines in one evaluation (point_tensors interpolates on the whole mesh)
        fields = _probe_field_names(scene)
        for line in scene.output.lines.values():
            fields += [f for f in line.fields if f not in fields]
        xyz = np.vstack([points, *(x for _, x, _ in line_cells.values())])
        where = np.concatenate([cells, *(w for _, _, w in line_cells.values())])
        values = probe_fields(problem, fields, xyz, cells=where) if len(xyz) else {}
        start = len(points)
        results = _probe_results(scene, {f: v[:start] for f, v in values.items()})
        for name, (s, x, _) in line_cells.items():
            stop = start + len(s)
            wanted = scene.output.lines[name].fields
            solution.lines[name] = (s, x, {f: values[f][start:stop] for f in wanted})
            start = stop
        results |= staged
        if driven is not None:
            results[driven.name] = loop
        else:
            t = problem.thickness  # excavated cells (stages) store no energy
            t = t if problem.insitu is None else t * problem.insitu.alive
            results["strain_energy"] = integrate(
                strain_energy_form(uh, problem.lam, problem.mu, t, problem.dx), comm
            )
            assert problem.solver is not None  # set by the solve
            results["solver"] = problem.solver.describe() | {"iterations": problem.iterations}
        if geometry_report:
            results["geometry"] = geometry_report
        if facts := problem.describe():  # the element's own facts (EFMM's domains)
            results[problem.element.name] = facts
        if problem.exact is not None:
            results["errors"] = problem.error_norms()
            results["exact_probes"] = {
                n: [float(c) for c in problem.exact.displacement(*points[i, : scene.gdim])]
                for i, n in enumerate(names)
            }
            if "stress" in scene.output.probe_fields:
                results["exact_probe_stress"] = {
                    n: _exact_stress(problem.exact, points[i, : scene.gdim])
                    for i, n in enumerate(names)
                }
    solution.results = results
    return solution


def initial_balance(scene: Scene, comm: MPI.Comm) -> float:
    """The initial state's largest out-of-balance force over the largest applied force.

    Meshes the scene and assembles the initial state's forces (no solve): what ``geofrac
    check`` reports for a scene with ``[initial_stress]`` (collective;
    :meth:`geofrac.fem.stages.StagedRun.check`).
    """
    from geofrac.fem.stages import initial_balance as balance

    assert scene.geometry is not None and scene.discretization is not None  # a fem scene
    tagged = build_mesh(scene.geometry, comm)
    element = make_element(scene.discretization.element, tagged.mesh)
    problem = make_problem(
        tagged, element, scene, terms=effect_registry.linear_terms(scene.effects)
    )
    try:
        driven = effect_registry.driven(scene.effects)
        if driven is not None and driven.name == "cracking":  # the crack cells' operators
            from geofrac.fracture.insitu import initial_balance as crack_balance

            problem.compile()
            return crack_balance(driven.config, Solution(scene, tagged, problem))
        return balance(problem)
    finally:
        problem.destroy()


def _exact_stress(exact: ExactSolution, point: np.ndarray) -> dict[str, float]:
    """The exact solution's stress at ``point``, shape=(gdim,), by component name.

    In-plane components only in 2D (the exact solutions give the gdim × gdim tensor).
    """
    sigma = np.array(exact.stress(*point), dtype=float)
    names = ("xx", "yy", "xy") if len(point) == 2 else ("xx", "yy", "zz", "xy", "yz", "xz")
    return {c: float(sigma[COMPONENT_INDEX[c]]) for c in names}


def _probe_field_names(scene: Scene) -> list[str]:
    """The fields the probes are evaluated for.

    Displacement, ``output.probe_fields``, and the principal stress and stress that
    ``output.nominal_stress`` needs.
    """
    output = scene.output
    fields = ["displacement", *(f for f in output.probe_fields if f != "displacement")]
    if output.nominal_stress is not None and "principal_stress" not in fields:
        fields.append("principal_stress")
    if output.nominal_stress is not None and "stress" not in fields:
        fields.append("stress")
    return fields


def _probe_results(scene: Scene, values: dict[str, np.ndarray]) -> dict[str, Any]:
    """``probes`` (displacements), and ``probe_fields`` and ``stress_concentration`` if asked.

    ``values``: field -> value at each probe (:func:`_probe_field_names`), shape=(num_probes,
    components); empty without probes.
    ``probe_fields``: name -> field -> value (stress and strain as component -> value,
    :func:`~geofrac.model.fields.tensor_components`; ``principal_stress`` [σ1, σ2, σ3]).
    ``stress_concentration`` (with ``output.nominal_stress``): name -> ``principal``
    σ1/σ_nominal, and the normal stress along the load axis over σ_nominal (``yy`` for
    loads along y) when every traction load is along one axis.
    """
    output, gdim = scene.output, scene.gdim
    names = list(output.probes)
    results: dict[str, Any] = {
        "probes": {n: values["displacement"][i].tolist() for i, n in enumerate(names)}
    }
    extra = [f for f in output.probe_fields if f != "displacement"]
    components = tensor_components(gdim)
    if names and extra:
        results["probe_fields"] = {
            n: {f: _probe_entry(values[f][i], f, components) for f in output.probe_fields}
            for i, n in enumerate(names)
        }
    if names and output.nominal_stress is not None:
        axis = _load_axis(scene)
        concentration = {}
        for i, n in enumerate(names):
            factors = {"principal": float(values["principal_stress"][i, 0]) / output.nominal_stress}
            if axis is not None:
                key = "xyz"[axis] * 2
                factors[key] = (
                    float(values["stress"][i, components.index(key)]) / output.nominal_stress
                )
            concentration[n] = factors
        results["stress_concentration"] = concentration
        results["nominal_stress"] = output.nominal_stress
    return results


def _probe_entry(value: np.ndarray, field: str, components: tuple[str, ...]) -> Any:
    """One probe field's JSON value: a tensor as component -> value, von Mises a number."""
    if field in ("stress", "strain"):
        return {c: float(v) for c, v in zip(components, value, strict=True)}
    if field == "von_mises":
        return float(value[0])
    return [float(v) for v in value]


def _load_axis(scene: Scene) -> int | None:
    """The axis every traction load of ``scene`` acts along, or None (no clear one)."""
    axes = set()
    for load in scene.loads:
        if load.type != "traction" or not isinstance(load.value, tuple):
            return None
        if any(isinstance(c, str) for c in load.value):
            return None
        nonzero = [k for k, c in enumerate(load.value) if c != 0.0]
        if len(nonzero) != 1:
            return None
        axes.add(nonzero[0])
    return axes.pop() if len(axes) == 1 else None


def _solve_phases(problem: ElasticProblem, timings: Timings, say: Callable[[str], None]) -> None:
    """Compile, assemble and solve, reporting each phase as it ends (rank 0)."""
    with timings.phase("compile"):
        problem.compile()
    say(f"compile: forms ready in {format_seconds(timings.local['compile'])}")
    with timings.phase("assemble"):
        problem.assemble()
    say(f"assemble: {format_seconds(timings.local['assemble'])}")
    with timings.phase("solve"):
        problem.solve()
    assert problem.solver is not None  # set by the solve
    info = problem.solver.describe()
    say(
        f"solve: {format_seconds(timings.local['solve'])} ({info['preset']}: {info['ksp_type']} + "
        f"{info['pc_type']}, {problem.iterations} iterations, "
        f"relative residual {info['relative_residual']:.1e})"
    )


def _write_xdmf(solution: Solution) -> None:
    scene, problem = solution.scene, solution.problem
    mesh = solution.tagged.mesh
    functions = []
    if "displacement" in scene.output.fields:
        functions.append(problem.uh)  # write_fields brings it to the geometry degree
    if solution.frames:  # a staged run: one time step per stage
        steps = [frame.functions for frame in solution.frames]
        write_steps(scene.output.dir / "results.xdmf", mesh, steps)
        problem.write_extra(scene.output.dir)
        return
    wanted = [f for f in scene.output.fields if f in TENSOR_FIELDS]
    own = solution.fields  # an effect loop's own fields replace the ones computed from uh
    fields = problem.tensor_fields([f for f in wanted if f not in own])
    functions += [own[f] if f in own else fields[f] for f in wanted]
    functions += [fn for name, fn in own.items() if name not in TENSOR_FIELDS]
    write_fields(scene.output.dir / "results.xdmf", mesh, functions)
    problem.write_extra(scene.output.dir)


def _write_fractures(solution: Solution) -> None:
    """Write ``fractures.xdmf``: the fracture facets with their fracture and set numbers.

    Both are 1-based: ``fracture`` is the row of ``network.csv``, ``fracture_set`` the
    set in declaration order.
    """
    from dolfinx.mesh import meshtags

    from geofrac.dfn.check import match_facets

    tagged = solution.tagged
    clean = tagged.fractures
    dim, facets = tagged.entities("fractures")
    facets = np.sort(facets).astype(np.int32)
    fracture = clean.edge_fracture[match_facets(tagged.vertex_coordinates(dim, facets), clean)]
    values = {"fracture": fracture + 1, "fracture_set": clean.network.set_index[fracture] + 1}
    tags = []
    for name, value in values.items():
        tag = meshtags(tagged.mesh, dim, facets, value.astype(np.int32))
        tag.name = name
        tags.append(tag)
    write_meshtags(solution.scene.output.dir / "fractures.xdmf", tagged.mesh, tags)


def _write_network(solution: Solution, comm: MPI.Comm) -> None:
    """``network.csv`` and ``network.png`` (the fractures by set over the mesh; collective).

    Every rank sends its owned cells' edges to rank 0, which draws them faint under the
    fractures.
    """
    from geofrac.dfn.io import save_network
    from geofrac.io import pictures

    scene = solution.scene
    clean = solution.tagged.fractures
    mesh = solution.tagged.mesh
    tdim = mesh.topology.dim
    owned = mesh.topology.index_map(tdim).size_local
    corners = 3 if mesh.topology.cell_name() == "triangle" else 4
    nodes = mesh.geometry.dofmaps[0][:owned, :corners]
    xy = mesh.geometry.x[nodes][:, :, :2]  # (cells, corners, 2)
    edges = np.stack([xy, np.roll(xy, -1, axis=1)], axis=2).reshape(-1, 2, 2)
    parts = comm.gather(edges, root=0)
    if parts is None:  # not rank 0
        return
    save_network(clean.network, scene.output.dir / "network.csv")
    every = np.concatenate(parts)
    swap = (every[:, 0, 0] > every[:, 1, 0]) | (
        (every[:, 0, 0] == every[:, 1, 0]) & (every[:, 0, 1] > every[:, 1, 1])
    )
    every[swap] = every[swap][:, ::-1]
    unique = np.unique(every.reshape(-1, 4), axis=0).reshape(-1, 2, 2)  # an edge of 2 cells once
    network = clean.network
    fig = pictures.network_figure(
        domain=clean.domain,
        fractures=clean.vertices[clean.edges],
        sets=network.set_index[clean.edge_fracture],
        set_names=network.set_names,
        mesh_edges=unique,
        regions=clean.constraints,
        title=f"{scene.name}: {len(network.segments)} fractures and the mesh",
        units=scene.units,
    )
    pictures.save(fig, scene.output.dir / "network.png")


def _write_lines(solution: Solution, comm: MPI.Comm) -> dict[str, Any]:
    """Write each sampled line's CSV and PNG; the summary's ``lines`` entry."""
    scene = solution.scene
    return {
        name: write_line(
            scene.output.dir,
            scene.name,
            name,
            line=scene.output.lines[name],
            s=s,
            xyz=xyz,
            values=values,
            comm=comm,
            units=scene.units,
        )
        for name, (s, xyz, values) in solution.lines.items()
    }


class FemMethod:
    """The FEM method of the run pipeline (:class:`geofrac.pipeline.Method`)."""

    name = "fem"
    output_files = OUTPUT_FILES

    def head(self, scene: Scene) -> dict[str, Any]:
        """The summary head names the element."""
        assert scene.discretization is not None  # a fem scene has one
        return {"element": scene.discretization.element}

    def run(
        self, scene: Scene, comm: MPI.Comm, timings: Timings, *, verbose: bool, control: RunControl
    ) -> dict[str, Any]:
        """Solve (or run the effect's loop), write the fields; the summary entries."""
        solution = solve_scene(scene, comm, timings, verbose=verbose, write=True, control=control)
        try:
            if scene.output.xdmf:
                with timings.phase("output"):
                    _write_xdmf(solution)
                    if solution.tagged.fractures is not None:
                        _write_fractures(solution)
            if solution.lines:
                with timings.phase("output"):
                    solution.results["lines"] = _write_lines(solution, comm)
            if solution.tagged.fractures is not None:
                with timings.phase("output"):
                    _write_network(solution, comm)
            return {
                "mesh": solution.mesh_counts(),
                "dofs": solution.problem.element.num_dofs,
                "results": solution.results,
            }
        finally:
            solution.problem.destroy()

    def report(self, summary: dict[str, Any]) -> list[str]:
        """The sampled lines' files (their numbers are in the CSVs)."""
        lines = summary["results"].get("lines", {})
        return [
            f"line {n}: {e['points']} points -> {e['csv']}, {e['png']}" for n, e in lines.items()
        ]

    def result(self, scene: Scene, summary: dict[str, Any]) -> list[str]:
        """Probes against the exact values, the initial state, the stages, the error norms.

        The effects' lines (cracking, plasticity, dfn) follow from their own ``result``.
        """
        results = summary["results"]
        length = scene.units.of("length")
        exact = results.get("exact_probes", {})
        lines = []
        for name, value in results["probes"].items():
            line = f"probe {name}: u = {numbers(value, length)}"
            if name in exact:
                gap = versus_vector(value, exact[name], length)
                line += f"  (exact {numbers(exact[name])}; {gap})"
            lines += [line, *_probe_fields(scene, name, results)]
        if "initial_stress" in results:
            entry = results["initial_stress"]
            lines.append(
                f"initial stress: out of balance {entry['out_of_balance']:.2e} of the applied "
                f"force (tolerance {entry['tolerance']:g})"
            )
        for stage in results.get("stages", []):
            lines.append(
                f"stage {stage['index']} '{stage['name']}': max |u| = "
                f"{quantity(stage['max_displacement'], length, 6)}, out of balance "
                f"{stage['out_of_balance']:.1e}"
            )
        if "errors" in results:
            e = results["errors"]
            lines.append(
                f"accuracy: ||u - u_exact||_L2 = {e['u']:.4e} (relative {e['u_relative']:.3e}), "
                f"energy = {e['energy']:.4e} (relative {e['energy_relative']:.3e})"
            )
        return lines


def _probe_fields(scene: Scene, name: str, results: dict[str, Any]) -> list[str]:
    """Probe ``name``'s other fields (the exact stress beside), its stress concentration."""
    stress = scene.units.of("stress")
    exact_stress = results.get("exact_probe_stress", {})
    lines = []
    for field, v in results.get("probe_fields", {}).get(name, {}).items():
        if field == "displacement":
            continue
        unit = "" if field == "strain" else stress
        if isinstance(v, dict):
            text = ", ".join(f"{c} {x + 0.0:.6g}" for c, x in v.items())
            text += f" {unit}" if unit else ""
        elif isinstance(v, list):
            text = numbers(v, unit, digits=6) + " (σ1 >= σ2 >= σ3)"
        else:
            text = quantity(v, unit, 6)
        if field == "stress" and name in exact_stress:
            pairs = exact_stress[name]
            text += "  (exact " + ", ".join(f"{c} {x + 0.0:.6g}" for c, x in pairs.items())
            text += f"; {versus_vector([v[c] for c in pairs], list(pairs.values()), unit)})"
        lines.append(f"  {field.replace('_', ' ')}: {text}")
    concentration = results.get("stress_concentration", {})
    if name in concentration:
        factors = concentration[name]
        text = f"σ1/σ_nominal = {factors['principal']:.4f}"
        for key, k in factors.items():
            if key != "principal":
                text += f", σ{key}/σ_nominal = {k:.4f}"
        nominal = results.get("nominal_stress")
        suffix = "" if nominal is None else f" (σ_nominal = {quantity(nominal, stress, 6)})"
        lines.append(f"  stress concentration: {text}{suffix}")
    return lines


#: The FEM method (``method = "fem"``, the default).
FEM = FemMethod()
