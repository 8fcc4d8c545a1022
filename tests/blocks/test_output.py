"""Block set writers (geofrac.blocks.output): VTU/PVTU, block file, volume histogram."""

import numpy as np
import pytest

from geofrac.blocks import output as io
from geofrac.blocks import quality as q
from tests.blocks.conftest import median_dual_2d, median_dual_3d, pieces_as_blocks, take_blocks

pv = pytest.importorskip("pyvista")


@pytest.fixture(scope="module")
def dual3d():
    blocks = median_dual_3d(3)
    blocks.kind[:3] = 1  # some immobile-looking blocks, to see kind survive
    blocks.ids[:3] = -1
    return blocks


def surface_volumes(grid) -> np.ndarray:
    """Each polyhedral cell's volume from its closed face surface (vtkMassProperties)."""
    out = []
    for i in range(grid.n_cells):
        faces = [f.point_ids for f in grid.get_cell(i).faces]
        stream = np.concatenate([[len(f), *f] for f in faces])
        out.append(pv.PolyData(grid.points, faces=stream).volume)
    return np.array(out)


def test_vtu_header_is_raw_appended_uint64(tmp_path, dual3d):
    path = io.write_vtu(tmp_path / "b.vtu", dual3d)
    head = path.read_bytes()[:2000].split(b"<AppendedData")[0].decode()
    assert 'header_type="UInt64"' in head
    assert 'byte_order="LittleEndian"' in head
    assert 'Name="faces"' in head
    assert 'Name="faceoffsets"' in head
    assert 'format="appended"' in head
    assert b'<AppendedData encoding="raw">' in path.read_bytes()


def test_vtu_compressed_by_default_and_plain_on_request(tmp_path, dual3d):
    """Compressed by default (VTK reads it back: the next test); plain data is larger."""
    packed = io.write_vtu(tmp_path / "z.vtu", dual3d)
    plain = io.write_vtu(tmp_path / "p.vtu", dual3d, compress=False)
    assert b'compressor="vtkZLibDataCompressor"' in packed.read_bytes()[:400]
    assert b"compressor" not in plain.read_bytes()[:400]
    assert packed.stat().st_size < 0.7 * plain.stat().st_size
    a, b = pv.read(packed), pv.read(plain)
    np.testing.assert_array_equal(a.points, b.points)
    np.testing.assert_array_equal(a.cell_connectivity, b.cell_connectivity)
    np.testing.assert_array_equal(a.cell_data["id"], b.cell_data["id"])


@pytest.mark.parametrize("compress", [True, False, "small_blocks"], ids=["zlib", "plain", "z64"])
def test_vtu_polyhedra_read_back(tmp_path, dual3d, compress, monkeypatch):
    if compress == "small_blocks":  # many zlib blocks per array, a short last one
        monkeypatch.setattr(io, "ZLIB_BLOCK", 72)
    vol = q.block_volumes(dual3d)
    path = io.write_vtu(
        tmp_path / "b.vtu",
        dual3d,
        {"volume": vol, "big": vol > vol.mean()},
        compress=bool(compress),
    )
    grid = pv.read(path)
    assert grid.n_cells == dual3d.num_blocks
    assert set(np.unique(grid.celltypes)) == {pv.CellType.POLYHEDRON}
    np.testing.assert_array_equal(grid.cell_data["id"], dual3d.ids)
    np.testing.assert_array_equal(grid.cell_data["kind"], dual3d.kind)
    np.testing.assert_array_equal(grid.cell_data["volume"], vol)
    np.testing.assert_array_equal(grid.cell_data["big"], vol > vol.mean())
    # each polyhedron lists exactly its own points and its own faces
    offsets, _ = q.block_points(dual3d)
    np.testing.assert_array_equal(np.diff(grid.cell_offsets), np.diff(offsets))
    assert [grid.get_cell(i).n_faces for i in range(3)] == list(np.diff(dual3d.face_offsets)[:3])
    # blocks are not convex: VTK's cell size is the convex hull's, the surface is exact
    np.testing.assert_allclose(surface_volumes(grid), vol, rtol=0, atol=1e-14)


def test_vtu_convex_cells_match_vtk_cell_sizes(tmp_path, dual3d):
    hexes = pieces_as_blocks(dual3d)
    grid = pv.read(io.write_vtu(tmp_path / "h.vtu", hexes))
    sizes = grid.compute_cell_sizes(length=False, area=False)["Volume"]
    np.testing.assert_allclose(sizes, q.block_volumes(hexes), rtol=1e-12)


def test_vtu_polygons_read_back(tmp_path):
    blocks = median_dual_2d(4)
    grid = pv.read(io.write_vtu(tmp_path / "p.vtu", blocks))
    assert grid.n_cells == blocks.num_blocks
    assert set(np.unique(grid.celltypes)) == {pv.CellType.POLYGON}
    sizes = grid.compute_cell_sizes(length=False, volume=False)["Area"]
    np.testing.assert_allclose(sizes, q.block_volumes(blocks), rtol=1e-12)
    assert np.all(grid.points[:, 2] == 0)


def test_pvtu_of_two_pieces(tmp_path, dual3d):
    half = dual3d.num_blocks // 2
    parts = [take_blocks(dual3d, np.arange(half)), take_blocks(dual3d, np.arange(half, 64))]
    names = []
    for rank, part in enumerate(parts):
        names.append(f"blocks_{rank}.vtu")
        io.write_vtu(tmp_path / names[-1], part, {"volume": q.block_volumes(part)})
    pvtu = io.write_pvtu(tmp_path / "blocks.pvtu", names, {"volume": np.zeros(0)})
    grid = pv.read(pvtu)
    merged = grid if isinstance(grid, pv.UnstructuredGrid) else grid.combine()
    assert merged.n_cells == dual3d.num_blocks
    np.testing.assert_array_equal(np.sort(merged.cell_data["id"]), np.sort(dual3d.ids))
    assert merged.cell_data["volume"].sum() == pytest.approx(1.0, abs=1e-12)


@pytest.mark.parametrize("dim", [2, 3])
def test_block_file_round_trip(tmp_path, dim):
    blocks = median_dual_2d(3) if dim == 2 else median_dual_3d(2)
    blocks.kind[-1] = 1
    path = io.write_block_file(tmp_path / "blocks.txt", blocks)
    back = io.read_block_file(path)
    assert back.dim == dim
    assert back.num_blocks == blocks.num_blocks
    np.testing.assert_array_equal(back.ids, blocks.ids)
    np.testing.assert_array_equal(back.kind, blocks.kind)
    np.testing.assert_array_equal(back.seeds, blocks.seeds)
    np.testing.assert_array_equal(back.face_offsets, blocks.face_offsets)
    # coordinates are written exactly; faces and pieces keep their orientation
    np.testing.assert_array_equal(back.points[back.faces], blocks.points[blocks.faces])
    np.testing.assert_array_equal(back.points[back.pieces], blocks.points[blocks.pieces])
    np.testing.assert_array_equal(back.piece_block, blocks.piece_block)
    np.testing.assert_array_equal(q.block_volumes(back), q.block_volumes(blocks))
    assert q.check_closed(back).all()


def test_block_file_layout(tmp_path):
    """The first record follows the documented layout line by line."""
    blocks = median_dual_3d(1)  # 8 corner blocks of one cube
    lines = io.write_block_file(tmp_path / "b.txt", blocks).read_text().splitlines()
    assert lines[0] == "geofrac-blocks 1 3 8"
    head = lines[1].split()
    nv, nf, npc = (int(v) for v in head[2:5])
    assert head[:2] == ["0", "0"]
    assert float(head[5]) == pytest.approx(q.block_volumes(blocks)[0], rel=1e-15)
    assert len(head) == 9  # id kind nv nf np volume seed(3)
    verts = np.array([line.split() for line in lines[2 : 2 + nv]], float)
    faces = np.array([line.split() for line in lines[2 + nv : 2 + nv + nf]], int)
    pieces = np.array([line.split() for line in lines[2 + nv + nf : 2 + nv + nf + npc]], int)
    assert verts.shape == (nv, 3)
    assert (faces[:, 0] == 4).all() and faces[:, 1:].max() < nv
    assert (pieces[:, 0] == 8).all() and pieces[:, 1:].max() < nv
    first = blocks.faces[: blocks.face_offsets[1]]
    np.testing.assert_array_equal(verts[faces[:, 1:]], blocks.points[first])
    assert lines[2 + nv + nf + npc].split()[0] == "1"  # the next block's header


def test_histogram_png_and_csv(tmp_path, dual3d):
    vol = q.block_volumes(dual3d)
    counts, edges = io.write_histogram(tmp_path / "h.png", tmp_path / "h.csv", vol, bins=8)
    assert (tmp_path / "h.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    rows = (tmp_path / "h.csv").read_text().splitlines()
    assert rows[0] == "bin_lo,bin_hi,count"
    table = np.loadtxt(tmp_path / "h.csv", delimiter=",", skiprows=1)
    assert table.shape == (8, 3)
    assert table[:, 2].sum() == dual3d.num_blocks
    np.testing.assert_allclose(table[:, 0], edges[:-1], rtol=1e-9)
    np.testing.assert_array_equal(table[:, 2], counts)


def _labels(fig):
    ax, bar = fig.axes
    return ax.get_xlabel(), ax.get_ylabel(), ax.get_title(), bar.get_ylabel()


def test_section_of_3d_blocks_is_a_cut_in_the_scenes_units(dual3d):
    from geofrac.io.pictures import section_polygons
    from geofrac.model.scene import Units

    vol = q.block_volumes(dual3d)
    fig = io.section_figure(dual3d, vol, name="cube", units=Units(length="m"))
    x, y, title, bar = _labels(fig)
    assert (x, y, bar) == ("x (m)", "z (m)", "block volume (m³)")
    assert title.startswith("cube: section at y = ") and title.endswith(" m")
    x, y, title, bar = _labels(io.section_figure(dual3d, vol, name="cube", units=Units()))
    assert (x, y, bar) == ("x", "z", "block volume") and "(" not in title  # no [units]
    polygons, _ = section_polygons(dual3d.points, dual3d.pieces, axis=1, at=0.4)
    area = sum(
        0.5 * abs(np.dot(p[:, 0], np.roll(p[:, 1], -1)) - np.dot(p[:, 1], np.roll(p[:, 0], -1)))
        for p in polygons
    )
    assert area == pytest.approx(1.0)  # the pieces fill the unit cube: the cut is its square


def test_section_of_2d_blocks_colours_them_by_area():
    from geofrac.model.scene import Units

    blocks = median_dual_2d(4)
    fig = io.section_figure(blocks, q.block_volumes(blocks), name="square", units=Units("mm"))
    assert _labels(fig) == ("x (mm)", "y (mm)", "square: 25 blocks by area", "block area (mm²)")
