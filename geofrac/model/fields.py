"""Names of the probe fields' components (pure data, shared by evaluation and files).

The fields a probe or line may report are ``geofrac.scene.load.PROBE_FIELDS``;
:func:`geofrac.fem.post.probe_fields` evaluates them and :mod:`geofrac.io.lines` writes
them under these column names.
"""

from __future__ import annotations

__all__ = ["COMPONENT_INDEX", "field_columns", "tensor_components"]


def tensor_components(gdim: int) -> tuple[str, ...]:
    """Names of the components a probed stress or strain reports, in order.

    2D: ``xx, yy, zz, xy`` (zz of the analysis plane); 3D: ``xx, yy, zz, xy, yz, xz``.
    Strain components are tensor components (ε_xy = γ_xy / 2).
    """
    return ("xx", "yy", "zz", "xy") if gdim == 2 else ("xx", "yy", "zz", "xy", "yz", "xz")


#: Component name -> (row, column) of the 3 × 3 tensor.
COMPONENT_INDEX = {
    "xx": (0, 0),
    "yy": (1, 1),
    "zz": (2, 2),
    "xy": (0, 1),
    "yz": (1, 2),
    "xz": (0, 2),
}


def field_columns(field: str, gdim: int) -> tuple[str, ...]:
    """Column names of probe field ``field`` (``geofrac.scene.load.PROBE_FIELDS``)."""
    if field == "displacement":
        return tuple(f"u_{a}" for a in "xyz"[:gdim])
    if field in ("stress", "strain"):
        return tuple(f"{field}_{c}" for c in tensor_components(gdim))
    if field == "principal_stress":
        return ("stress_1", "stress_2", "stress_3")
    return (field,)
