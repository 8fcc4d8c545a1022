"""Construction stages of an elasto-plastic run (docs/plasticity.md, "Construction stages").

After the initial state (an ``[initial_stress]`` K0 start, or the gravity phase and its
reset) and the analysis of the scene's loads, each ``[[stages]]`` entry is solved with
the load-stepped Newton of :class:`~geofrac.fem.plastic.PlasticProblem`:

- a stage that removes cell groups sets ``alive`` to 0 there (the internal force, the
  tangent and the weight ρ·alive of those cells go; their quadrature points keep the
  stress they had), holds the DOFs that no live cell touches where they are
  (:func:`geofrac.fem.insitu.untouched_blocks`, shared with the elastic stages) and
  computes the release r = I_live(σ) − F_live at the current state;
- the stage applies its share s (``relaxation``; default all that remains) of it:
  residual F(u) − (1 − μ) r with μ ramped from the share applied so far by s in the
  effect's ``load_steps`` increments, cut and verdict as the analysis's. μ = 0 is the
  previous equilibrium, μ = 1 the body without the removed cells (the gradual release
  of the excavation forces). A later stage without ``remove`` applies a further share.

The loads and supports are held in full during the stages. A stage that cannot converge
ends the run with ``converged = false``, the fields of its last converged share.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any

import dolfinx_solver  # noqa: F401  (orders MPI before the DOLFINx bindings)

import dolfinx
import numpy as np
from mpi4py import MPI

from geofrac.fem.insitu import cell_dofs, untouched_blocks
from geofrac.fem.plastic import PlasticProblem, PlasticResult
from geofrac.fem.plastic_outputs import cell_fields, step_rows
from geofrac.fem.stage_checkpoint import Frame
from geofrac.fem.stage_switches import owned_rows
from geofrac.model.scene import Stage

__all__ = ["PlasticStages"]


class PlasticStages:
    """The stage loop on a :class:`PlasticProblem` built with ``alive`` (collective methods).

    Args:
        plastic: the problem, after the analysis of the scene's loads converged.
        solution: the scene's solution (its tagged mesh, scene, probes).
        hold: the external work's constant that holds the loads in full (set to 1 here).
        say: progress (rank 0 prints).
    """

    def __init__(
        self,
        plastic: PlasticProblem,
        solution: Any,
        *,
        hold: dolfinx.fem.Constant,
        say: Callable[[str], None],
    ) -> None:
        assert plastic.alive is not None and plastic.release is not None
        self.plastic, self.solution, self.say = plastic, solution, say
        self.alive: dolfinx.fem.Function = plastic.alive
        self.release = plastic.release
        self.supports = list(plastic.newton.bcs)
        self.orphans = np.empty(0, dtype=np.int32)  # local blocks no live cell touches
        self.share = 1.0  # of the pending release applied so far
        self.scale = 0.0  # the largest |r| of the last removal
        #: the probes' displacements now (collective), or None without probes.
        self.probes: Callable[[], dict[str, list[float]]] | None = None
        hold.value = 1.0

    def remove(self, groups: Sequence[str]) -> None:
        """Excavate ``groups``: alive 0, orphans held, the release r of the new body."""
        plastic, alive = self.plastic, self.alive
        for group in groups:
            _, cells = self.solution.tagged.entities(group)
            alive.x.array[cell_dofs(alive, cells)] = 0.0
        alive.x.scatter_forward()
        V = plastic.V
        self.orphans = untouched_blocks(V, alive)
        here = dolfinx.fem.Function(V)
        here.x.array[:] = plastic.u.x.array
        plastic.newton.bcs = [*self.supports, dolfinx.fem.dirichletbc(here, self.orphans)]
        plastic.set_alive()
        self.release.active = False
        r = plastic.residual()
        r[self.held()] = 0.0
        self.release.vector = r
        self.release.active = True
        self.release.start = self.release.share = self.share = 0.0
        local = float(np.max(np.abs(r), initial=0.0))
        self.scale = float(plastic.comm.allreduce(local, op=MPI.MAX))

    def held(self) -> np.ndarray:
        """The owned rows the supports and the orphan holding fix, shape=(p,)."""
        return owned_rows(self.plastic.newton.bcs, self.plastic.V)

    def apply(self, stage: Stage, *, steps: int, max_cuts: int, observe: Any) -> PlasticResult:
        """Solve ``stage``'s share of the pending release; the verdict."""
        share = 1.0 - self.share if stage.relaxation is None else stage.relaxation
        self.release.start, self.release.share = self.share, share
        talk = self.say if self.plastic.comm.rank == 0 else None
        result = self.plastic.solve_stage(
            stage.name, steps, max_cuts=max_cuts, say=talk, observe=observe
        )
        self.share += share * result.factor
        self.release.start, self.release.share = self.share, 0.0
        return result

    def out_of_balance(self) -> float:
        """Largest |F(u) − (1 − μ) r| on the free rows over the largest |r| (collective)."""
        r = self.plastic.residual()
        r[self.held()] = 0.0
        local = float(np.max(np.abs(r), initial=0.0))
        value = float(self.plastic.comm.allreduce(local, op=MPI.MAX))
        return value / self.scale if self.scale > 0 else value

    def max_displacement(self) -> float:
        """Largest |u| over the nodes of live cells (collective)."""
        plastic = self.plastic
        bs = plastic.V.dofmap.index_map_bs
        owned = plastic.V.dofmap.index_map.size_local
        u = plastic.u.x.array[: owned * bs].reshape(-1, bs).copy()
        u[self.orphans[self.orphans < owned]] = 0.0
        local = float(np.max(np.linalg.norm(u, axis=1), initial=0.0))
        return float(plastic.comm.allreduce(local, op=MPI.MAX))

    def frame(self, index: int, name: str) -> Frame:
        """The XDMF time step of the current state: u, the cell fields and ``alive``."""
        u = self.plastic.u.copy()
        u.name = "displacement"
        kept = self.alive.copy()
        kept.name = "alive"
        return Frame(index, name, [u, *cell_fields(self.plastic).values(), kept])

    def run(
        self, k: int, stage: Stage, *, steps: int, max_cuts: int, observe: Any
    ) -> tuple[dict[str, Any], bool]:
        """Stage ``k``: remove, apply its share; its summary entry and verdict."""
        if stage.remove:
            self.remove(stage.remove)
        before = self.share
        result = self.apply(stage, steps=steps, max_cuts=max_cuts, observe=observe)
        plastic = self.plastic
        last = [s for s in result.steps if s.accepted]
        entry: dict[str, Any] = {
            "index": k,
            "name": stage.name,
            "removed": list(stage.remove),
            "converged": result.converged,
            "end_reason": result.end_reason,
            "factor": result.factor,
            "share": self.share - before,
            "released": self.share,
            "max_displacement": self.max_displacement(),
            **({} if self.probes is None else {"probes": self.probes()}),
            "reactions": last[-1].observed["reactions"] if last else None,
            "out_of_balance": self.out_of_balance(),
            "plastic_points": plastic.plastic_points(),
            "yielded_area": plastic.yielded_area(),
            "steps": step_rows(result.steps),
        }
        verdict = "converged" if result.converged else "NOT CONVERGED"
        removed = f"removed {', '.join(stage.remove)}; " if stage.remove else ""
        self.say(
            f"stage {k}/{len(self.solution.scene.stages)} '{stage.name}': {removed}"
            f"released {self.share:.3g}, {verdict}, max |u| = {entry['max_displacement']:.4g}, "
            f"{entry['plastic_points']} plastic points, out of balance "
            f"{entry['out_of_balance']:.1e}"
        )
        return entry, result.converged
