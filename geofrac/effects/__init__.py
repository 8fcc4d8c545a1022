"""Effects registry: an effect's code is imported only when a scene declares it.

An effect is a module named in :data:`REGISTRY` that provides

- ``configure(table, ctx) -> config``: validate the scene's ``[<name>]`` table (may be
  empty) against the already validated material and dimension; raise
  :class:`~geofrac.model.errors.SceneError` naming the key. Must be cheap and must not
  import DOLFINx, PETSc, numba or cffi.
- optionally ``linear_form(config, ctx) -> ufl.Form``: a right-hand-side term of the
  elastic problem (see :class:`geofrac.fem.elastic.FormContext`); the run binds it to
  the config (:func:`linear_terms`) and hands it to the problem, which knows no effect.
- optionally ``geometry(table, file) -> (config, Geometry)``: the effect builds the
  scene's geometry (``dfn``); the scene then has no ``[geometry]`` table and the loader
  calls this instead of ``configure``. The returned
  :class:`~geofrac.model.scene.Geometry` carries a builder that makes the gmsh model on
  one rank.

- optionally ``STRAIGHT_CELLS = True``: the effect assumes straight cells (``cracking``:
  MLS-cracked cells); the loader refuses it on curved geometry
  (:attr:`geofrac.model.scene.Geometry.order` > 1).
- optionally ``result(config, scene, results) -> list[str]``: the effect's lines of the
  run's result block (:func:`geofrac.pipeline.report`) from the summary's ``results``:
  its headline numbers in the scene's ``[units]`` (:attr:`geofrac.model.scene.Scene.units`)
  and their differences from the references the scene names, worded by
  :mod:`geofrac.headline`; empty when ``results`` hold nothing of it (an MPM scene's).
  :func:`result_lines` collects them.
- optionally ``driver(config, solution, say, write)``: the effect replaces the single
  elastic solve by its own loop (``cracking``: the sequentially linear event loop); see
  :func:`geofrac.effects.cracking.driver`. A scene declares at most one such effect
  (the loader refuses two); :func:`driven` names it.

MPM scenes (``method = "mpm"``) use ``configure`` only: the MPM driver
(:mod:`geofrac.mpm.driver`) reads the validated configs of ``gravity``,
``mls_smoothing``, ``plasticity`` and ``friction`` and imports the engine code of an
effect only when it is declared; see ``docs/architecture.md``. Nothing in :mod:`geofrac`
imports an effect module except through :func:`load`.
"""

from __future__ import annotations

import functools
import importlib
from collections.abc import Sequence
from dataclasses import dataclass, field
from types import ModuleType
from typing import TYPE_CHECKING, Any

from geofrac.model.scene import BoundaryCondition, EffectSpec, Load, Material, Scene

if TYPE_CHECKING:
    from geofrac.fem.elastic import LinearTerm

__all__ = [
    "REGISTRY",
    "ConfigureContext",
    "available",
    "driven",
    "drives",
    "linear_terms",
    "load",
    "result_lines",
]

#: effect name -> module implementing it.
REGISTRY: dict[str, str] = {
    "cracking": "geofrac.effects.cracking",
    "dfn": "geofrac.effects.dfn",
    "dfn3d": "geofrac.effects.dfn3d",
    "friction": "geofrac.effects.friction",
    "gravity": "geofrac.effects.gravity",
    "joints": "geofrac.effects.joints",
    "mls_smoothing": "geofrac.effects.mls_smoothing",
    "plasticity": "geofrac.effects.plasticity",
}


@dataclass(frozen=True)
class ConfigureContext:
    """What an effect may look at while validating its table.

    Attributes:
        file: the scene file (for error messages).
        gdim: geometric dimension of the problem.
        material: the validated material (:class:`geofrac.model.scene.Material`).
        element: the scene's element name.
        groups: physical group name -> dimension of the scene's geometry.
        bcs: the validated Dirichlet conditions
            (:class:`geofrac.model.scene.BoundaryCondition`).
        method: the scene's ``method``, ``"fem"`` or ``"mpm"``. An effect module lists
            the methods it serves in ``METHODS`` (absent: ``("fem",)``); for MPM scenes
            ``groups`` names the walled grid sides and ``"bed"``.
        gradient_bc: the scene's ``discretization.gradient_bc``.
        previous: the configurations of the effects declared before this one, by name
            (``cracking`` reads the ``dfn`` fracture sets' names).
        loads: the validated loads (:class:`geofrac.model.scene.Load`; ``cracking``
            reads the one its ``control`` names).
        staged: the scene has ``[[stages]]`` (``cracking``: the stages' release is the
            control).
    """

    file: str
    gdim: int
    material: Material
    element: str = ""
    groups: dict[str, int] = field(default_factory=dict)
    bcs: tuple[BoundaryCondition, ...] = ()
    method: str = "fem"
    gradient_bc: str = "consistent"
    previous: dict[str, object] = field(default_factory=dict)
    loads: tuple[Load, ...] = ()
    staged: bool = False


def available() -> tuple[str, ...]:
    """Names of all registered effects, sorted."""
    return tuple(sorted(REGISTRY))


def load(name: str) -> ModuleType:
    """Import and return the module implementing effect ``name``."""
    return importlib.import_module(REGISTRY[name])


def drives(name: str) -> bool:
    """Whether effect ``name`` brings its own ``driver`` loop (imports its module)."""
    return hasattr(load(name), "driver")


def driven(effects: Sequence[EffectSpec[object]]) -> EffectSpec[object] | None:
    """The declared effect that brings its own ``driver`` loop, or None.

    The loader has checked that there is at most one.
    """
    owners = [spec for spec in effects if drives(spec.name)]
    assert len(owners) <= 1, f"more than one driver-owning effect: {owners}"
    return owners[0] if owners else None


def linear_terms(effects: Sequence[EffectSpec[object]]) -> list[LinearTerm]:
    """The ``linear_form`` hooks of the declared effects, bound to their configs."""
    terms: list[LinearTerm] = []
    for spec in effects:
        module = load(spec.name)
        if hasattr(module, "linear_form"):
            terms.append(functools.partial(module.linear_form, spec.config))
    return terms


def result_lines(scene: Scene, results: dict[str, Any]) -> list[str]:
    """The declared effects' lines of the result block, in declaration order.

    ``results``: the summary's ``results``. Each effect with a ``result`` hook gives its
    own (see the module text); the others give none.
    """
    lines: list[str] = []
    for spec in scene.effects:
        module = load(spec.name)
        if hasattr(module, "result"):
            lines += module.result(spec.config, scene, results)
    return lines
