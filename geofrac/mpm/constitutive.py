"""MPM constitutive models: the protocol a material follows, and the registry of models.

A model is one module named in :data:`MODELS` (docs/mpm.md, "Adding a constitutive
model"). The registry key is the scene's name for it: the effect that selects it
(``plasticity``: Drucker-Prager), or :data:`DEFAULT` (``elastic``), the material of a
scene that declares none. The module provides

- ``from_scene(E, nu, config) -> ConstitutiveModel``: the model of the scene's
  ``[material]`` E, ν and its effect's validated config (None for the default);
- the model class, which satisfies :class:`ConstitutiveModel`.

The step (:func:`geofrac.mpm.schemes.step`) asks the model for the stress update and
keeps the kinematics (volume D.9, deformation gradient 4.70, cpGIMP half-widths 4.69)
to itself; the time step (4.72) and the energies (:mod:`~geofrac.mpm.energy`) ask it for
the wave speed, the stored energy and the dissipation. Elastic constants come from
:mod:`geofrac.materials` only.

Importing this module imports no model: :func:`load` imports one when a scene uses it.
"""

from __future__ import annotations

import importlib
from collections.abc import Iterable
from types import ModuleType
from typing import TYPE_CHECKING, ClassVar, Protocol

import numpy as np

if TYPE_CHECKING:
    from geofrac.mpm.energy import StepBudget
    from geofrac.mpm.particles import Particles

__all__ = [
    "DEFAULT",
    "MODELS",
    "ConstitutiveModel",
    "available",
    "load",
    "model_effects",
    "select",
]

#: Scene name of a model (the effect that selects it, or DEFAULT) -> its module.
MODELS: dict[str, str] = {
    "elastic": "geofrac.mpm.elastic",
    "plasticity": "geofrac.mpm.plasticity",
}

#: The model of a scene that declares no model effect.
DEFAULT = "elastic"


class ConstitutiveModel(Protocol):
    """What the MPM step, the time step and the energy budget ask of a material.

    Attributes:
        name: the model's key in :data:`MODELS`.
        dims: the particle dimensions it serves (e.g. ``(2, 3)``: plane strain and 3D).
        state: the :class:`~geofrac.mpm.particles.Particles` arrays its update writes
            (the per-particle state it keeps between steps; every array of the
            particles migrates between ranks and is checkpointed).
        compiled: whether its ``numba`` update is compiled; the step then updates
            volume and deformation gradient with the compiled loop too, else with
            numpy (whose matmul rounds differently: a numpy model's results stay those
            of the numpy kinematics on either backend).
    """

    name: ClassVar[str]
    dims: ClassVar[tuple[int, ...]]
    state: ClassVar[tuple[str, ...]]
    compiled: ClassVar[bool]

    @property
    def E(self) -> float:
        """Young's modulus."""
        ...

    @property
    def nu(self) -> float:
        """Poisson's ratio (0 in 1D)."""
        ...

    def wave_speed(self, density: float, dim: int) -> float:
        """The fastest elastic wave c of the time step Δt = α L / c (eq. 4.72)."""
        ...

    def stored_energy(self, p: Particles) -> np.ndarray:
        """The elastic energy ½ V_p σ_p : D⁻¹ : σ_p stored in the stresses, shape=(n,)."""
        ...

    def results(self) -> dict[str, float]:
        """What the model adds to ``summary.json``'s ``results`` (e.g. its parameters)."""
        ...

    def stress_update(
        self,
        p: Particles,
        deps: np.ndarray,
        L: np.ndarray,
        *,
        dt: float,
        backend: str,
        budget: StepBudget | None,
    ) -> None:
        """Turn and update the stresses of ``p`` in place for one strain increment.

        In 2D and 3D σ is first turned by the Jaumann rate, σ + σ Δω − Δω σ
        (D.30-D.31, :func:`geofrac.mpm.rotation.rotate_stress` with
        :func:`~geofrac.mpm.rotation.spin_increment`; plane strain's σ_zz does not turn),
        then the constitutive increment is added. Only the arrays of :attr:`state`
        change; volume, deformation gradient and half-widths are the step's.

        Args:
            p: the particles (their volume is still the one at the update's start).
            deps: strain increments Δε, shape=(n, dim, dim).
            L: velocity gradients ∇v, shape=(n, dim, dim).
            dt: the step of this update.
            backend: ``numba`` (compiled loops where the model has them) or ``numpy``;
                the two agree to round-off.
            budget: add the energy the update dissipates to ``budget.plastic``
                (stored energy of the rotated elastic trial minus that after the
                update, at the updated volume V (1 + tr Δε)); None: compute nothing.
        """
        ...


def available() -> tuple[str, ...]:
    """Names of all registered models, sorted."""
    return tuple(sorted(MODELS))


def load(name: str) -> ModuleType:
    """Import and return the module of model ``name``."""
    return importlib.import_module(MODELS[name])


def model_effects() -> tuple[str, ...]:
    """The scene effects that select a model (every registered model but the default)."""
    return tuple(n for n in MODELS if n != DEFAULT)


def select(effects: Iterable[str]) -> str:
    """The model a scene's declared effects choose: its one model effect, else DEFAULT.

    Raises:
        ValueError: more than one model effect is declared.
    """
    chosen = [e for e in effects if e in MODELS and e != DEFAULT]
    if len(chosen) > 1:
        raise ValueError(f"one material model per scene; declared: {', '.join(chosen)}")
    return chosen[0] if chosen else DEFAULT
