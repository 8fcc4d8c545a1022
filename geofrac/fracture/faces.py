"""Crack-face contact in the event loop: the face pairs' blocks, states and joint properties.

The mechanics are pure numpy in :mod:`geofrac.fracture.contact`; this module maps them to
the global DOFs and the scene: friction and cohesion per edge from ``[cracking]``
(new cracks), ``[cracking.joints.NAME]`` (a ``precracked`` group or a DFN fracture set),
the stiffness blocks of the closed pairs for the assembly, and the signed block changes
(new − old) that the ``update`` solver folds into its factorisation
(:meth:`~geofrac.fracture.linear.UpdateSolver.contact_changed`).

Per event the loop's solve (:class:`~geofrac.fracture.equilibrium.ContactEquilibrium`)
runs an active-set iteration (solve, update the states, apply the changed blocks, solve
again) until no pair changes state, at most ``contact_iterations`` times; a state that
does not settle ends the run with ``end_reason = "contact"``.

With a fracture energy (material ``fracture_energy``) the faces of every edge cracked in
tension are *cohesive* (docs/cracking.md, "Fracture energy"): springs of the edge's
saw-tooth (:func:`~geofrac.fracture.softening.saw_tooth`). Its first tooth is the intact
edge: the stiffness of closed faces, k₀ = ``contact_penalty`` · E / L per unit area
(closed faces so held carry the intact load within 2 %, tests/fracture/
test_contact_mechanics.py), so cracking does not make the edge jump below the intact
stiffness; the crack's onset (the tension event) is that tooth's drop, each later drop
a ``"soften"`` event. Without ``cracking.contact`` only cohesive pairs exist: they start
open, close without friction (the penalty normal spring) and stop being pairs after
their last tooth (the brittle crack's free faces).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from geofrac.errors import RunError
from geofrac.fracture.contact import NO_PAIR, OPEN, ROUNDOFF, SLIP, FacePairs, pair_block
from geofrac.fracture.context import CrackContext, JsonValue, Sites, facet_nodes
from geofrac.fracture.softening import saw_tooth
from geofrac.fracture.units import Block, EdgeUnits

__all__ = [
    "PAIR_FIELDS",
    "Faces",
    "Softening",
    "contact_frame",
    "contact_summary",
    "joint_properties",
]

#: Per-pair arrays of :class:`~geofrac.fracture.contact.FacePairs` that a checkpoint keeps
#: (the operators and blocks follow from them and the fits).
PAIR_FIELDS = (
    "state",
    "sign",
    "bonded",
    "gap",
    "slip",
    "pressure",
    "shear",
    "frozen",
    "held_at",
    "violation",
)


def joint_properties(
    ctx: CrackContext, units: EdgeUnits, sites: Sites
) -> tuple[np.ndarray, np.ndarray]:
    """Friction μ and cohesion c per edge, each shape=(num_edges,) (collective).

    New cracks and pre-existing ones without an entry take ``cracking.friction`` and
    ``cracking.cohesion``; a ``joints`` entry naming a ``precracked`` group sets its
    edges; one naming a DFN fracture set sets the edges of that set's traces (matched
    to the meshed network, :func:`geofrac.dfn.check.match_facets`).
    """
    cfg = ctx.config
    ne = len(units.state.mesh.edges)
    mu = np.full(ne, cfg.crack_faces.friction)
    c = np.full(ne, cfg.crack_faces.cohesion)
    if not cfg.joints:
        return mu, c
    network = ctx.tagged.fractures
    mesh = units.state.mesh
    for name, props in cfg.joints:
        if name in cfg.precracked:
            pairs = np.sort(facet_nodes(ctx.tagged, ctx.gm, name), axis=1)
            edges = units.group_sites(pairs)
        else:
            from geofrac.dfn.check import match_facets

            set_of = network.network.set_index[network.edge_fracture]
            on = match_facets(mesh.coords[mesh.edges[sites.group]], network)
            ok = on >= 0
            chosen = np.zeros(len(on), dtype=bool)
            chosen[ok] = np.array(network.network.set_names)[set_of[on[ok]]] == name
            edges = sites.group[chosen]
        mu[edges] = props.friction
        c[edges] = props.cohesion
    return mu, c


@dataclass(frozen=True)
class Softening:
    """The saw-tooth of cohesive faces (docs/cracking.md, "Fracture energy").

    Attributes:
        tensile_strength: f_t, the first tooth's peak traction.
        fracture_energy: G_f per unit area.
        teeth: N, the number of teeth.
    """

    tensile_strength: float
    fracture_energy: float
    teeth: int


class Faces:
    """The face pairs of the crack state and what they add to the linear system.

    Args:
        ctx: the shared set-up data.
        units: the edge units (cells and their MLS fits).
        contact: crack-face contact (``cracking.contact``); False: cohesive pairs only.
        joints: friction μ and cohesion c per edge (:func:`joint_properties`), each
            shape=(num_edges,); None: no friction, no cohesion (cohesive faces only).
        penalty: the stiffness of closed faces (``contact_penalty``).
        softening: the cohesive faces' saw-tooth, or None (brittle cracks).
    """

    def __init__(
        self,
        ctx: CrackContext,
        units: EdgeUnits,
        *,
        contact: bool,
        joints: tuple[np.ndarray, np.ndarray] | None,
        penalty: float,
        softening: Softening | None,
    ) -> None:
        self.ctx, self.units = ctx, units
        #: crack-face contact (``cracking.contact``); False: cohesive pairs only.
        self.contact_on = contact
        if joints is None:  # cohesive faces close without friction
            mu = c = np.zeros(len(units.state.mesh.edges))
        else:
            mu, c = joints
        E = float(ctx.scene.material.E)
        self.pairs = FacePairs(
            units.state.mesh,
            mu,
            c,
            modulus=E,
            penalty=penalty,
            D=ctx.D,
            jump_floor=ROUNDOFF * ctx.scales.displacement,
            traction_floor=ROUNDOFF * ctx.scales.stress,
        )
        n_nodes = len(ctx.gm.coords)
        self._node_dofs = ctx.node_dofs(np.arange(n_nodes), 2).reshape(n_nodes, 2)
        #: the block of each pair as it is in the system now (absent: nothing).
        self.applied: dict[int, Block] = {}
        #: active-set iterations (solves after the first) over the run.
        self.iterations = 0
        #: most negative gap times the load factor over the run (penetration < 0).
        self.worst_gap = 0.0
        #: pairs held in their least violated state after a cycle, over the run, and
        #: the largest violation so held (units of the largest |g|, |s|).
        self.frozen_pairs = 0
        self.worst_violation = 0.0
        #: energy dissipated by the cohesive pairs' teeth so far (times the thickness).
        self.dissipated = 0.0
        self._softening = softening
        #: the first tooth's stiffness per unit area of each edge, E / d (module
        #: docstring), shape=(num_edges,); None without a fracture energy.
        self.k0: np.ndarray | None = None
        if softening is not None:
            self.k0 = self.pairs.k.copy()

    @property
    def softening(self) -> bool:
        """Whether cracked edges get cohesive faces (a fracture energy is given)."""
        return self.k0 is not None

    def _teeth(self, edges: np.ndarray) -> None:
        """Give the pairs ``edges`` their saw-tooth (collective-free: replicated).

        Raises:
            RunError: G_f is not above a first tooth's elastic energy (cells too large).
        """
        soft = self._softening
        assert self.k0 is not None and soft is not None
        if not len(edges):
            return
        try:
            st = saw_tooth(
                self.k0[edges],
                ft=soft.tensile_strength,
                gf=soft.fracture_energy,
                n=soft.teeth,
            )
        except ValueError as exc:
            raise RunError(
                f"material.fracture_energy: {exc} (edge {int(edges[0])}: refine the mesh, "
                "cells must be narrower than 2 E G_f / f_t²)"
            ) from None
        self.pairs.make_cohesive(edges, st.k, st.f)

    # -- the system ------------------------------------------------------------------
    def _block(self, edge: int) -> Block | None:
        b = pair_block(self.pairs, edge)
        if b is None:
            return None
        nodes, K = b
        return self.ctx.mls_dofs(nodes), self.ctx.t * K

    def owned_blocks(self) -> list[Block]:
        """The blocks of the pairs whose plus cell this rank owns (for the assembly)."""
        owned = self.units.owned
        return [b for e, b in self.applied.items() if owned[self.pairs.plus[e]]]

    def has_slip(self) -> bool:
        """Whether a slipping pair makes the system unsymmetric."""
        return bool(np.any(self.pairs.state[list(self.applied)] == SLIP)) if self.applied else False

    def _diff(self, edges: np.ndarray) -> list[Block]:
        """Bring ``applied`` to the pairs' state; the signed changes (old −, new +)."""
        out: list[Block] = []
        for e in np.unique(np.asarray(edges, dtype=np.int64)).tolist():
            old = self.applied.pop(e, None)
            new = self._block(e)
            if old is not None:
                out.append((old[0], -old[1]))
            if new is not None:
                out.append(new)
                self.applied[e] = new
        return out

    def start(self, cracked: np.ndarray) -> None:
        """Pairs of the edges cracked before loading (their blocks go into the assembly).

        Pre-cracked edges (notches, joints) are never cohesive: without contact they
        are no pairs.
        """
        if not self.contact_on:
            return
        new = self.pairs.add(cracked)
        self.pairs.refresh(new, self.units.state.fits, own=self.units.state.own_fits)
        self._diff(new)

    def cracked(
        self, edges: np.ndarray, changed_cells: np.ndarray, *, cohesive: bool = False
    ) -> list[Block]:
        """New pairs for ``edges`` and new operators where cells changed; the block changes.

        ``cohesive``: the edges cracked in tension with a fracture energy; their pairs get
        teeth (without contact, only such edges become pairs, open at first).
        """
        edges = np.asarray(edges, dtype=np.int64)
        if self.contact_on:
            new = self.pairs.add(edges)
        elif cohesive:
            new = self.pairs.add(edges, OPEN)
        else:
            new = np.zeros(0, dtype=np.int64)
        if cohesive and self.softening:
            self._teeth(new)
            for e in new.tolist():  # the crack's onset is the first tooth's drop
                energy, _ = self.pairs.soften(e)
                self.dissipated += energy * float(self.pairs.length[e]) * self.ctx.t
        touched = np.union1d(new, self.pairs.pairs_of_cells(changed_cells))
        self.release(touched)
        self.pairs.refresh(touched, self.units.state.fits, own=self.units.state.own_fits)
        return self._diff(touched)

    # -- the active set --------------------------------------------------------------
    def nodal(self, u: np.ndarray) -> np.ndarray:
        """Nodal displacements of a global solution, shape=(num_nodes, 2)."""
        return u[self._node_dofs]

    def update(self, u: np.ndarray) -> tuple[list[tuple[int, int, int]], list[Block]]:
        """One active-set step (:meth:`FacePairs.update`): (state changes, block changes)."""
        changes = self.pairs.update(self.nodal(u))
        blocks = self._diff(np.array([e for e, _, _ in changes], dtype=np.int64))
        return changes, blocks

    def soften(self, edge: int) -> list[Block]:
        """The pair's next tooth (a ``"soften"`` event); the block changes.

        Adds the tooth's dissipation times the edge's area L t to :attr:`dissipated`.
        After the last tooth a pair without contact is no pair any more.
        """
        energy, last = self.pairs.soften(edge)
        self.dissipated += energy * float(self.pairs.length[edge]) * self.ctx.t
        if last and not self.contact_on:
            self.pairs.remove(edge)
        return self._diff(np.array([edge], dtype=np.int64))

    def freeze_least_violated(self, history: dict[int, dict[int, tuple[float, float]]]) -> int:
        """Hold each pair that cycled in the state it violated least; returns how many.

        ``history``: per pair, per visited state, (violation, slip direction). The
        violations stay in :attr:`FacePairs.violation` and the results report the largest.
        """
        pairs = self.pairs
        held = []
        for e, seen in history.items():
            if len(seen) < 2:
                continue
            state = min(seen, key=lambda k: seen[k][0])
            pairs.state[e] = state
            pairs.sign[e] = seen[state][1]
            pairs.frozen[e] = True
            pairs.held_at[e] = seen[state][0]
            held.append(e)
        self.frozen_pairs += len(held)
        self.worst_violation = max(
            [self.worst_violation] + [history[e][int(pairs.state[e])][0] for e in held]
        )
        return len(held)

    def resync(self, edges: list[int]) -> list[Block]:
        """The block changes that bring the system to the pairs' states on ``edges``."""
        return self._diff(np.array(edges, dtype=np.int64))

    def release(self, edges: np.ndarray) -> None:
        """Let the active set change held pairs ``edges`` again (a cell beside them changed)."""
        self.pairs.frozen[np.asarray(edges, dtype=np.int64)] = False

    def record(self, r: float) -> dict[str, int | float]:
        """Counts and the worst gap of the settled state scaled by r (event log columns).

        The gap is the least over every pair, open ones included: a pair held open after
        a cycle may interpenetrate.
        """
        pairs = self.pairs
        act = pairs.active()
        gap = min(float(r * pairs.gap[act].min()), 0.0) if len(act) else 0.0
        self.worst_gap = min(self.worst_gap, gap)
        out: dict[str, int | float] = dict(pairs.counts())
        out["min_gap"] = gap
        return out

    # -- checkpoints -----------------------------------------------------------------
    def snapshot(self) -> tuple[dict[str, JsonValue], dict[str, np.ndarray]]:
        """The contact state now, for a checkpoint: (counters, arrays).

        The arrays are :data:`PAIR_FIELDS` on the pairs (``contact_edges``, sorted) and the
        pairs whose block is in the system, in the order they entered it
        (``contact_applied``: the assembly sums in that order), alike on every rank.
        """
        p = self.pairs
        edges = np.flatnonzero(p.state != NO_PAIR)
        arrays = {f"contact_{name}": getattr(p, name)[edges].copy() for name in PAIR_FIELDS}
        arrays["contact_edges"] = edges
        arrays["contact_applied"] = np.fromiter(self.applied, dtype=np.int64)
        counters: dict[str, JsonValue] = {
            "iterations": self.iterations,
            "frozen_pairs": self.frozen_pairs,
            "worst_violation": self.worst_violation,
        }
        if self.softening:  # the teeth follow from the mesh; the current tooth does not
            arrays["contact_tooth"] = p.tooth[edges].copy()
            counters["dissipated"] = self.dissipated
        return counters, arrays

    def restore(
        self, counters: dict[str, JsonValue], arrays: dict[str, np.ndarray], min_gaps: list[float]
    ) -> None:
        """Bring the pairs to a :meth:`snapshot` (the fits already rebuilt to match it).

        ``min_gaps``: the ``min_gap`` of every event in the restored log (the worst gap
        of the run so far).

        Raises:
            RunError: the snapshot does not fit this mesh or crack state.
        """
        p = self.pairs
        try:
            edges = arrays["contact_edges"].astype(np.int64)
            values = {name: arrays[f"contact_{name}"] for name in PAIR_FIELDS}
            applied = arrays["contact_applied"].astype(np.int64)
        except KeyError as exc:
            raise RunError(f"--resume: the checkpoint has no crack-face contact ({exc})") from None
        ne = len(p.state)
        lengths = {len(v) for v in values.values()} | {len(edges)}
        if np.any((edges < 0) | (edges >= ne)) or len(lengths) > 1:
            raise RunError("--resume: the checkpoint's face pairs do not match this mesh")
        p.state[:] = NO_PAIR
        for name, v in values.items():
            getattr(p, name)[edges] = v
        p.tooth[:] = -1
        p.teeth.clear()
        if self.softening:
            if "contact_tooth" not in arrays or len(arrays["contact_tooth"]) != len(edges):
                raise RunError("--resume: the checkpoint was written without fracture energy")
            tooth = arrays["contact_tooth"].astype(np.int64)
            cohesive = edges[tooth >= 0]
            self._teeth(cohesive)
            p.tooth[cohesive] = tooth[tooth >= 0]
            self.dissipated = float(counters["dissipated"])  # type: ignore[arg-type]
        p.ops.clear()
        p.refresh(edges, self.units.state.fits, own=self.units.state.own_fits)
        self.applied = {}
        for e in applied.tolist():
            block = self._block(e)
            if block is None:
                raise RunError(f"--resume: face pair {e} of the checkpoint carries nothing here")
            self.applied[e] = block
        self.iterations = int(counters["iterations"])  # type: ignore[arg-type]
        self.frozen_pairs = int(counters["frozen_pairs"])  # type: ignore[arg-type]
        self.worst_violation = float(counters["worst_violation"])  # type: ignore[arg-type]
        self.worst_gap = min([0.0, *min_gaps])


def contact_summary(faces: Faces, events: int, control: float) -> dict[str, int | float]:
    """The ``contact`` entry of the results.

    ``control``: the largest |control displacement| of the run (the gap's scale).
    """
    out: dict[str, int | float] = {"pairs": len(faces.pairs.active())}
    out |= faces.pairs.counts()
    out["bonded"] = int(np.count_nonzero(faces.pairs.bonded))
    out["worst_gap"] = faces.worst_gap
    out["worst_gap_relative"] = faces.worst_gap / control if control > 0 else 0.0
    out["frozen_pairs"] = faces.frozen_pairs
    out["worst_violation"] = faces.worst_violation
    out["iterations"] = faces.iterations
    out["iterations_per_event"] = faces.iterations / events if events else 0.0
    return out


def contact_frame(pairs: FacePairs, r: float) -> dict[str, np.ndarray]:
    """Per-edge fields of the crack series at load factor r (−1 state: no pair)."""
    ne = len(pairs.state)
    state = np.full(ne, -1.0)
    act = pairs.active()
    state[act] = pairs.state[act]
    p, tau = pairs.tractions(act)
    out = {"contact_state": state}
    for name, values in (
        ("gap", pairs.gap[act]),
        ("slip", pairs.slip[act]),
        ("normal_traction", p),
        ("shear_traction", tau),
    ):
        full = np.zeros(ne)
        full[act] = r * values
        out[name] = full
    return out
