"""The event loop's parts on their own: the contact settle of the solve step."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from geofrac.fracture.equilibrium import (
    ContactEquilibrium,
    ContactUnsettled,
    LinearEquilibrium,
    Solved,
)


class _Faces:
    """Scripted crack faces: ``update`` returns the next list of state changes."""

    def __init__(self, script: list[list[tuple[int, int, int]]]) -> None:
        self.script = list(script)
        self.pairs = SimpleNamespace(
            violation=np.zeros(4), sign=np.ones(4), state=np.zeros(4, dtype=np.int8)
        )
        self.iterations = 0
        self.frozen: list[int] = []

    def update(self, u: np.ndarray) -> tuple[list[tuple[int, int, int]], list]:
        changes = self.script.pop(0) if self.script else []
        for e, _, new in changes:
            self.pairs.state[e] = new
        return changes, []

    def freeze_least_violated(self, history: dict) -> int:
        self.frozen += list(history)
        return len(history)

    def resync(self, edges: list[int]) -> list:
        return []


class _Strategy:
    def __init__(self) -> None:
        self.changed: list[list] = []

    def contact_changed(self, blocks: list) -> None:
        self.changed.append(blocks)


def _equilibrium(faces: _Faces, iterations: int) -> ContactEquilibrium:
    eq = ContactEquilibrium(_Strategy(), faces, iterations)  # type: ignore[arg-type]
    eq.solve = lambda u: Solved(u + 1.0, 7)  # type: ignore[method-assign]
    return eq


def test_linear_equilibrium_has_nothing_to_settle():
    solved = Solved(np.zeros(3), 2)
    assert LinearEquilibrium(_Strategy()).settle(solved) is solved  # type: ignore[arg-type]


def test_settle_solves_again_until_no_pair_changes():
    faces = _Faces([[(1, 1, 0)], [(2, 1, 2)]])
    out = _equilibrium(faces, 5).settle(Solved(np.zeros(2), 3))
    assert out.changes == [(1, 1, 0), (2, 1, 2)]
    assert out.iterations == 3  # the first solve's
    assert np.array_equal(out.u, np.full(2, 2.0))  # two more solves
    assert faces.iterations == 2


def test_a_pair_returning_to_a_state_it_left_is_held():
    faces = _Faces([[(1, 1, 0)], [(1, 0, 1)]])
    _equilibrium(faces, 5).settle(Solved(np.zeros(2), 0))
    assert faces.frozen == [1]


def test_faces_that_do_not_settle_end_the_event():
    faces = _Faces([[(e % 4, 1, 0)] for e in range(10)])
    with pytest.raises(ContactUnsettled, match="did not settle in 2 iterations"):
        _equilibrium(faces, 2).settle(Solved(np.zeros(2), 0))
