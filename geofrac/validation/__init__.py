"""The validation suite (``geofrac validate``): cases, their references, and the page.

:mod:`geofrac.validation.cases` defines the cases (pure Python: the references and how to
read geofrac's value); :mod:`geofrac.validation.suite` runs them and writes
``docs/validation.md`` with its data ``docs/validation.json``.
"""

from geofrac.validation.cases import CASES, CHAPTERS, Case, Reference, select

__all__ = ["CASES", "CHAPTERS", "Case", "Reference", "select"]
