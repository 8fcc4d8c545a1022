"""UFL forms of geofrac (imported as :mod:`geofrac_forms`).

Only :mod:`ufl` is imported here: the forms are pure symbolic definitions that
DOLFINx compiles. Material constants enter as arguments (normally
``dolfinx.fem.Constant``) so that a compiled kernel is reused when values change.
"""

__all__: list[str] = []
