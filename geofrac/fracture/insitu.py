"""An initial (in-situ) stress in a cracking run: part of the constant load.

With ``[initial_stress]`` (docs/insitu.md) a cracking scene runs the loop of loads that do
not scale together (:mod:`~geofrac.fracture.constant`; DeJong, Hendriks and Rots (2008)):
the stress at a crack site is σ0 + σ_c + λ σ_v, where σ0 is the pure field of
:mod:`geofrac.geometry.insitu` at the site's points (each cell's edge midpoints, where the
criteria read the cells' stress) and σ_c, σ_v are the stresses of the constant and the
variable solutions, both measured from the initial state. The constant right-hand side
carries, besides the ``cracking.constant`` groups' loads, the out-of-balance force of σ0 on
the *current* crack state,

  F0 = F_ext,0 − I(σ0),   I(σ0) = t Σ_cells ∫ Bᵀ σ0 dA,

F_ext,0 the forces the initial state carries (σ0·n on the ``loaded`` sides and the
effects' terms, gravity, assembled by DOLFINx as in :mod:`geofrac.fem.stages`), I the
internal force through each cell's own strain operator: the element's for an intact cell
(six-point rule, exact for the RGNT/GNT strain times a linear σ0), the MLS fit's for a
cracked cell (constant strain: its area times Bᵀ of σ0's cell mean), nothing for a void
cell. On the intact mesh F0 is round-off for an equilibrated σ0 (checked, as the FEM path
does); once edges crack, it is the release of the traction σ0·n that the new crack
faces no longer carry. I is kept as the intact cells' sum plus, per event, the change of
the cracked cells, so only those are reassembled.

With crack-face contact (``cracking.contact``) a closed pair carries the initial traction
σ0·n of its edge (:class:`~geofrac.fracture.constant_contact.ConstantFaces`): the
constant right-hand side holds, besides F0, the closed pairs' initial tractions F_p, and
the pre-cracked state with every pair closed is the initial state, in balance:

  F = F0 + F_p − R,   R = F0 + F_p of the pre-cracked state with every pair stuck,

so a joint that stays closed and stuck moves nothing at λ = 0. R is, for a uniform σ0,
mostly the MLS cells' patch-test residual on the edges around the joint (a linear fit's
t A Bᵀ σ0 is t ∮ N σ0·n ds over the cell's sides, so on the joint's own edges F0 is
−F_p; measured, F_p takes the largest |F0| of docs/cracking.md's joint from 17.3 to
5.1); it is reported (``contact_initial.residual``) and not released. A pair that
opens (or slips) releases its initial traction (or the shear beyond friction) through
F_p; a new crack's release through F0 as without contact.
"""

from __future__ import annotations

from typing import Any

import dolfinx_solver  # noqa: F401  (orders MPI before the DOLFINx bindings)

import dolfinx
import numpy as np
import ufl
from mpi4py import MPI

from geofrac.errors import RunError
from geofrac.fem.insitu import in_plane, stress_field
from geofrac.fem.solution import Solution
from geofrac.fem.stages import TOLERANCE, refusal
from geofrac.fracture.cells import MIDPOINTS, strain_operator
from geofrac.fracture.config import CrackingConfig, LoopSettings
from geofrac.fracture.consistent import void_sides
from geofrac.fracture.constant import ConstantChooser, ConstantLoad, constant_load
from geofrac.fracture.constant_loop import ConstantEventLoop
from geofrac.fracture.contact import ROUNDOFF
from geofrac.fracture.context import CrackContext, JsonValue, Sites, crack_context, gather_vector
from geofrac.fracture.criterion import edge_means
from geofrac.fracture.equilibrium import Solved
from geofrac.fracture.event_criterion import EdgeCriterion
from geofrac.fracture.loop import LoopParts, _Run
from geofrac.fracture.modes import Choice
from geofrac.fracture.units import GAUSS_6, EdgeUnits, mls_settings
from geofrac.geometry.insitu import column_weight, evaluate, surface_height
from geofrac.io.checkpoint import RunControl
from geofrac.mls.shape import LinearFit, strain_matrix
from geofrac.solvers import assemble_vector
from geofrac_forms import elasticity as forms

__all__ = [
    "RESIDUAL_WARNING",
    "InitialStressLoad",
    "InsituEventLoop",
    "checked_initial_stress",
    "initial_balance",
    "initial_stress_at",
    "insitu_loop",
]


#: The closed joints' residual R (module docstring), relative to the largest applied force,
#: above which a run warns: the discretisation error σ0 leaves on the pre-cracked mesh is
#: then larger than the loads (measured: 0.056 on jobs/joint_slip_opening.toml,
#: 0.51 on tests/fracture/scenes/joint_insitu.toml, 45 on the DFN tunnel of docs/insitu.md).
RESIDUAL_WARNING = 1.0


def _cell_regions(ctx: CrackContext) -> np.ndarray:
    """The cell group tag of every cell of the gathered mesh, shape=(nc,); -1 if none."""
    mesh = ctx.tagged.mesh
    n_own = mesh.topology.index_map(2).size_local
    local = np.full(n_own, -1, dtype=np.int64)
    tags = ctx.tagged.tags.get(2)
    if tags is not None:
        mine = tags.indices < n_own
        local[tags.indices[mine]] = tags.values[mine]
    out = np.full(len(ctx.gm.cells), -1, dtype=np.int64)
    out[ctx.gm.local_cell[:n_own]] = local
    ctx.comm.Allreduce(MPI.IN_PLACE, out, op=MPI.MAX)
    return out


def initial_stress_at(ctx: CrackContext, bary: np.ndarray) -> np.ndarray:
    """σ0 (Voigt, tension positive) at barycentric points of every cell, shape=(nc, nq, 3).

    The pure field of :mod:`geofrac.geometry.insitu` with the cell groups as regions; a
    geostatic field with a density per group integrates the column above each point
    through the gathered triangles, as the FEM path does.

    Args:
        ctx: the crack context (its scene has an ``[initial_stress]``).
        bary: barycentric coordinates, shape=(nq, 3).
    """
    spec = ctx.scene.initial_stress
    assert spec is not None
    field = stress_field(spec, ctx.tagged)
    gm = ctx.gm
    corners = gm.coords[gm.cells]  # shape=(nc, 3, 2)
    points = np.einsum("qk,ckd->cqd", bary, corners).reshape(-1, 2)
    regions = _cell_regions(ctx)
    point_regions = np.repeat(regions, len(bary))
    column = None
    try:
        if field.kind == "geostatic" and field.layered:
            rho = np.full(len(gm.cells), field.density)
            for region, value in field.densities.items():
                rho[regions == region] = value
            top = surface_height(field, points[:, 0])
            column = column_weight(points, corners, rho, surface=top, above=field.density)
        voigt = evaluate(field, points, point_regions, column=column)
    except ValueError as exc:
        raise RunError(f"initial_stress.surface: {exc}") from None
    return voigt.reshape(len(gm.cells), len(bary), 3)


class InitialStressLoad:
    """σ0 at the sites and its out-of-balance force F0 on the current crack state.

    Args:
        ctx: the crack context (a scene with ``[initial_stress]``).
        units: the edge units (their crack state and owned cells).

    Attributes:
        site_stress: σ0 at each cell's edge midpoints, shape=(nc, 3, 3) ([cell, local
            edge, component]): :attr:`ConstantLoad.extra_stress`.
        held_terms: the effects' terms (gravity) on the unknowns, gathered,
            shape=(n_global,): part of F_ext,0, so not of the variable load.
        balance: the intact state's largest |F0| on the free DOFs over the largest
            applied force.
    """

    def __init__(self, ctx: CrackContext, units: EdgeUnits) -> None:
        self.ctx, self.units = ctx, units
        gm, own = ctx.gm, units.own
        self.site_stress = initial_stress_at(ctx, MIDPOINTS)
        bary, w = GAUSS_6
        sigma = initial_stress_at(ctx, bary)  # shape=(nc, 6, 3)
        #: σ0's mean over each cell (the MLS cells' constant strain), shape=(nc, 3).
        self.cell_mean = np.einsum("q,cqi->ci", w, sigma)
        weight = ctx.t * units.state.areas
        B = strain_operator(ctx.spec, gm.coords[gm.cells[own]], bary)  # (n_own, 6, 3, nd)
        #: t ∫ Bᵀ σ0 dA of each owned cell's element field, shape=(n_own, nd).
        self.fe_force = weight[own, None] * np.einsum("q,cqip,cqi->cp", w, B, sigma[own])
        intact = np.zeros(ctx.n_global)
        np.add.at(intact, units.fe_dofs, self.fe_force)
        ctx.comm.Allreduce(MPI.IN_PLACE, intact, op=MPI.SUM)
        external, self.held_terms = self._external()
        #: F_ext,0 − I(σ0) of the intact mesh, shape=(n_global,).
        self.base = external - intact
        scale = max(float(np.max(np.abs(a), initial=0.0)) for a in (external, intact))
        free = np.ones(ctx.n_global, dtype=bool)
        free[ctx.bc_rows] = False
        worst = float(np.max(np.abs(self.base[free]), initial=0.0))
        self.balance = worst / scale if scale > 0.0 else 0.0
        #: the larger of |F_ext,0| and |I(σ0)| (the balance's scale).
        self.scale = scale
        self.free = free
        self.position = {int(c): i for i, c in enumerate(own)}

    def _external(self) -> tuple[np.ndarray, np.ndarray]:
        """(F_ext,0, the effects' terms alone) on the unknowns, gathered, shape=(n_global,)."""
        problem, comm = self.ctx.problem, self.ctx.comm
        spec = self.ctx.scene.initial_stress
        assert spec is not None and problem.insitu is not None
        V = problem.element.space
        v = ufl.TestFunction(V)
        gdim = problem.mesh.geometry.dim
        traction = in_plane(problem.insitu.sigma0, gdim) * ufl.FacetNormal(problem.mesh)
        ds, t = problem.ds, problem.thickness
        loaded = [
            forms.traction_form(v, traction, t, ds(problem.tagged.groups[g][1]))
            for g in spec.loaded
        ]
        terms = [term(problem.form_context(v)) for term in problem.terms]
        zero = ufl.inner(dolfinx.fem.Constant(problem.mesh, np.zeros(gdim)), v) * problem.dx
        out = []
        for part in (loaded + terms, terms):
            form: Any = sum(part, zero)
            b = problem._on_unknowns(assemble_vector(dolfinx.fem.form(form)))
            try:
                out.append(gather_vector(b, comm))
            finally:
                b.destroy()
        return out[0] + 0.0, out[1]

    def force(self) -> np.ndarray:
        """F0 = F_ext,0 − I(σ0) on the current crack state, shape=(n_global,) (collective).

        The intact mesh's F0 plus, for every owned cracked cell, its element field's
        t ∫ Bᵀ σ0 dA (no longer there) minus its MLS fit's t A Bᵀ σ̄0 (none when void).
        """
        ctx, units = self.ctx, self.units
        state = units.state
        keeps = state.fits is not state.own_fits  # consistent cells: void ones keep σ0
        dead = getattr(state, "removed", None)
        change = np.zeros(ctx.n_global)
        for c, fit in state.fits.items():
            i = self.position.get(int(c))
            if i is None:
                continue
            np.add.at(change, units.fe_dofs[i], self.fe_force[i])
            if fit is None:
                if keeps and (dead is None or not dead[c]):
                    self._void_force(change, int(c), dead)
                continue
            assert isinstance(fit, LinearFit)
            weight = ctx.t * units.state.areas[c]
            f = weight * strain_matrix(fit).T @ self.cell_mean[c]
            np.add.at(change, ctx.mls_dofs(fit.nodes), -f)
        ctx.comm.Allreduce(MPI.IN_PLACE, change, op=MPI.SUM)
        return self.base + change

    def _void_force(self, change: np.ndarray, c: int, dead: np.ndarray | None) -> None:
        """Subtract void cell c's t Σ_sides (σ̄0 L n) w from ``change`` (it keeps σ0)."""
        ctx, state = self.ctx, self.units.state
        s = self.cell_mean[c]
        sigma = np.array([[s[0], s[2]], [s[2], s[1]]])
        for nodes, weights, ln in void_sides(
            c,
            mesh=state.mesh,
            own=state.own_fits,
            cracked=state.cracked,
            node_cracks=state.node_cracks,
            dead=dead,
        ):
            f = ctx.t * np.outer(weights, sigma @ ln)  # shape=(q, 2)
            np.add.at(change, ctx.mls_dofs(nodes), -f.ravel())


class InsituEventLoop(ConstantEventLoop):
    """The constant-load loop whose constant right-hand side follows the crack state.

    Args:
        ctx, parts, sites, settings, control, load, chooser: as
            :class:`~geofrac.fracture.constant_loop.ConstantEventLoop`.
        insitu: σ0 at the sites and its out-of-balance force.
    """

    def __init__(
        self,
        ctx: CrackContext,
        parts: LoopParts,
        sites: Sites,
        *,
        settings: LoopSettings,
        control: RunControl | None,
        load: ConstantLoad,
        chooser: ConstantChooser,
        insitu: InitialStressLoad,
    ) -> None:
        super().__init__(
            ctx, parts, sites, settings=settings, control=control, load=load, chooser=chooser
        )
        self.insitu = insitu
        lo, hi = ctx.row0, ctx.row0 + ctx.n_local
        #: the constant groups' loads (owned entries), shape=(n_local,).
        self.named = np.array(load.constant.load.getArray(readonly=True), dtype=float)
        self._rows = slice(lo, hi)
        self._sigma0_reaction = 0.0
        #: with contact: F0 + F_p of the pre-cracked state with every pair stuck (the
        #: module docstring's R), shape=(n_global,); its largest free entry over the scale.
        self._reference: np.ndarray | None = None
        self.residual = 0.0

    def _fresh(self, space: dolfinx.fem.FunctionSpace) -> _Run:
        """The pre-cracked state; with contact, σ0 on the pairs and their initial states.

        A resumed run starts from it too (R is the pre-cracked state's), then restores.
        """
        run = super()._fresh(space)
        if self.faces is not None:
            insitu, faces = self.insitu, self.faces
            edge_stress = edge_means(self.parts.units.state.mesh, insitu.site_stress)
            faces.set_initial(edge_stress)
            self._reference = insitu.force() + faces.force()
            units = self.parts.units
            used = insitu.free & (units.use_counts(units.state.is_mls()) > 0)
            worst = float(np.max(np.abs(self._reference[used]), initial=0.0))
            self.residual = worst / insitu.scale if insitu.scale > 0.0 else 0.0
            faces.start_states(ROUNDOFF * float(np.max(np.abs(edge_stress), initial=0.0)))
            self.ctx.say(
                f"cracking: the initial stress on {len(faces.faces.pairs.active())} face "
                f"pairs: {faces.started_open} open (tension), {faces.started_slipping} slip "
                "before any release (initial shear beyond c + μ p0); the closed joints' "
                f"residual {self.residual:.2e} of the applied force is not released"
            )
            if self.residual > RESIDUAL_WARNING:
                state = self.parts.units.state
                remedy = (
                    "Where joints end on a loaded or supported side, the boundary's loads "
                    "and the cells' own fits there differ; keep joints off those sides"
                    if state.fits is not state.own_fits
                    else "Use cracking.mls_gradient = 'consistent' (docs/cracking.md, "
                    "'Integration-consistent MLS cells')"
                )
                self.ctx.say(
                    f"warning: the closed joints' residual is {self.residual:.3g} times the "
                    "largest applied force: the MLS cells beside the joints carry σ0 with "
                    "an error larger than the loads, and every cell whose fit a crack or a "
                    "removal changes releases its share of it as a spurious force (cracks "
                    f"at λ = 0 that are not physics). {remedy} (docs/insitu.md)"
                )
        return run

    def _initial_force(self) -> np.ndarray:
        """σ0's force on the current state, shape=(n_global,) (collective).

        F0 of the current crack state; with contact, plus the closed pairs' σ0·n minus
        the pre-cracked state's R (module docstring): zero while nothing changed.
        """
        force = self.insitu.force()
        if self.faces is not None:
            assert self._reference is not None
            force = force + self.faces.force() - self._reference
        return force

    def _solve(self, run: _Run, event: int, *, replay: bool) -> Solved | None:
        """Reassemble F0 (and the closed pairs' σ0·n) on the current state; solve both loads."""
        force = self._initial_force()
        base = self.insitu.base if self.faces is None else np.zeros_like(force)
        self.load.constant.load.setArray(self.named + force[self._rows])
        # the control DOFs' share of I(σ0) that cracks moved: −(F0 − F0 of the initial
        # state: the intact mesh, or the pre-cracked one with contact)
        sign = self.ctx.control_sign[:-1]
        self._sigma0_reaction = -float(sign @ (force - base))
        return super()._solve(run, event, replay=replay)

    def _choose(self, run: _Run, event: int) -> Choice | None:
        """The constant load's reaction, relative to the initial state, includes σ0's change.

        Under displacement control the reaction is I(σ) − I(σ0 on the intact mesh) on the
        control DOFs: the cells' K u plus I(σ0) on the current crack state minus on the
        intact mesh (an MLS fit that reaches a control node carries σ0 there).
        """
        choice = super()._choose(run, event)
        if self.ctx.control.kind == "displacement":
            energy, disp, force, cross = self._const
            self._const = (energy, disp, force + self._sigma0_reaction, cross)
        return choice

    def _finish(self, run: _Run, unknown: dolfinx.fem.Function) -> dict[str, JsonValue]:
        """The results, with ``initial_stress``: its kind and the intact state's balance."""
        results = super()._finish(run, unknown)
        spec = self.ctx.scene.initial_stress
        assert spec is not None
        results["initial_stress"] = {
            "kind": spec.kind,
            "out_of_balance": self.insitu.balance,
            "tolerance": TOLERANCE,
        }
        if self.faces is not None:
            results["contact_initial"] = {
                "open": self.faces.started_open,
                "slipping": self.faces.started_slipping,
                "residual": self.residual,
            }
        return results


def checked_initial_stress[L: InitialStressLoad](
    ctx: CrackContext,
    parts: LoopParts,
    kind: type[L],
    *,
    key: str,
    role: str,
) -> tuple[L, EdgeCriterion]:
    """σ0 at the sites of an edge-cracking run, its balance said and checked (collective).

    ``kind`` builds the load from (ctx, units); ``key`` names the scene key in the
    refusal of grain interfaces; ``role`` ends the line said about the balance.

    Raises:
        RunError: collectively, for grain interfaces or an initial state out of balance
            (beyond :data:`~geofrac.fem.stages.TOLERANCE`, as the FEM path).
    """
    units, criterion = parts.units, parts.criterion
    if not isinstance(units, EdgeUnits) or not isinstance(criterion, EdgeCriterion):
        raise RunError(f"{key}: cracking at element edges only (not grain interfaces)")
    insitu = kind(ctx, units)
    spec = ctx.scene.initial_stress
    assert spec is not None
    ctx.say(
        f"initial stress ({spec.kind}): out of balance {insitu.balance:.2e} of the applied "
        f"force (tolerance {TOLERANCE:g}); {role}"
    )
    if insitu.balance > TOLERANCE:
        raise RunError(refusal(insitu.balance))
    return insitu, criterion


def insitu_loop(
    ctx: CrackContext,
    parts: LoopParts,
    sites: Sites,
    *,
    settings: LoopSettings,
    control: RunControl | None,
) -> InsituEventLoop:
    """The loop of a cracking scene with ``[initial_stress]`` (collective).

    Checks the initial state's balance on the intact mesh (refused beyond
    :data:`~geofrac.fem.stages.TOLERANCE`, as the FEM path), moves the effects' terms
    (gravity) from the variable to the constant load and sets σ0 at the sites.

    Raises:
        RunError: collectively, when the initial state is out of balance.
    """
    insitu, criterion = checked_initial_stress(
        ctx,
        parts,
        InitialStressLoad,
        key="initial_stress",
        role="it is held constant while the control load scales",
    )
    load = constant_load(ctx, ctx.config)
    if np.any(insitu.held_terms):
        owned = insitu.held_terms[ctx.row0 : ctx.row0 + ctx.n_local]
        b_var = load.variable.load
        b_var.setArray(np.array(b_var.getArray(readonly=True)) - owned)
    load.extra_stress = insitu.site_stress
    parts.assembler.case = load.variable
    return InsituEventLoop(
        ctx,
        parts,
        sites,
        settings=settings,
        control=control,
        load=load,
        chooser=ConstantChooser(criterion, insitu.units, ctx.config),
        insitu=insitu,
    )


def initial_balance(config: object, solution: Solution) -> float:
    """The intact state's out-of-balance ratio of :class:`InitialStressLoad` (collective).

    What ``geofrac check`` reports for a cracking scene: the crack driver's own cell
    operators (the RGNT/GNT vertex DOFs included), no solve. ``config``: the
    validated ``[cracking]`` settings (a :class:`CrackingConfig`).
    """
    assert isinstance(config, CrackingConfig)
    ctx = crack_context(config, solution, lambda _: None)
    units = EdgeUnits(ctx, mls=mls_settings(config), cut=False, keep_stress=False)
    return InitialStressLoad(ctx, units).balance
