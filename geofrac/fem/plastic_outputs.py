"""What an engineer reads from an elasto-plastic run (docs/plasticity.md, "Outputs").

- :func:`cell_fields`: the returned stress, its von Mises value and the accumulated
  plastic shear strain γᵖ as DG0 cell fields (the mean over each cell of the
  quadrature-point values, ∫_cell q dx / |cell|) for ``results.xdmf``, which ParaView reads;
- :class:`ProbeHistory`: the ``output.probes`` displacements at every converged load
  step (``load_steps.csv``) and, with ``[plasticity].ground_reaction``, the ground reaction
  curve of a circular opening beside Salençon's closed form
  (:class:`geofrac.analytic_plastic.MohrCoulombOpening`): ``ground_reaction.csv`` and
  ``ground_reaction.png``;
- :func:`write_reduction_csv`: each strength-reduction trial (``strength_reduction.csv``);
- :func:`plot_cell_field`: a DG0 field drawn on the mesh (rank 0 gathers the cells):
  ``plastic_shear_strain.png``, and ``failure_mechanism.png`` at the critical factor.
"""

from __future__ import annotations

import csv
import math
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import dolfinx_solver  # noqa: F401  (orders MPI before the DOLFINx bindings)

import basix.ufl
import dolfinx
import numpy as np
import ufl

from geofrac.analytic_plastic import MohrCoulombOpening
from geofrac.fem.plastic import PlasticProblem
from geofrac.fem.post import locate_points, probe
from geofrac.plasticity import MohrCoulomb

__all__ = [
    "ProbeHistory",
    "cell_fields",
    "cell_triangles",
    "displacement_magnitude",
    "plot_cell_field",
    "step_rows",
    "write_reduction_csv",
]


def _cell_mean(
    expr: Any, dx: ufl.Measure, space: dolfinx.fem.FunctionSpace, area: np.ndarray, name: str
) -> dolfinx.fem.Function:
    """The DG0 function ∫_cell expr dx / |cell| on ``space``; ``area``: |cell| of owned cells."""
    out = dolfinx.fem.Function(space, name=name)
    b = dolfinx.fem.assemble_vector(dolfinx.fem.form(ufl.inner(expr, ufl.TestFunction(space)) * dx))
    b.scatter_reverse(dolfinx.la.InsertMode.add)
    bs = space.dofmap.index_map_bs
    n = len(area)
    out.x.array[: n * bs] = (b.array[: n * bs].reshape(n, bs) / area[:, None]).ravel()
    out.x.scatter_forward()
    return out


def cell_fields(plastic: PlasticProblem) -> dict[str, dolfinx.fem.Function]:
    """DG0 ``stress`` (3×3), ``von_mises`` and ``plastic_shear_strain`` of the current state.

    Each is the cell mean of the quadrature-point values (the returned stress of the
    last converged step; γᵖ = √(2/3 dev εᵖ : dev εᵖ) accumulated). Collective.
    """
    mesh = plastic.mesh
    n = mesh.topology.index_map(mesh.topology.dim).size_local
    scalar = dolfinx.fem.functionspace(mesh, ("DG", 0))
    area_vec = dolfinx.fem.assemble_vector(dolfinx.fem.form(ufl.TestFunction(scalar) * plastic.dx))
    area_vec.scatter_reverse(dolfinx.la.InsertMode.add)
    area = area_vec.array[:n].copy()
    element = basix.ufl.quadrature_element(mesh.basix_cell(), value_shape=(), degree=plastic._qdeg)
    Q = dolfinx.fem.functionspace(mesh, element)
    pairs = plastic.layout.stress  # 2D: xx, yy, zz, xy; 3D: the six Voigt components
    st = plastic.sig.x.array.reshape(-1, len(pairs))
    full = np.zeros((len(st), 3, 3))
    for k, (i, j) in enumerate(pairs):
        full[:, i, j] = full[:, j, i] = st[:, k]
    dev = full - np.trace(full, axis1=1, axis2=2)[:, None, None] / 3.0 * np.eye(3)
    j2 = 0.5 * np.sum(dev * dev, axis=(1, 2))
    von_mises = dolfinx.fem.Function(Q)
    von_mises.x.array[:] = np.sqrt(3.0 * j2)
    shear = dolfinx.fem.Function(Q)
    shear.x.array[:] = plastic.plastic_shear_strain()
    index = {pair: k for k, pair in enumerate(pairs)}
    index.update({(j, i): k for (i, j), k in list(index.items())})
    s = plastic.sig
    sigma = ufl.as_tensor(
        [[s[index[i, j]] if (i, j) in index else 0.0 for j in range(3)] for i in range(3)]
    )
    tensor = dolfinx.fem.functionspace(mesh, ("DG", 0, (3, 3)))
    return {
        "stress": _cell_mean(sigma, plastic.dx, tensor, area, "stress"),
        "von_mises": _cell_mean(von_mises, plastic.dx, scalar, area, "von_mises"),
        "plastic_shear_strain": _cell_mean(shear, plastic.dx, scalar, area, "plastic_shear_strain"),
    }


def displacement_magnitude(u: dolfinx.fem.Function) -> dolfinx.fem.Function:
    """|u| at each cell's midpoint as a DG0 function (for a picture of the mechanism)."""
    mesh = u.function_space.mesh
    space = dolfinx.fem.functionspace(mesh, ("DG", 0))
    out = dolfinx.fem.Function(space, name="displacement_magnitude")
    expr = ufl.sqrt(ufl.inner(u, u))
    out.interpolate(dolfinx.fem.Expression(expr, space.element.interpolation_points))
    return out


def cell_triangles(
    fn: dolfinx.fem.Function, *, alive: dolfinx.fem.Function | None = None
) -> tuple[np.ndarray, np.ndarray] | None:
    """The owned 2D cells' corners and ``fn``'s DG0 values, gathered on rank 0 (collective).

    Returns (corners, shape=(3 m, 2); values, shape=(m,)) on rank 0, m the cells of all
    ranks (those with ``alive`` > 0.5 when given), None on the other ranks.
    """
    mesh = fn.function_space.mesh
    n = mesh.topology.index_map(mesh.topology.dim).size_local
    keep = np.ones(n, dtype=bool)
    if alive is not None:
        keep = alive.x.array[alive.function_space.dofmap.list[:n, 0]] > 0.5
    cells = mesh.geometry.dofmaps[0][:n, :3][keep]
    corners = mesh.geometry.x[cells, :2]  # shape=(kept cells, 3, 2)
    values = fn.x.array[fn.function_space.dofmap.list[:n, 0]][keep]
    parts = mesh.comm.gather((corners, values), root=0)
    if parts is None:
        return None
    return np.concatenate([p[0] for p in parts]).reshape(-1, 2), np.concatenate(
        [p[1] for p in parts]
    )


def plot_cell_field(
    fn: dolfinx.fem.Function,
    path: Path,
    *,
    title: str,
    label: str,
    length: str,
    joints: np.ndarray | None = None,
    alive: dolfinx.fem.Function | None = None,
) -> None:
    """Draw the scalar DG0 ``fn`` on the mesh's straight-sided cells into ``path`` (rank 0).

    Collective: every rank sends its owned cells' corners and values to rank 0.
    ``label`` names the colour bar, ``length`` the axes' unit. ``joints``: the joint
    pairs' table (:meth:`geofrac.fem.joints.JointInterface.table`, columns x, y, …,
    state), drawn as points coloured by state (closed, slipping, open). ``alive``: the
    DG0 indicator of construction stages; the removed cells (0) are left blank. 2D meshes
    only: in 3D nothing is drawn (the field is in the XDMF for ParaView).
    """
    if fn.function_space.mesh.geometry.dim != 2:
        return
    gathered = cell_triangles(fn, alive=alive)
    if gathered is None:
        return
    xy, v = gathered
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    span = np.ptp(xy, axis=0)
    aspect = float(span[1] / span[0]) if span[0] > 0 else 1.0
    wide = aspect < 0.6  # a slope: the colour bar goes below
    height = 1.4 + 6.0 * min(max(aspect, 0.25), 1.2) + (0.4 if wide else 0.0)
    fig, ax = plt.subplots(figsize=(7.0, height), constrained_layout=True)
    triangles = np.arange(len(xy)).reshape(-1, 3)
    art = ax.tripcolor(xy[:, 0], xy[:, 1], triangles, facecolors=v, cmap="viridis")
    ax.set_aspect("equal")
    if joints is not None and len(joints):
        state = joints[:, -1].astype(int)
        for code, colour, name in (
            (0, "white", "closed"),
            (1, "red", "slipping"),
            (2, "k", "open"),
        ):
            at = state == code
            if at.any():
                ax.plot(*joints[at, :2].T, "o", ms=3, color=colour, mec="k", mew=0.3, label=name)
        ax.legend(title="joint pairs", fontsize=8, loc="upper left", framealpha=0.8)
    fig.colorbar(art, ax=ax, label=label, orientation="horizontal" if wide else "vertical")
    ax.set_xlabel(f"x ({length})" if length else "x")
    ax.set_ylabel(f"y ({length})" if length else "y")
    ax.set_title(title, fontsize=10)
    fig.savefig(path, dpi=90)
    plt.close(fig)


def write_reduction_csv(trials: Sequence[Any], path: Path) -> None:
    """``strength_reduction.csv``: one row per trial in the order run (rank 0 calls).

    Columns: trial, factor, stable, load_factor (the last converged), end_reason,
    monitor (|u| at the monitor at the trial's end), newton_iterations, seconds,
    rejected (PETSc reasons of the rejected increments).
    """
    with open(path, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(
            [
                "trial",
                "factor",
                "stable",
                "load_factor",
                "end_reason",
                "monitor",
                "newton_iterations",
                "seconds",
                "rejected",
            ]
        )
        for i, t in enumerate(trials, 1):
            rejected = " ".join(f"{k}x{v}" for k, v in sorted(t.diverged.items()))
            monitor = "" if t.monitor is None else f"{t.monitor:.10g}"
            w.writerow(
                [
                    i,
                    f"{t.factor:.10g}",
                    int(t.stable),
                    f"{t.load_factor:.10g}",
                    t.end_reason,
                    monitor,
                    t.iterations,
                    f"{t.seconds:.3f}",
                    rejected,
                ]
            )


class ProbeHistory:
    """The probes' displacements at every converged load step, and the ground reaction curve.

    Args:
        u: the displacement being solved for.
        probes: name → point (x, y) (``output.probes``).
        ground: the validated ``ground_reaction`` table
            (:class:`geofrac.effects.plasticity.GroundReactionConfig`), or None.
        p0: the in-situ pressure (−σ0_xx of a constant isotropic initial stress, 0 without).
        law: the plastic law (its c, φ, ψ, E, ν give the closed form, Mohr-Coulomb only).
    """

    def __init__(
        self,
        u: dolfinx.fem.Function,
        probes: dict[str, tuple[float, ...]],
        *,
        ground: Any = None,
        p0: float = 0.0,
        law: Any = None,
    ) -> None:
        self.u, self.names = u, list(probes)
        self.gdim = u.function_space.mesh.geometry.dim
        self.points = np.zeros((len(self.names), 3))
        for i, name in enumerate(self.names):
            self.points[i, : self.gdim] = probes[name][: self.gdim]
        labels = [f"output.probes.{n}" for n in self.names]
        self.cells = locate_points(u.function_space.mesh, self.points, labels)
        self.ground, self.p0, self.law = ground, p0, law
        #: (load factor, probe displacements shape=(num_probes, gdim)) per converged step,
        #: filled by :meth:`replay`.
        self.rows: list[tuple[float, np.ndarray]] = []

    def record(self) -> dict[str, list[float]]:
        """Evaluate the probes now (collective); the values by name (JSON-ready)."""
        values = probe(self.u, self.points, self.cells) if self.names else np.zeros((0, 2))
        return {n: [float(c) for c in values[i]] for i, n in enumerate(self.names)}

    def replay(self, steps: list[tuple[float, dict[str, list[float]]]]) -> None:
        """The rows from the converged steps' recorded values (a resumed run's included).

        Args:
            steps: (load factor, :meth:`record`'s values) of every converged step, in order.
        """
        shape = (len(self.names), self.gdim)
        self.rows = [(0.0, np.zeros(shape))] + [
            (f, np.array([v[n] for n in self.names], dtype=float).reshape(shape)) for f, v in steps
        ]

    def write_steps(self, path: Path) -> None:
        """``load_steps.csv``: load factor and every probe's u_x, u_y per converged step."""
        with open(path, "w", newline="") as f:
            w = csv.writer(f)
            axes = ("ux", "uy", "uz")[: self.gdim]
            w.writerow(["load_factor", *(f"{n}_{c}" for n in self.names for c in axes)])
            for factor, values in self.rows:
                w.writerow([f"{factor:.10g}", *(f"{v:.10g}" for v in values.ravel())])

    # -- the ground reaction curve ------------------------------------------------------

    def _closed_form_reason(self) -> str | None:
        """Why Salençon's closed form does not apply, or None when it does."""
        law, g = self.law, self.ground
        if not isinstance(law, MohrCoulomb) or law.tension is not None:
            return "the closed form is for Mohr-Coulomb without a tension cut-off"
        if not law.friction_angle > 0.0:
            return "the closed form needs friction_angle > 0"
        final = self.p0 + g.pressure
        if not (self.p0 > 0.0 and 0.0 <= final <= self.p0):
            return (
                "the closed form needs 0 <= p_i <= p0 with p0 > 0 "
                f"(p0 = {self.p0:g}, final p_i = {final:g})"
            )
        return None

    def _opening(self, pi: float) -> MohrCoulombOpening:
        law, g = self.law, self.ground
        radius = math.dist(self.points[self.names.index(g.probe), :2], g.centre)
        return MohrCoulombOpening(
            a=radius,
            b=g.outer_radius,
            p0=self.p0,
            pi=min(max(pi, 0.0), self.p0),
            E=law.E,
            nu=law.nu,
            cohesion=law.cohesion,
            friction_angle=law.friction_angle,
            dilatancy_angle=law.dilatancy_angle,
        )

    def curve(self) -> list[dict[str, float | None]]:
        """The ground reaction curve, one row per converged step (from λ = 0).

        Each row: the load factor λ, p_i = p0 + λ Δp, the wall's radial displacement
        u_r = u·(x − centre)/|x − centre| (negative: converging) and, where it applies,
        the closed form's u_r and plastic radius ρ (else None).
        """
        g = self.ground
        k = self.names.index(g.probe)
        x = self.points[k, :2] - np.asarray(g.centre)
        radial = x / np.linalg.norm(x)
        exact = self._closed_form_reason() is None
        out: list[dict[str, float | None]] = []
        for factor, values in self.rows:
            pi = self.p0 + factor * g.pressure
            row: dict[str, float | None] = {
                "load_factor": factor,
                "p_i": pi,
                "u_r": float(values[k] @ radial),
                "u_r_closed_form": None,
                "plastic_radius_closed_form": None,
            }
            if exact:
                opening = self._opening(pi)
                row["u_r_closed_form"] = opening.wall_displacement
                row["plastic_radius_closed_form"] = opening.plastic_radius
            out.append(row)
        return out

    def ground_reaction(self, directory: Path | None, *, title: str, units: Any) -> dict[str, Any]:
        """The summary's ``ground_reaction``; with ``directory`` (rank 0) its CSV and PNG."""
        g = self.ground
        curve = self.curve()
        reason = self._closed_form_reason()
        last = curve[-1]
        final: dict[str, Any] = {k: last[k] for k in ("load_factor", "p_i", "u_r")}
        if reason is None:
            assert last["u_r_closed_form"] is not None and last["u_r"] is not None
            final["u_r_closed_form"] = last["u_r_closed_form"]
            final["plastic_radius_closed_form"] = last["plastic_radius_closed_form"]
            exact = last["u_r_closed_form"]  # 0 where p_i = p0: no relative difference
            gap = last["u_r"] - exact
            final["relative_difference"] = gap / abs(exact) if exact != 0.0 else None
        entry: dict[str, Any] = {
            "probe": g.probe,
            "group": g.group,
            "p0": self.p0,
            "outer_radius": None if math.isinf(g.outer_radius) else g.outer_radius,
            "closed_form": reason or "Salençon (1969); Carranza-Torres and Fairhurst (1999)",
            "final": final,
        }
        if directory is not None:
            self._write_csv(curve, directory / "ground_reaction.csv")
            self._plot(curve, directory / "ground_reaction.png", title=title, units=units)
            entry["csv"], entry["png"] = "ground_reaction.csv", "ground_reaction.png"
        return entry

    def _write_csv(self, curve: list[dict[str, float | None]], path: Path) -> None:
        keys = list(curve[0])
        with open(path, "w", newline="") as f:
            w = csv.writer(f)
            w.writerow(keys)
            for row in curve:
                w.writerow(["" if row[k] is None else f"{row[k]:.10g}" for k in keys])

    def _plot(
        self, curve: list[dict[str, float | None]], path: Path, *, title: str, units: Any
    ) -> None:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        fig, ax = plt.subplots(figsize=(6, 4))
        pi = [float(r["p_i"] or 0.0) for r in curve]
        if curve[0]["u_r_closed_form"] is not None:
            fine = np.linspace(self.p0, min(pi), 101)
            exact = [-self._opening(float(p)).wall_displacement for p in fine]
            ax.plot(exact, fine, "k-", label="closed form (Salençon 1969)")
        ax.plot(
            [-float(r["u_r"] or 0.0) for r in curve],
            pi,
            "o",
            mfc="none",
            label="geofrac (load steps)",
        )
        ax.set_xlabel(units.label("wall convergence −u_r", "length"))
        ax.set_ylabel(units.label("internal pressure p_i", "stress"))
        ax.set_title(title)
        ax.legend()
        fig.tight_layout()
        fig.savefig(path, dpi=90)
        plt.close(fig)


def step_rows(records: Sequence[Any], *, probes: bool = False) -> list[dict[str, Any]]:
    """The results' rows of a phase's attempted steps (:class:`~geofrac.fem.plastic.StepRecord`).

    Factor, verdict, SNES reason, iterations (with the watchdog steps among them, joints
    only: :mod:`geofrac.solvers.snes`), final residual, plastic points and the
    reactions the step observed (None where nothing was observed); with ``probes`` the
    accepted steps' probe values too.
    """
    return [
        {
            "factor": s.factor,
            "accepted": s.accepted,
            "reason": s.report.reason_name,
            "iterations": s.report.iterations,
            "watchdog_steps": s.report.watchdog_steps,
            "residual": s.report.residuals[-1] if s.report.residuals else None,
            "plastic_points": s.plastic_points,
            "reactions": None if s.observed is None else s.observed["reactions"],
        }
        | ({"probes": s.observed["probes"]} if probes and s.accepted else {})
        for s in records
    ]
