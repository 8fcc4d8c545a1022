"""A time series of particles (points that move) as XDMF + HDF5, written by one process.

Each frame stores the particle positions and fields; the topology (one vertex per
particle, ``Polyvertex``) is stored once, as the particle count never changes (a
particle leaving the grid stops the run). ParaView opens ``particles.xdmf`` as a
temporal point cloud (use the "Point Gaussian" representation); meshio and pyvista
read it too. The XML is rewritten after every frame, so an interrupted run leaves a
readable series of the frames done.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from pathlib import Path

import h5py
import numpy as np

from geofrac.io.series import hdf_item, hdf_put, kept_steps, temporal_collection, write_xml

__all__ = ["PointSeries", "last_frame"]

_KIND = {1: "Scalar", 3: "Vector", 9: "Tensor"}


class PointSeries:
    """Particle frames in ``path`` (``.xdmf``) and its sibling ``.h5``.

    Args:
        path: the ``.xdmf`` file.
        count: number of particles.
    """

    def __init__(self, path: Path, count: int) -> None:
        self.path = Path(path)
        self.h5 = self.path.with_suffix(".h5")
        self.count = int(count)
        with h5py.File(self.h5, "w") as f:
            hdf_put(f, "topology", np.arange(self.count, dtype=np.int64))
        self.frames: list[tuple[float, list[tuple[str, int]]]] = []

    def write(self, t: float, x: np.ndarray, fields: dict[str, np.ndarray]) -> None:
        """Append a frame.

        Args:
            t: time.
            x: positions, shape=(count, dim).
            fields: name -> values, shape=(count,) (scalar), (count, dim) (vector; padded
                to 3 components) or (count, 3, 3) (tensor).
        """
        i = len(self.frames)
        kinds = []
        with h5py.File(self.h5, "a") as f:
            xyz = np.zeros((self.count, 3))
            xyz[:, : x.shape[1]] = x
            hdf_put(f, f"frame_{i}/geometry", xyz)
            for name, given in fields.items():
                values = np.asarray(given, dtype=float).reshape(self.count, -1)
                if values.shape[1] in (1, 2):
                    values = values if given.ndim == 1 else _pad(values)
                if values.shape[1] not in _KIND:
                    raise ValueError(f"field {name!r}: {values.shape[1]} components")
                hdf_put(f, f"frame_{i}/{name}", values if values.shape[1] > 1 else values[:, 0])
                kinds.append((name, values.shape[1]))
            # the time last: a frame with a time is complete (reopen drops any other)
            f[f"frame_{i}"].attrs["fields"] = ",".join(name for name, _ in kinds)
            f[f"frame_{i}"].attrs["t"] = float(t)
        self.frames.append((float(t), kinds))
        self._write_xml()

    @classmethod
    def reopen(cls, path: Path, count: int, t_max: float) -> PointSeries:
        """The series in ``path`` with its frames of time <= ``t_max`` (later ones dropped).

        A resumed run continues the series of the interrupted one; frames that run wrote
        after its checkpoint are removed, so each time appears once.

        Raises:
            ValueError: the file holds another number of particles.
        """
        self = cls.__new__(cls)
        self.path, self.h5, self.count = Path(path), Path(path).with_suffix(".h5"), int(count)
        self.frames = []
        if not self.h5.exists():
            return cls(path, count)
        with h5py.File(self.h5, "a") as f:
            if len(f["topology"]) != self.count:
                raise ValueError(f"{self.h5.name}: {len(f['topology'])} particles, not {count}")
            for t, group in kept_steps(f, "frame_", t_max * (1 + 1e-12)):
                names = str(group.attrs.get("fields", "")).split(",")
                kinds = [(n, group[n].shape[1] if group[n].ndim > 1 else 1) for n in names if n]
                self.frames.append((t, kinds))
        self._write_xml()
        return self

    def _write_xml(self) -> None:
        h5, n = self.h5.name, self.count
        root, series = temporal_collection(self.path.stem)
        for i, (t, kinds) in enumerate(self.frames):
            grid = ET.SubElement(series, "Grid", Name=f"frame_{i}", GridType="Uniform")
            top = ET.SubElement(
                grid,
                "Topology",
                TopologyType="Polyvertex",
                NumberOfElements=str(n),
                NodesPerElement="1",
            )
            hdf_item(top, f"{n} 1", "Int", path=f"{h5}:/topology")
            geo = ET.SubElement(grid, "Geometry", GeometryType="XYZ")
            hdf_item(geo, f"{n} 3", "Float", path=f"{h5}:/frame_{i}/geometry")
            ET.SubElement(grid, "Time", Value=repr(t))
            for name, k in kinds:
                attr = ET.SubElement(
                    grid, "Attribute", Name=name, AttributeType=_KIND[k], Center="Node"
                )
                hdf_item(
                    attr, f"{n} {k}" if k > 1 else f"{n}", "Float", path=f"{h5}:/frame_{i}/{name}"
                )
        write_xml(root, self.path)


def _pad(values: np.ndarray) -> np.ndarray:
    """Vectors with fewer than 3 components, zero-padded to 3 (ParaView wants 3D vectors)."""
    out = np.zeros((len(values), 3))
    out[:, : values.shape[1]] = values
    return out


def last_frame(h5: Path) -> dict[str, np.ndarray]:
    """The datasets of the last frame of a series' ``.h5`` (``geometry`` and the fields).

    Raises:
        ValueError: the file holds no frame.
    """
    with h5py.File(h5) as f:
        frames = [int(k.split("_")[1]) for k in f if k.startswith("frame_")]
        if not frames:
            raise ValueError(f"{Path(h5).name}: no frame")
        group = f[f"frame_{max(frames)}"]
        return {k: group[k][()] for k in group}
