"""What drives the events: the control group's unit load and how it is reported.

A sequentially linear run solves the *unit load* (every load and prescribed displacement
of the scene as given) and scales it by r (Edo (2016), eqs. 2.20-2.21). The event log
reports the control group's displacement and force at each event; :class:`Control` says
how, for the two kinds of ``cracking.control``:

- *displacement control*, a ``[[bc]]`` group with a non-zero prescribed displacement:
  the control displacement is r δ, δ the mean |prescribed displacement| of its DOFs, and
  the reaction is r times the unit solution's force on those DOFs (signed by the
  prescribed direction; :meth:`~geofrac.fracture.units.Units.measures`);
- *force control*, a traction, pressure or point ``[[load]]`` group: the reaction is r F,
  F the magnitude of the resultant of the group's unit nodal forces f (shape=(n,)), and
  the control displacement is r δ_u, δ_u = f·u / F the displacement work-conjugate to
  the load (f·u is the work of the unit load on the unit solution u), or, with
  ``control_point``, the displacement of the node nearest to that point along the
  resultant. A self-equilibrated load (a pressure in a hole: |resultant| below
  :data:`SELF_EQUILIBRATED` of Σ|f_i|) has F = Σ|f_i|, the sum of the nodal forces'
  magnitudes, so that δ_u is then the mean displacement along the load;
- *release*, a cracking scene with ``[[stages]]`` (docs/insitu.md, "Stages in a cracking
  scene"): λ is the share of a stage's excavation release; no group is controlled, so
  the control displacement and force are 0 and the stages' summary reports the release
  (:mod:`~geofrac.fracture.staged`).

Pure numpy: the caller assembles f (:meth:`~geofrac.fem.elastic.ElasticProblem.load_part`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = [
    "FORCE_LOADS",
    "KINDS",
    "RELEASE",
    "SELF_EQUILIBRATED",
    "Control",
    "displacement_control",
    "force_control",
    "release_control",
]

#: The kinds of ``cracking.control``.
KINDS = ("displacement", "force", "release")

#: The ``cracking.control`` of a cracking scene with ``[[stages]]``: the stages' release.
RELEASE = "release"

#: ``[[load]]`` types whose group may be the control (force control); a body force acts
#: on no group.
FORCE_LOADS = ("traction", "pressure", "point")

#: A control load whose resultant is below this fraction of the sum of its nodal forces'
#: magnitudes Σ|f_i| is self-equilibrated (a pressure on a closed boundary: zero in exact
#: arithmetic, round-off of about 1e-16 Σ|f_i|; a load on one side of a specimen has a
#: resultant of order Σ|f_i|). Its F is Σ|f_i| instead of the resultant.
SELF_EQUILIBRATED = 1e-6


@dataclass(frozen=True)
class Control:
    """How the control group's load is measured at each event.

    Attributes:
        kind: ``"displacement"`` or ``"force"`` (:data:`KINDS`).
        group: the ``cracking.control`` group.
        unit: displacement control: δ, the mean |prescribed displacement| of the control
            DOFs; force control: F, the magnitude of the unit load's resultant (Σ|f_i|
            when self-equilibrated).
        scale: the a-priori displacement of the unit load that the loop's decisions are
            judged against (:class:`~geofrac.fracture.scales.Scales`): δ, or F/(E t).
        weights: force control: f / F, the control load's unit nodal forces over F, so
            that δ_u = weights·u, shape=(n_global,); None under displacement control.
        direction: force control: the unit vector of the resultant, shape=(2,); None
            under displacement control or for a self-equilibrated load.
        node: force control with ``control_point``: the node whose displacement along
            ``direction`` is reported (gathered-mesh numbering), else None.
        node_dofs: that node's two translation DOFs, shape=(2,), or None.
        resultant: force control: the resultant (R_x, R_y) of the unit load, shape=(2,).
    """

    kind: str
    group: str
    unit: float
    scale: float
    weights: np.ndarray | None = None
    direction: np.ndarray | None = None
    node: int | None = None
    node_dofs: np.ndarray | None = None
    resultant: np.ndarray | None = None

    def measure(self, u: np.ndarray, reaction: float) -> tuple[float, float]:
        """(control displacement, force) of the unit solution ``u``, shape=(n_global,).

        ``reaction``: the unit solution's signed force on the control DOFs
        (displacement control; ignored under force control, where the force is F).
        """
        if self.kind == "displacement":
            return self.unit, reaction
        if self.kind == RELEASE:  # no group: the stages' summary reports the release
            return 0.0, 0.0
        if self.node_dofs is not None:
            assert self.direction is not None
            return float(u[self.node_dofs] @ self.direction), self.unit
        assert self.weights is not None
        return float(self.weights @ u), self.unit

    def describe(self, input_ids: np.ndarray, coords: np.ndarray) -> dict[str, object]:
        """The results' ``control`` entry (summary.json).

        Args:
            input_ids: the mesh file's node index of each node, shape=(num_nodes,).
            coords: node coordinates, shape=(num_nodes, 2).
        """
        out: dict[str, object] = {"group": self.group, "kind": self.kind}
        if self.kind == "displacement":
            out["unit_displacement"] = self.unit
            return out
        if self.kind == RELEASE:
            out["displacement_scale"] = self.scale
            return out
        assert self.resultant is not None
        out |= {
            "unit_force": self.unit,
            "resultant": [float(c) for c in self.resultant],
            "self_equilibrated": self.direction is None,
            "displacement_scale": self.scale,
        }
        if self.node is not None:
            out["point_node"] = int(input_ids[self.node])
            out["point_xy"] = [float(c) for c in coords[self.node]]
        return out


def displacement_control(group: str, prescribed: np.ndarray) -> Control:
    """Displacement control by the non-zero prescribed values of ``group``, shape=(k,)."""
    delta = float(np.mean(np.abs(prescribed))) if len(prescribed) else 0.0
    return Control("displacement", group, delta, delta)


def force_control(
    group: str,
    forces: np.ndarray,
    *,
    bs: int,
    modulus: float,
    thickness: float,
    point_dofs: tuple[int, np.ndarray] | None = None,
) -> Control:
    """Force control by the unit nodal forces ``forces`` of the group's load.

    Args:
        group: the ``cracking.control`` group.
        forces: the load vector of the control load alone on all DOFs (replicated,
            global numbering: ``bs`` DOFs per node, the two translations first),
            shape=(n_global,).
        bs: DOFs per node.
        modulus: E of the a-priori displacement scale F/(E t).
        thickness: t of that scale.
        point_dofs: ``control_point``'s nearest node and its two translation DOFs,
            shape=(2,), or None.

    Raises:
        ValueError: the load is zero, or ``point_dofs`` is given for a self-equilibrated
            load (no direction to read the displacement along).
    """
    f = np.asarray(forces, dtype=float)
    nodal = np.column_stack([f[0::bs], f[1::bs]])  # shape=(num_nodes, 2)
    resultant = nodal.sum(axis=0)
    total = float(np.hypot(nodal[:, 0], nodal[:, 1]).sum())
    if not total > 0.0:
        raise ValueError(f"the [[load]] on '{group}' gives no nodal force")
    size = float(np.hypot(*resultant))
    balanced = size <= SELF_EQUILIBRATED * total
    direction = None if balanced else resultant / size
    unit = total if balanced else size
    node = dofs = None
    if point_dofs is not None:
        if direction is None:
            raise ValueError(
                f"the [[load]] on '{group}' is self-equilibrated (resultant {size:.3g}, "
                f"below {SELF_EQUILIBRATED:g} of the sum of its nodal forces {total:.3g}): "
                "there is no direction to read control_point's displacement along"
            )
        node, dofs = point_dofs
    return Control(
        "force",
        group,
        unit,
        unit / (modulus * thickness),
        weights=f / unit,
        direction=direction,
        node=node,
        node_dofs=dofs,
        resultant=resultant,
    )


def release_control(scale: float) -> Control:
    """The control of a staged cracking run: λ scales a stage's release.

    ``scale``: the release's a-priori displacement (|σ0| L / E), > 0.
    """
    return Control(RELEASE, RELEASE, 1.0, float(scale))
