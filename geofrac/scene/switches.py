"""Validate the per-stage switching of ``[[load]]`` and ``[[bc]]`` entries (docs/scenes.md).

A load or a support may be switched on at the start of a stage (``from = "NAME"``) and
off at the start of a later one (``until = "NAME"``); without them it acts from the
initial step to the end. The physics is in :mod:`geofrac.fem.stages` (docs/insitu.md,
"Loads and supports per stage").
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

from geofrac import effects
from geofrac.model.errors import SceneError, did_you_mean
from geofrac.model.scene import BoundaryCondition, Load, acts
from geofrac.model.table import Table

__all__ = ["SWITCH_KEYS", "stage_names", "switch_keys", "switched", "switches"]

#: Keys of a ``[[load]]`` or ``[[bc]]`` entry that switch it per stage.
SWITCH_KEYS = ("from", "until")


def switch_keys(t: Table) -> tuple[str | None, str | None]:
    """``from`` and ``until`` of one entry, as given (names checked by :func:`switches`)."""
    on = t.string("from") if t.has("from") else None
    off = t.string("until") if t.has("until") else None
    return on, off


def switched(bcs: Sequence[BoundaryCondition], loads: Sequence[Load]) -> frozenset[str]:
    """The stage names some load or support is switched at (a stage may do only that)."""
    entries: list[BoundaryCondition | Load] = [*bcs, *loads]
    names = [x for e in entries for x in (e.switch_on, e.switch_off)]
    return frozenset(n for n in names if n is not None)


def _index(file: Path, key: str, name: str, names: Sequence[str]) -> int:
    """The step of stage ``name`` (1 for the first stage)."""
    if not names:
        raise SceneError(
            file, key, "needs [[stages]]: it names the stage at whose start the entry switches"
        )
    if name not in names:
        raise SceneError(file, key, f"unknown stage '{name}'" + did_you_mean(name, names))
    return list(names).index(name) + 1


def stage_names(raw: Any) -> list[str]:
    """The names of the raw ``[[stages]]`` entries (their keys are checked later)."""
    if not isinstance(raw, list):
        return []
    return [e["name"] for e in raw if isinstance(e, dict) and isinstance(e.get("name"), str)]


def switches(
    file: Path,
    names: Sequence[str],
    *,
    bcs: Sequence[BoundaryCondition],
    loads: Sequence[Load],
    declared: Sequence[str],
) -> None:
    """Check the ``from``/``until`` names of every load and support.

    Called before the stages' own checks (:func:`stage_names` of the raw entries), so
    that a misspelt name is reported as such.

    Each must name a stage of the scene, ``until`` a stage after ``from``; a support
    installed in a stage has a number ``value`` (its displacement increment); every step
    must hold some ``[[bc]]`` (else the problem is singular); the run must be the elastic
    staged run (no effect that drives the run), or, for loads only, a cracking run with
    stages (:func:`geofrac.scene.insitu.stages` checks their kind).

    Raises:
        SceneError: naming the entry's key.
    """
    entries: list[tuple[str, BoundaryCondition | Load]] = []
    entries += [(f"bc[{i}]", e) for i, e in enumerate(bcs)]
    entries += [(f"load[{i}]", e) for i, e in enumerate(loads)]
    for where, e in entries:
        if e.switch_on is None and e.switch_off is None:
            continue
        owners = [n for n in declared if effects.drives(n)]
        if owners == ["cracking"] and isinstance(e, BoundaryCondition):
            raise SceneError(
                file,
                f"{where}.{'from' if e.switch_on is not None else 'until'}",
                "a cracking scene switches loads per stage, not supports: install support "
                "with a stage's 'add' (docs/insitu.md, 'Stages in a cracking scene')",
            )
        if owners and owners != ["cracking"]:
            raise SceneError(
                file,
                f"{where}.{'from' if e.switch_on is not None else 'until'}",
                f"effect '{owners[0]}' drives the run with its own loop; loads and supports "
                "switched per stage are available in elastic staged runs only",
            )
        on = 0 if e.switch_on is None else _index(file, f"{where}.from", e.switch_on, names)
        if e.switch_off is not None:
            off = _index(file, f"{where}.until", e.switch_off, names)
            if off <= on:
                raise SceneError(
                    file,
                    f"{where}.until",
                    f"stage '{e.switch_off}' is not after the stage it is switched on at "
                    f"('{e.switch_on}'): 'until' names a later stage",
                )
        if isinstance(e, BoundaryCondition) and e.switch_on is not None and e.value == "exact":
            raise SceneError(
                file,
                f"{where}.value",
                "'exact' applies from the initial step only: a support installed in a stage "
                "holds its current displacement plus a number value (an increment)",
            )
    for step in range(len(names) + 1):
        if not any(acts(bc, step, names) for bc in bcs):
            when = "the initial step" if step == 0 else f"stage '{names[step - 1]}'"
            raise SceneError(
                file,
                "bc",
                f"no [[bc]] is active in {when} ('from'/'until'): the elastic problem would "
                "be singular",
            )
