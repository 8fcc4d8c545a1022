"""A time series of fields on a fixed mesh, written by one process as XDMF + HDF5.

The crack driver keeps the whole crack state on every rank, so rank 0 writes the crack
picture itself: one HDF5 file with the mesh once and a dataset per field and step, and an
XDMF temporal collection that ParaView, pyvista and meshio read. The XML is rewritten
after every step, so an interrupted run leaves a readable series of the steps done.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from pathlib import Path

import h5py
import numpy as np

__all__ = ["XdmfSeries", "hdf_item", "temporal_collection", "write_xml"]

_TOPOLOGY = {2: "Polyline", 3: "Triangle"}


class XdmfSeries:
    """Fields over steps on one mesh of lines or triangles.

    Args:
        path: the ``.xdmf`` file; the data go to the sibling ``.h5``.
        coords: node coordinates, shape=(num_nodes, 2).
        cells: node ids per cell, shape=(num_cells, 2) (lines) or (num_cells, 3).
    """

    def __init__(self, path: Path, coords: np.ndarray, cells: np.ndarray) -> None:
        self.path = Path(path)
        self.h5 = self.path.with_suffix(".h5")
        self.num_nodes, self.num_cells = len(coords), len(cells)
        self.nv = cells.shape[1]
        xyz = np.zeros((len(coords), 3))
        xyz[:, : coords.shape[1]] = coords
        with h5py.File(self.h5, "w") as f:
            f["mesh/geometry"] = xyz
            f["mesh/topology"] = np.asarray(cells, dtype=np.int64)
        self.steps: list[tuple[float, list[tuple[str, str, int]]]] = []

    def write(
        self,
        t: float,
        point_data: dict[str, np.ndarray] | None = None,
        cell_data: dict[str, np.ndarray] | None = None,
    ) -> None:
        """Append a step at time ``t``.

        Args:
            t: the step's time value (the event number for the crack driver).
            point_data: name -> values, shape=(num_nodes,) or (num_nodes, k).
            cell_data: name -> values, shape=(num_cells,) or (num_cells, k).
        """
        i = len(self.steps)
        fields = []
        with h5py.File(self.h5, "a") as f:
            for centre, data in (("Node", point_data or {}), ("Cell", cell_data or {})):
                for name, given in data.items():
                    values = np.asarray(given, dtype=float)
                    if values.ndim == 2 and values.shape[1] == 2:  # ParaView wants 3D vectors
                        values = np.column_stack([values, np.zeros(len(values))])
                    f[f"step_{i}/{name}"] = values
                    fields.append((name, centre, values.shape[1] if values.ndim == 2 else 1))
        self.steps.append((float(t), fields))
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
            hdf_item(top, f"{self.num_cells} {self.nv}", "Int", f"{h5}:/mesh/topology")
            geo = ET.SubElement(grid, "Geometry", GeometryType="XYZ")
            hdf_item(geo, f"{self.num_nodes} 3", "Float", f"{h5}:/mesh/geometry")
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
                hdf_item(attr, dims, "Float", f"{h5}:/step_{i}/{name}")
        write_xml(root, self.path)


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
    """Write an XML tree atomically (a reader never sees half a file)."""
    ET.indent(root)
    tmp = path.with_suffix(path.suffix + ".tmp")
    ET.ElementTree(root).write(tmp, xml_declaration=True, encoding="utf-8")
    tmp.replace(path)


def hdf_item(
    parent: ET.Element, dims: str, number_type: str, path: str, precision: int = 8
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
