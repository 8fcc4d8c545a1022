"""Crack propagation on element edges and grain interfaces: sites, fields, event driver.

Pure numpy modules: :mod:`~geofrac.fracture.topology`, :mod:`~geofrac.fracture.visibility`,
:mod:`~geofrac.fracture.cells`, :mod:`~geofrac.fracture.state`,
:mod:`~geofrac.fracture.grains`, :mod:`~geofrac.fracture.criterion`,
:mod:`~geofrac.fracture.direction`,
:mod:`~geofrac.fracture.woodbury`, :mod:`~geofrac.fracture.nonprop`. The driver
(:mod:`~geofrac.fracture.driver`) composes
parts behind protocols: :mod:`~geofrac.fracture.units` (the crack state's
discretisation), :mod:`~geofrac.fracture.event_criterion`,
:mod:`~geofrac.fracture.linear` (solver strategies, with
:mod:`~geofrac.fracture.incremental`), :mod:`~geofrac.fracture.assembly`,
:mod:`~geofrac.fracture.output` and :mod:`~geofrac.fracture.loop`, the loop of Fig. 2.6
over its parts :mod:`~geofrac.fracture.equilibrium` (solve),
:mod:`~geofrac.fracture.modes` (choose), :mod:`~geofrac.fracture.crack_update` (crack,
update), :mod:`~geofrac.fracture.record`, :mod:`~geofrac.fracture.replay` (checkpoints)
and :mod:`~geofrac.fracture.summary` (results); the grain variant is
:mod:`~geofrac.fracture.grain_driver`. Loads that stay constant while the others scale
(``cracking.constant``): :mod:`~geofrac.fracture.constant` and
:mod:`~geofrac.fracture.constant_loop`.
"""

__all__ = ["CRITERION_NAMES", "SOLVERS"]

#: Solvers of the event loop (``cracking.solver``), the default first.
SOLVERS = ("update", "reuse", "refactor")

#: Edge criteria (``cracking.criterion``), the default first
#: (:data:`~geofrac.fracture.event_criterion.CRITERIA`).
CRITERION_NAMES = ("direction", "traction", "principal")
