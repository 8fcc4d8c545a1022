"""A time series of fields on a fixed mesh, written by one process as XDMF + HDF5.

The crack driver keeps the whole crack state on every rank, so rank 0 writes the crack
picture itself: one HDF5 file with the mesh once and a dataset per field and step, and an
XDMF temporal collection that ParaView, pyvista and meshio read. The XML is rewritten
after every step, so an interrupted run leaves a readable series of the steps done.

Each time appears once: writing a step at the time of the last one replaces it (VTK's
XDMF reader shows an empty mesh for a time listed twice). A resumed run continues a
series with ``keep_until``: the steps after that time, which the interrupted run may have
written after its checkpoint, are dropped.
"""

from __future__ import annotations

import os
import tempfile
import xml.etree.ElementTree as ET
from pathlib import Path

import h5py
import numpy as np

__all__ = [
    "XdmfSeries",
    "hdf_item",
    "hdf_put",
    "kept_steps",
    "temporal_collection",
    "write_xml",
]

_TOPOLOGY = {2: "Polyline", 3: "Triangle"}

#: gzip level of the series' datasets: 1 is near disk speed; higher levels gain little.
GZIP_LEVEL = 1


def hdf_put(group: h5py.Group, name: str, values: np.ndarray) -> None:
    """Store ``values`` as dataset ``name``, gzip-compressed with byte shuffling.

    HDF5's deflate filter is built into every HDF5 library, so ParaView's XDMF reader,
    h5py and meshio read the data unchanged; empty arrays are stored plain, and so is
    everything if this h5py has no deflate filter (see :mod:`geofrac`: h5py must be
    imported before the PETSc wheel's HDF5).
    """
    values = np.asarray(values)
    if values.size == 0 or not h5py.h5z.filter_avail(h5py.h5z.FILTER_DEFLATE):
        group[name] = values
        return
    group.create_dataset(
        name, data=values, compression="gzip", compression_opts=GZIP_LEVEL, shuffle=True
    )


class XdmfSeries:
    """Fields over steps on one mesh of lines or triangles.

    Args:
        path: the ``.xdmf`` file; the data go to the sibling ``.h5``.
        coords: node coordinates, shape=(num_nodes, 2).
        cells: node ids per cell, shape=(num_cells, 2) (lines) or (num_cells, 3).
        keep_until: continue the series in ``path`` with its steps of time <= this
            (a resumed run); None starts a new series.
    """

    def __init__(
        self,
        path: Path,
        coords: np.ndarray,
        cells: np.ndarray,
        *,
        keep_until: float | None = None,
    ) -> None:
        self.path = Path(path)
        self.h5 = self.path.with_suffix(".h5")
        self.num_nodes, self.num_cells = len(coords), len(cells)
        self.nv = cells.shape[1]
        self.steps: list[tuple[float, list[tuple[str, str, int]]]] = []
        #: why an existing series could not be continued (it was started anew), or None.
        self.note: str | None = None
        if keep_until is not None and self.h5.exists():
            try:
                self._continue(np.asarray(coords), np.asarray(cells), keep_until)
                return
            except (OSError, KeyError, ValueError) as exc:
                self.steps = []
                self.note = f"{self.path.name}: cannot continue the series ({exc}); started anew"
        xyz = np.zeros((len(coords), 3))
        xyz[:, : coords.shape[1]] = coords
        with h5py.File(self.h5, "w") as f:
            hdf_put(f, "mesh/geometry", xyz)
            hdf_put(f, "mesh/topology", np.asarray(cells, dtype=np.int64))
        if self.note is not None:
            self._write_xml()  # no step: the old XML named data that is gone

    def _continue(self, coords: np.ndarray, cells: np.ndarray, keep_until: float) -> None:
        """Reopen the series, dropping its steps after ``keep_until``.

        A step is kept when its group holds the attributes :meth:`write` sets last (its
        time, field names and centres) and every step before it is kept.

        Raises:
            OSError, KeyError, ValueError: the files are unreadable or of another mesh.
        """
        with h5py.File(self.h5, "a") as f:
            geometry, topology = f["mesh/geometry"][()], f["mesh/topology"][()]
            if not (
                np.array_equal(topology, cells)
                and geometry.shape == (len(coords), 3)
                and np.array_equal(geometry[:, : coords.shape[1]], coords)
            ):
                raise ValueError(f"{self.h5.name} holds another mesh")
            for t, group in kept_steps(f, "step_", keep_until):
                names = [n for n in str(group.attrs.get("fields", "")).split(",") if n]
                centres = str(group.attrs.get("centres", "")).split(",")
                fields = [
                    (n, c, group[n].shape[1] if group[n].ndim == 2 else 1)
                    for n, c in zip(names, centres, strict=True)
                ]
                self.steps.append((t, fields))
        self._write_xml()

    def write(
        self,
        t: float,
        point_data: dict[str, np.ndarray] | None = None,
        cell_data: dict[str, np.ndarray] | None = None,
    ) -> None:
        """Append a step at time ``t`` (or replace the last step, if it has that time).

        Args:
            t: the step's time value (the event number for the crack driver).
            point_data: name -> values, shape=(num_nodes,) or (num_nodes, k).
            cell_data: name -> values, shape=(num_cells,) or (num_cells, k).
        """
        t = float(t)
        if self.steps and self.steps[-1][0] == t:
            self.steps.pop()
        i = len(self.steps)
        fields = []
        with h5py.File(self.h5, "a") as f:
            if f"step_{i}" in f:
                del f[f"step_{i}"]
            for centre, data in (("Node", point_data or {}), ("Cell", cell_data or {})):
                for name, given in data.items():
                    values = np.asarray(given, dtype=float)
                    if values.ndim == 2 and values.shape[1] == 2:  # ParaView wants 3D vectors
                        values = np.column_stack([values, np.zeros(len(values))])
                    hdf_put(f, f"step_{i}/{name}", values)
                    fields.append((name, centre, values.shape[1] if values.ndim == 2 else 1))
            group = f.require_group(f"step_{i}")
            group.attrs["t"] = t
            group.attrs["fields"] = ",".join(n for n, _, _ in fields)
            group.attrs["centres"] = ",".join(c for _, c, _ in fields)
        self.steps.append((t, fields))
        self._write_xml()

    def _write_xml(self) -> None:
        h5 = self.h5.name
        root, series = temporal_collection(self.path.stem)
        for i, (t, fields) in enumerate(self.steps):
            grid = ET.SubElement(series, "Grid", Name=f"step_{i}", GridType="Uniform")
            top = ET.SubElement(
                grid,
                "Topology",
                TopologyType=_TOPOLOGY[self.nv],
                NumberOfElements=str(self.num_cells),
                NodesPerElement=str(self.nv),
            )
            hdf_item(top, f"{self.num_cells} {self.nv}", "Int", path=f"{h5}:/mesh/topology")
            geo = ET.SubElement(grid, "Geometry", GeometryType="XYZ")
            hdf_item(geo, f"{self.num_nodes} 3", "Float", path=f"{h5}:/mesh/geometry")
            ET.SubElement(grid, "Time", Value=repr(t))
            for name, centre, k in fields:
                n = self.num_nodes if centre == "Node" else self.num_cells
                attr = ET.SubElement(
                    grid,
                    "Attribute",
                    Name=name,
                    AttributeType="Vector" if k > 1 else "Scalar",
                    Center=centre,
                )
                dims = f"{n} {k}" if k > 1 else f"{n}"
                hdf_item(attr, dims, "Float", path=f"{h5}:/step_{i}/{name}")
        write_xml(root, self.path)


def kept_steps(f: h5py.File, prefix: str, keep_until: float) -> list[tuple[float, h5py.Group]]:
    """The steps ``<prefix>0, <prefix>1, ...`` of an open series file that a resumed run keeps.

    A step is kept when its group carries its time (written last, so the step is
    complete), the time is <= ``keep_until`` and every step before it is kept; every
    other step group is deleted from ``f``.

    Returns:
        (time, group) of the kept steps, in order.
    """
    numbered = sorted(
        (int(name[len(prefix) :]), name)
        for name in f
        if name.startswith(prefix) and name[len(prefix) :].isdigit()
    )
    kept: list[tuple[float, h5py.Group]] = []
    for i, name in numbered:
        t = float(f[name].attrs.get("t", np.inf))
        if t > keep_until or i != len(kept):
            del f[name]
        else:
            kept.append((t, f[name]))
    return kept


def temporal_collection(name: str) -> tuple[ET.Element, ET.Element]:
    """An XDMF 3 root and its temporal collection grid, to which steps are added."""
    root = ET.Element("Xdmf", Version="3.0")
    series = ET.SubElement(
        ET.SubElement(root, "Domain"),
        "Grid",
        Name=name,
        GridType="Collection",
        CollectionType="Temporal",
    )
    return root, series


def write_xml(root: ET.Element, path: Path) -> None:
    """Write an XML tree atomically (a reader never sees half a file).

    The temporary file has a unique name beside ``path`` and is removed on any error.
    """
    ET.indent(root)
    fd, name = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    try:
        with os.fdopen(fd, "wb") as f:
            ET.ElementTree(root).write(f, xml_declaration=True, encoding="utf-8")
        os.chmod(name, 0o644)
        os.replace(name, path)
    except BaseException:
        Path(name).unlink(missing_ok=True)
        raise


def hdf_item(
    parent: ET.Element, dims: str, number_type: str, *, path: str, precision: int = 8
) -> None:
    """An HDF5 DataItem ``path`` (``file.h5:/dataset``) of shape ``dims``, ``precision`` bytes."""
    ET.SubElement(
        parent,
        "DataItem",
        Dimensions=dims,
        NumberType=number_type,
        Precision=str(precision),
        Format="HDF",
    ).text = path
