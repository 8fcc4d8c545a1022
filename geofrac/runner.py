"""The FEM method: scene → mesh → discretisation → solve (or an effect's loop) → fields.

Data flows one way. :func:`solve_scene` does the computation and returns everything a
caller may want (the benchmarks call it directly); :data:`FEM` is the method the run
pipeline (:func:`geofrac.pipeline.run_scene`) calls, adding the XDMF fields and the
network; the pipeline writes ``summary.json`` and publishes the directory.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import dolfinx_solver  # noqa: F401  (orders MPI before the DOLFINx bindings)

import numpy as np
from mpi4py import MPI

from geofrac import effects as effect_registry
from geofrac.elements import make_element
from geofrac.errors import RunError
from geofrac.fem.elastic import ElasticProblem, make_problem
from geofrac.fem.post import (
    TENSOR_FIELDS,
    integrate,
    locate_points,
    probe,
)
from geofrac.fem.solution import Solution
from geofrac.io.checkpoint import RunControl
from geofrac.io.xdmf import write_fields, write_meshtags
from geofrac.log import format_seconds, sayer
from geofrac.meshing.distribute import build_mesh, check_fracture_cover
from geofrac.model.scene import Scene
from geofrac.timing import Timings
from geofrac_forms.elasticity import strain_energy_form

__all__ = ["FEM", "OUTPUT_FILES", "FemMethod", "solve_scene"]

#: Files a run writes into its output directory.
OUTPUT_FILES = (
    "results.xdmf",
    "results.h5",
    "summary.json",
    "fractures.xdmf",
    "fractures.h5",
    "network.csv",
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
)


def solve_scene(
    scene: Scene,
    comm: MPI.Comm,
    timings: Timings | None = None,
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
    say = sayer(comm, verbose)
    with timings.phase("mesh"):
        tagged = build_mesh(scene.geometry, comm)
        geometry_report = dict(tagged.report)
        if tagged.fractures is not None:
            geometry_report |= check_fracture_cover(tagged)
    if geometry_report and scene.geometry.builder is not None:
        say(scene.geometry.builder.describe(geometry_report))
    mesh = tagged.mesh
    names = list(scene.output.probes)
    points = np.zeros((len(names), 3))
    for i, name in enumerate(names):
        points[i, : scene.gdim] = scene.output.probes[name]
    with timings.phase("setup"):
        element = make_element(scene.discretization.element, mesh)
        try:
            cells = locate_points(mesh, points)
        except RunError as exc:
            raise RunError(f"output.probes: {exc}") from None
        problem = make_problem(tagged, element, scene, effect_registry.linear_terms(scene.effects))
    solution = Solution(scene, tagged, problem, timings=timings, control=control)
    counts = solution.mesh_counts()
    say(
        f"mesh: {counts['vertices']} vertices, {counts['cells']} cells; "
        f"element {element.name}: {element.num_dofs} DOFs on {comm.size} rank(s)"
    )
    driven = effect_registry.driven(scene.effects)
    try:
        if driven is not None:  # the effect's loop replaces the single solve (cracking)
            with timings.phase("compile"):
                problem.compile()
            with timings.phase("events"):
                loop = effect_registry.load(driven.name).driver(driven.config, solution, say, write)
        else:
            _solve_phases(problem, timings, say)
    except BaseException:
        problem.destroy()
        raise
    uh = problem.uh
    with timings.phase("postprocess"):
        values = probe(uh, points, cells)
        results: dict[str, Any] = {"probes": {n: values[i].tolist() for i, n in enumerate(names)}}
        if driven is not None:
            results[driven.name] = loop
        else:
            results["strain_energy"] = integrate(
                strain_energy_form(uh, problem.lam, problem.mu, problem.thickness, problem.dx), comm
            )
            results["solver"] = problem.solver.describe() | {"iterations": problem.iterations}  # type: ignore[union-attr]
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
    solution.results = results
    return solution


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
    info = problem.solver.describe()  # type: ignore[union-attr]
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
    wanted = [f for f in scene.output.fields if f in TENSOR_FIELDS]
    fields = problem.tensor_fields(wanted)
    functions += [fields[f] for f in wanted]
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


class FemMethod:
    """The FEM method of the run pipeline (:class:`geofrac.pipeline.Method`)."""

    name = "fem"
    output_files = OUTPUT_FILES

    def head(self, scene: Scene) -> dict[str, Any]:
        """The summary head names the element."""
        return {"element": scene.discretization.element}

    def run(
        self, scene: Scene, comm: MPI.Comm, timings: Timings, verbose: bool, control: RunControl
    ) -> dict[str, Any]:
        """Solve (or run the effect's loop), write the fields; the summary entries."""
        solution = solve_scene(scene, comm, timings, verbose, write=True, control=control)
        try:
            if scene.output.xdmf:
                with timings.phase("output"):
                    _write_xdmf(solution)
                    if solution.tagged.fractures is not None:
                        _write_fractures(solution)
            if solution.tagged.fractures is not None and comm.rank == 0:
                from geofrac.dfn.io import save_network

                save_network(solution.tagged.fractures.network, scene.output.dir / "network.csv")
            return {
                "mesh": solution.mesh_counts(),
                "dofs": solution.problem.element.num_dofs,
                "results": solution.results,
            }
        finally:
            solution.problem.destroy()

    def report(self, summary: dict[str, Any]) -> list[str]:
        """Probes (with the exact values) and the error norms."""
        results = summary["results"]
        exact = results.get("exact_probes", {})
        lines = []
        for name, value in results["probes"].items():
            line = f"probe {name}: u = [{_numbers(value)}]"
            if name in exact:
                line += f"  (exact [{_numbers(exact[name])}])"
            lines.append(line)
        if "errors" in results:
            e = results["errors"]
            lines.append(
                f"accuracy: ||u - u_exact||_L2 = {e['u']:.4e} (relative {e['u_relative']:.3e}), "
                f"energy = {e['energy']:.4e} (relative {e['energy_relative']:.3e})"
            )
        return lines


def _numbers(values: list[float]) -> str:
    return ", ".join(f"{v + 0.0:.10g}" for v in values)  # + 0.0 turns -0 into 0


#: The FEM method (``method = "fem"``, the default).
FEM = FemMethod()
