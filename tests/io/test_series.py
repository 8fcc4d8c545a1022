"""The XDMF series of the crack drivers: each time once, continuing after a resume."""

import xml.etree.ElementTree as ET

import h5py
import numpy as np
import pytest
import pyvista as pv

from geofrac.io import series as series_module
from geofrac.io.series import XdmfSeries

COORDS = np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [1.0, 1.0]])
CELLS = np.array([[0, 1, 2], [1, 3, 2]])


def times(path) -> list[float]:
    return [float(t.get("Value")) for t in ET.parse(path).getroot().iter("Time")]


def read(path, t: float) -> pv.UnstructuredGrid:
    """The step at time t as VTK's XDMF reader (ParaView's) gives it."""
    reader = pv.get_reader(str(path))
    assert isinstance(reader, pv.XdmfReader)
    reader.set_active_time_value(t)
    return reader.read()


def write_steps(path, ts) -> XdmfSeries:
    s = XdmfSeries(path, COORDS, CELLS)
    for t in ts:
        s.write(t, point_data={"u": np.full((4, 2), t)}, cell_data={"crack": [t, -t]})
    return s


def test_a_step_at_the_last_time_replaces_it(tmp_path):
    path = tmp_path / "a.xdmf"
    s = write_steps(path, [1.0, 2.0])
    s.write(2.0, point_data={"u": np.full((4, 2), 7.0)}, cell_data={"crack": [7.0, 7.0]})
    assert times(path) == [1.0, 2.0]
    reader = pv.get_reader(str(path))
    assert reader.time_values == [1.0, 2.0]
    mesh = read(path, 2.0)
    assert mesh.n_cells == 2 and list(mesh.cell_data["crack"]) == [7.0, 7.0]
    assert np.allclose(mesh.point_data["u"][:, :2], 7.0)


def test_continue_keeps_the_steps_up_to_a_time_and_appends(tmp_path):
    path = tmp_path / "a.xdmf"
    write_steps(path, [1.0, 3.0, 5.0, 7.0, 9.0])
    s = XdmfSeries(path, COORDS, CELLS, keep_until=5.0)
    assert s.note is None and times(path) == [1.0, 3.0, 5.0]
    with h5py.File(tmp_path / "a.h5") as f:
        assert sorted(k for k in f if k.startswith("step_")) == ["step_0", "step_1", "step_2"]
    s.write(6.0, point_data={"u": np.full((4, 2), 6.0)}, cell_data={"crack": [6.0, -6.0]})
    assert times(path) == [1.0, 3.0, 5.0, 6.0]
    assert list(read(path, 3.0).cell_data["crack"]) == [3.0, -3.0]
    assert list(read(path, 6.0).cell_data["crack"]) == [6.0, -6.0]


def test_continue_drops_a_step_written_in_part(tmp_path):
    """A step whose group lacks the attributes written last (a killed write) is dropped."""
    path = tmp_path / "a.xdmf"
    write_steps(path, [1.0, 2.0])
    with h5py.File(tmp_path / "a.h5", "a") as f:
        f["step_2/crack"] = np.zeros(2)  # no "t": the process died here
    s = XdmfSeries(path, COORDS, CELLS, keep_until=10.0)
    assert times(path) == [1.0, 2.0] and len(s.steps) == 2
    s.write(3.0, cell_data={"crack": [3.0, 3.0]})
    assert list(read(path, 3.0).cell_data["crack"]) == [3.0, 3.0]


def test_continue_another_mesh_or_a_broken_file_starts_anew(tmp_path):
    path = tmp_path / "a.xdmf"
    write_steps(path, [1.0, 2.0])
    s = XdmfSeries(path, COORDS + 1.0, CELLS, keep_until=2.0)
    assert s.note is not None and "another mesh" in s.note
    assert s.steps == [] and times(path) == []
    (tmp_path / "a.h5").write_bytes(b"not hdf5")
    s = XdmfSeries(path, COORDS, CELLS, keep_until=2.0)
    assert s.note is not None and s.steps == []
    s.write(3.0, cell_data={"crack": [1.0, 0.0]})
    assert times(path) == [3.0]


def test_xml_temporary_files_are_unique_and_removed_on_error(tmp_path, monkeypatch):
    path = tmp_path / "a.xdmf"
    write_steps(path, [1.0, 2.0])
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.h5", "a.xdmf"]
    assert (path.stat().st_mode & 0o777) == 0o644

    def fail(*args, **kw):
        raise OSError("disk full")

    monkeypatch.setattr(series_module.ET.ElementTree, "write", fail)
    with pytest.raises(OSError, match="disk full"):
        series_module.write_xml(ET.Element("Xdmf"), path)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.h5", "a.xdmf"]
    assert times(path) == [1.0, 2.0]  # the old file is intact


def test_series_data_are_gzip_compressed_and_read_back(tmp_path):
    """The steps are stored compressed (large crack series) and VTK still reads them."""
    write_steps(tmp_path / "s.xdmf", [1.0])
    with h5py.File(tmp_path / "s.h5") as f:
        assert f["step_0/u"].compression == "gzip" and f["mesh/topology"].compression == "gzip"
    grid = read(tmp_path / "s.xdmf", 1.0)
    np.testing.assert_array_equal(grid.point_data["u"][:, :2], np.full((4, 2), 1.0))
    np.testing.assert_array_equal(grid.cell_data["crack"], [1.0, -1.0])


def test_compression_survives_the_fem_stack_import_order():
    """h5py keeps its deflate filter in a process that imports as the CLI does.

    geofrac, then DOLFINx/PETSc, then the writers: imported after the PETSc wheel's
    HDF5, h5py had no deflate filter, and every crack run failed to write its series.
    """
    import subprocess
    import sys

    code = (
        "import geofrac\n"
        "from geofrac.pipeline import get\n"
        "get('fem')\n"
        "import h5py\n"
        "assert h5py.h5z.filter_avail(h5py.h5z.FILTER_DEFLATE)\n"
    )
    subprocess.run([sys.executable, "-c", code], check=True, timeout=120)
