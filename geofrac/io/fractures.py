"""The fracture-surface file: a joint's faces as triangles with their values (VTU, ParaView).

One rank writes (the faces and their values are the same on every rank). The file is an
unstructured grid of triangles, one per joint face, its cell data the face's values
(opening, slip, tractions, contact state, set), for ParaView beside the volume fields of
``results.xdmf`` (docs/output.md).
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path

import numpy as np

__all__ = ["write_fracture_faces"]


def write_fracture_faces(
    path: Path, faces: np.ndarray, cell_data: Mapping[str, np.ndarray]
) -> Path:
    """Write triangles with per-triangle values as a VTU file.

    Args:
        path: the ``.vtu`` file.
        faces: the triangles' vertices, shape=(k, 3, 3).
        cell_data: name -> values per triangle, shape=(k,) or (k, c).

    Returns:
        The path.

    Raises:
        ValueError: an array's length is not the number of triangles.
    """
    import pyvista as pv

    k = len(faces)
    for name, values in cell_data.items():
        if len(values) != k:
            raise ValueError(f"fracture faces: {name!r} has {len(values)} values, {k} faces")
    points = np.asarray(faces, dtype=float).reshape(-1, 3)
    cells = np.column_stack([np.full(k, 3), np.arange(3 * k).reshape(k, 3)]).ravel()
    grid = pv.UnstructuredGrid(cells, np.full(k, pv.CellType.TRIANGLE, dtype=np.uint8), points)
    for name, values in cell_data.items():
        grid.cell_data[name] = np.asarray(values)
    grid.save(str(path))
    return Path(path)
