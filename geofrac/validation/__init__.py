"""The validation suite (``geofrac validate``): cases, their references, and the page.

:mod:`geofrac.validation.cases` defines the cases (pure Python: the references and how to
read geofrac's value), each in one section of :data:`SECTIONS` (validation against the
physics, consistency with the scene's own inputs, reproduction of Edo (2016));
:mod:`geofrac.validation.suite` runs them and writes the page with its data (JSON).
"""

from geofrac.validation.cases import (
    CASES,
    CHAPTERS,
    CONSISTENCY,
    REPRODUCTION,
    SECTIONS,
    VALIDATION,
    Case,
    Reference,
    select,
)

__all__ = [
    "CASES",
    "CHAPTERS",
    "CONSISTENCY",
    "REPRODUCTION",
    "SECTIONS",
    "VALIDATION",
    "Case",
    "Reference",
    "select",
]
