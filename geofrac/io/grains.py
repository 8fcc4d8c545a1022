"""EFMM integration domains ("grains") as polygons, written as VTU and XDMF + HDF5.

Each mesh node's integration domain (:func:`geofrac.elements.efmm_numpy.integration_domains`)
is a union of sub-triangles. :func:`grain_polygons` turns it into one simple polygon per
node: points shared between sub-triangles are bit-for-bit equal, so exact coordinate
equality identifies them; every sub-triangle is oriented counter-clockwise; directed edges
that occur both ways within one grain are interior and cancel; the edges left are chained
into the grain's boundary loop, which is then counter-clockwise. A grain whose boundary is
not one closed loop (a hole, two pieces, pieces touching at a point), or in which an edge
occurs twice the same way (overlapping sub-triangles), raises ``ValueError``; other
overlaps (a fan winding twice round a point) are not detected. Points on a straight part
of the boundary are kept (a boundary node lies between two boundary-edge midpoints); only
points on some grain's boundary are kept (an interior node's own point is not), sorted by
x, then y; each loop starts at its smallest point index.

Files (:func:`write_grains`), for a stem ``out/grains``:

``grains.vtu``
    pyvista ``UnstructuredGrid`` of ``VTK_POLYGON`` cells, points with z = 0.
``grains.xdmf`` + ``grains.h5``
    XDMF 3, one uniform grid; ``Mixed`` topology, per polygon the XDMF type id 3
    (Polygon), its number of points, then its point indices (``/topology``, int64);
    ``XYZ`` geometry with z = 0 (``/geometry``); each cell array an ``Attribute`` with
    ``Center="Cell"`` (``/cell_data/<name>``), ``AttributeType`` Scalar for 1 column,
    Vector for 3, Tensor for 9, otherwise Matrix.

Both files hold the cell arrays ``node`` and ``area`` and the caller's. The files are
written in a temporary folder beside them and moved into place at the end, so a file under
its final name is always complete. Grains may be non-convex: VTK's cell size filter
(ParaView's Cell Size, pyvista's ``compute_cell_sizes``) fans a polygon from its first
point and is right for convex polygons only; use the ``area`` array.
"""

from __future__ import annotations

import os
import shutil
import tempfile
import xml.etree.ElementTree as ET
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path

import h5py
import numpy as np
import pyvista as pv

from geofrac.io.series import hdf_item, hdf_put, write_xml

__all__ = ["XDMF_POLYGON", "Grains", "grain_polygons", "write_grains"]

#: XDMF 3 topology type id of a polygon in a ``Mixed`` topology.
XDMF_POLYGON = 3

#: numpy dtype kind and size -> XDMF NumberType.
_XDMF_NUMBER = {"f": "Float", "i": "Int", "u": "UInt"}
_XDMF_BYTE = {"i": "Char", "u": "UChar"}


@dataclass(frozen=True)
class Grains:
    """Grain polygons.

    Attributes:
        points: the polygons' points, unique, shape=(num_points, 2).
        offsets: polygon g is ``connectivity[offsets[g]:offsets[g + 1]]``,
            shape=(num_grains + 1,), int64.
        connectivity: each polygon's point indices counter-clockwise, no repeated closing
            point, shape=(offsets[-1],), int64.
        node: the node of each grain, ascending, shape=(num_grains,).
        area: each grain's area (sum of its sub-triangles' areas), shape=(num_grains,).
    """

    points: np.ndarray
    offsets: np.ndarray
    connectivity: np.ndarray
    node: np.ndarray
    area: np.ndarray

    @property
    def num_grains(self) -> int:
        """The number of grains."""
        return len(self.node)


def _unique_points(xy: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Unique rows by exact value: ``unique`` shape=(num_unique, 2), ``inverse`` shape=(n,)."""
    order = np.lexsort((xy[:, 1], xy[:, 0]))
    s = xy[order]
    new = np.ones(len(s), dtype=bool)
    new[1:] = (s[1:, 0] != s[:-1, 0]) | (s[1:, 1] != s[:-1, 1])
    inverse = np.empty(len(s), dtype=np.int64)
    inverse[order] = np.cumsum(new) - 1
    return s[new], inverse


def _fail(node: np.ndarray, grains: np.ndarray, what: str) -> ValueError:
    bad = np.unique(node[grains])
    shown = ", ".join(str(v) for v in bad[:10]) + (", ..." if len(bad) > 10 else "")
    return ValueError(f"grain of node(s) {shown}: {what}")


def grain_polygons(node: np.ndarray, corners: np.ndarray) -> Grains:
    """Each node's integration domain as one counter-clockwise polygon.

    Args:
        node: the node of each sub-triangle, shape=(num_sub,), integer.
        corners: each sub-triangle's corners, either orientation, shape=(num_sub, 3, 2);
            a point shared by sub-triangles must be the same floats in each. Sub-triangles
            of zero area are ignored.

    Returns:
        The grains, one per distinct node, ascending.

    Raises:
        ValueError: bad shapes or non-finite corners, or a grain whose boundary is not a
            single closed loop or in which two sub-triangles share an edge the same way.
    """
    node = np.asarray(node)
    corners = np.asarray(corners, dtype=float)
    if node.ndim != 1 or corners.shape != (len(node), 3, 2):
        raise ValueError(
            f"node shape={node.shape} and corners shape={corners.shape}: "
            "want (num_sub,) and (num_sub, 3, 2)"
        )
    if not np.isfinite(corners).all():
        raise ValueError("corners: not all finite")
    d1, d2 = corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0]
    signed = 0.5 * (d1[:, 0] * d2[:, 1] - d1[:, 1] * d2[:, 0])
    keep = signed != 0
    node, corners, signed = node[keep], corners[keep], signed[keep]
    grain_node, grain = np.unique(node, return_inverse=True)
    num_grains = len(grain_node)
    area = np.bincount(grain, weights=np.abs(signed), minlength=num_grains)
    xy, ids = _unique_points(corners.reshape(-1, 2))
    ids = ids.reshape(-1, 3)
    cw = signed < 0
    ids[cw] = ids[cw][:, [0, 2, 1]]  # counter-clockwise
    # number the (grain, point) pairs: q, ascending by grain, so one int64 names both
    gp_key, q = np.unique(
        np.repeat(grain, 3) * np.int64(len(xy)) + ids.ravel(), return_inverse=True
    )
    q_grain, q_point = np.divmod(gp_key, np.int64(len(xy)))
    # directed edges (a -> b) of every sub-triangle; an interior edge of a grain occurs once
    # each way in it and cancels
    q = q.reshape(-1, 3)
    a, b = q.ravel(), np.roll(q, -1, axis=1).ravel()
    key = np.minimum(a, b) * np.int64(len(gp_key)) + np.maximum(a, b)
    order = np.argsort(key)
    sorted_key = key[order]
    first = np.flatnonzero(np.append(True, sorted_key[1:] != sorted_key[:-1]))
    count = np.diff(np.append(first, len(order)))
    forward = np.add.reduceat(np.where(a[order] < b[order], 1, -1), first) if len(first) else first
    bad = (count > 2) | (np.abs(forward) > 1)
    if bad.any():
        wrong = q_grain[a[order[first[bad]]]]
        raise _fail(grain_node, wrong, "sub-triangles overlap (an edge occurs twice the same way)")
    edge = order[first[count == 1]]
    # chain the boundary edges: the next edge of a -> b is the one b -> .
    edge = edge[np.argsort(a[edge])]
    start, end = a[edge], b[edge]
    eg = q_grain[start]
    twice = np.flatnonzero(start[1:] == start[:-1])
    if len(twice):
        raise _fail(
            grain_node, eg[twice], "boundary is not a single closed loop (pieces touch at a point)"
        )
    nxt = np.minimum(np.searchsorted(start, end), len(start) - 1)
    open_end = np.flatnonzero(start[nxt] != end)
    if len(open_end):
        raise _fail(grain_node, eg[open_end], "boundary is not a single closed loop (open)")
    # nxt is now a permutation within each grain; walk every grain's loop at once
    per_grain = np.bincount(eg, minlength=num_grains)
    offsets = np.zeros(num_grains + 1, dtype=np.int64)
    np.cumsum(per_grain, out=offsets[1:])
    loops = np.empty(offsets[-1], dtype=np.int64)
    walked = np.zeros(num_grains, dtype=np.int64)
    active = np.flatnonzero(per_grain > 0)
    begin = offsets[active]  # each grain's first boundary edge (smallest start point)
    cur = begin.copy()
    step = 0
    while len(active):
        loops[offsets[active] + step] = q_point[start[cur]]
        step += 1
        cur = nxt[cur]
        done = cur == begin
        walked[active[done]] = step
        active, begin, cur = active[~done], begin[~done], cur[~done]
    several = np.flatnonzero(walked != per_grain)
    if len(several):
        raise _fail(grain_node, several, "boundary is not a single closed loop (a hole, or pieces)")
    used = np.zeros(len(xy), dtype=bool)
    used[loops] = True
    points = xy[used]
    connectivity = (np.cumsum(used) - 1)[loops]
    return Grains(points, offsets, connectivity.astype(np.int64), grain_node, area)


def _cell_arrays(grains: Grains, cell_data: Mapping[str, np.ndarray] | None) -> dict:
    """``node``, ``area`` and the caller's arrays, each shape=(num_grains,) or (num_grains, k)."""
    arrays = {"node": np.asarray(grains.node, dtype=np.int64), "area": grains.area}
    for name, given in (cell_data or {}).items():
        if name in arrays or not name or "/" in name:
            raise ValueError(f"cell array name {name!r} is reserved or not a valid name")
        values = np.asarray(given)
        if values.dtype == bool:
            values = values.astype(np.uint8)
        if values.dtype.kind not in "fiu":
            raise ValueError(f"cell array {name!r}: dtype {values.dtype} is not a real number")
        if values.ndim == 0 or len(values) != grains.num_grains:
            raise ValueError(
                f"cell array {name!r}: shape={values.shape}, want ({grains.num_grains}, ...)"
            )
        arrays[name] = values.reshape(grains.num_grains, -1) if values.ndim > 2 else values
    return arrays


def _attribute_type(values: np.ndarray) -> str:
    k = 1 if values.ndim == 1 else values.shape[1]
    return {1: "Scalar", 3: "Vector", 9: "Tensor"}.get(k, "Matrix")


def _data_item(parent: ET.Element, values: np.ndarray, h5_path: str) -> None:
    kind, size = values.dtype.kind, values.dtype.itemsize
    number = _XDMF_BYTE[kind] if size == 1 and kind in _XDMF_BYTE else _XDMF_NUMBER[kind]
    hdf_item(parent, " ".join(str(v) for v in values.shape), number, path=h5_path, precision=size)


def _write_vtu(path: Path, xyz: np.ndarray, grains: Grains, arrays: dict) -> None:
    n = np.diff(grains.offsets)
    stream = np.empty(len(grains.connectivity) + grains.num_grains, dtype=np.int64)
    head = grains.offsets[:-1] + np.arange(grains.num_grains)  # where each count goes
    stream[head] = n
    body = np.ones(len(stream), dtype=bool)
    body[head] = False
    stream[body] = grains.connectivity
    celltypes = np.full(grains.num_grains, pv.CellType.POLYGON, dtype=np.uint8)
    grid = pv.UnstructuredGrid(stream, celltypes, xyz)
    for name, values in arrays.items():
        grid.cell_data[name] = values
    grid.save(path)


def _write_xdmf(xdmf: Path, h5: Path, xyz: np.ndarray, grains: Grains, arrays: dict) -> None:
    n = np.diff(grains.offsets)
    stream = np.empty(len(grains.connectivity) + 2 * grains.num_grains, dtype=np.int64)
    head = grains.offsets[:-1] + 2 * np.arange(grains.num_grains)
    stream[head] = XDMF_POLYGON
    stream[head + 1] = n
    body = np.ones(len(stream), dtype=bool)
    body[head] = body[head + 1] = False
    stream[body] = grains.connectivity
    with h5py.File(h5, "w") as f:
        hdf_put(f, "geometry", xyz)
        hdf_put(f, "topology", stream)
        for name, values in arrays.items():
            hdf_put(f, f"cell_data/{name}", values)
    root = ET.Element("Xdmf", Version="3.0")
    grid = ET.SubElement(ET.SubElement(root, "Domain"), "Grid", Name=xdmf.stem, GridType="Uniform")
    top = ET.SubElement(
        grid, "Topology", TopologyType="Mixed", NumberOfElements=str(grains.num_grains)
    )
    _data_item(top, stream, f"{h5.name}:/topology")
    _data_item(ET.SubElement(grid, "Geometry", GeometryType="XYZ"), xyz, f"{h5.name}:/geometry")
    for name, values in arrays.items():
        attr = ET.SubElement(
            grid, "Attribute", Name=name, AttributeType=_attribute_type(values), Center="Cell"
        )
        _data_item(attr, values, f"{h5.name}:/cell_data/{name}")
    write_xml(root, xdmf)


def write_grains(
    stem: str | os.PathLike, grains: Grains, cell_data: Mapping[str, np.ndarray] | None = None
) -> list[Path]:
    """Write the grains as ``stem.vtu`` and ``stem.xdmf`` + ``stem.h5`` (module docstring).

    Args:
        stem: the files' path without suffix, e.g. ``out/grains``.
        grains: the polygons.
        cell_data: name -> values per grain, shape=(num_grains,) or (num_grains, k)
            (e.g. a stress tensor as (num_grains, 9); further axes are flattened into k);
            ``node`` and ``area`` are always written and may not be given.

    Returns:
        The paths written: ``[stem.vtu, stem.xdmf, stem.h5]``.
    """
    stem = Path(stem)
    arrays = _cell_arrays(grains, cell_data)
    xyz = np.zeros((len(grains.points), 3))
    xyz[:, :2] = grains.points
    final = [stem.with_name(stem.name + ext) for ext in (".vtu", ".xdmf", ".h5")]
    stem.parent.mkdir(parents=True, exist_ok=True)
    work = Path(tempfile.mkdtemp(prefix=f".{stem.name}.", suffix=".tmp", dir=stem.parent))
    try:
        vtu, xdmf, h5 = (work / p.name for p in final)
        _write_vtu(vtu, xyz, grains, arrays)
        _write_xdmf(xdmf, h5, xyz, grains, arrays)
        for path in (vtu, h5, xdmf):  # the h5 before the xdmf that points to it
            path.replace(stem.parent / path.name)
    finally:
        shutil.rmtree(work, ignore_errors=True)
    return final
