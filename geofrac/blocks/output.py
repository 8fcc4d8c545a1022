"""Block sets on disk: VTU for ParaView, a text block file for DEM/DDA codes, a histogram.

Pure numpy; matplotlib only for the histogram and section PNGs.

VTU (``write_vtu``, ``write_pvtu``)
    XML ``UnstructuredGrid``, version 1.0, raw binary appended data, ``header_type="UInt64"``,
    little-endian, zlib-compressed by default (``compressor="vtkZLibDataCompressor"``: each
    array is a header ``[num_blocks, block_size, last_block_size, compressed sizes...]``
    followed by the compressed blocks of :data:`ZLIB_BLOCK` bytes; ``compress=False``
    writes each array as its byte count and the plain bytes). Point ids and offsets are
    ``Int32`` when they fit, ``Int64`` otherwise. 3D blocks are ``VTK_POLYHEDRON`` cells
    (type 42) in the legacy face layout: the ``<Cells>`` section holds ``connectivity``
    (each block's own distinct points), ``offsets``, ``types``, ``faces`` (per block:
    number of faces, then per face its number of points and point ids) and
    ``faceoffsets`` (end of each block's entry in ``faces``). ParaView 5.11-5.13 (VTK
    9.2-9.3) read only this layout; VTK >= 9.4 (and ParaView 6) still read it and write
    the newer ``face_connectivity`` / ``face_offsets`` / ``polyhedron_to_faces`` /
    ``polyhedron_offsets`` arrays with version 2.3, which older readers reject. 2D
    blocks are ``VTK_POLYGON`` cells (type 7), points padded with z = 0. Cell data:
    ``id`` and ``kind`` of every block, plus the caller's arrays. Only the points the
    blocks' faces use are written.

Block file (``write_block_file``, ``read_block_file``)
    ASCII, whitespace-separated, one record per line, indices 0-based::

        geofrac-blocks 1 <dim> <num_blocks>
        then for every block:
        <id> <kind> <nv> <nf> <np> <volume> <seed_1> .. <seed_dim>
        nv lines   <x_1> .. <x_dim>                 the block's vertices
        nf lines   <k> <i_1> .. <i_k>               a face: k local vertex indices
        np lines   <k> <i_1> .. <i_k>               a convex piece: k local vertex indices

    ``id`` is the global block id (-1: immobile block), ``kind`` 0 for a block of the
    moving layer, 1 for an immobile block, ``volume`` the block's volume (area in 2D),
    ``seed`` the point the block surrounds. Vertex indices refer to the block's own
    vertex list (0 .. nv - 1); blocks share no vertices in the file. Faces: 3D, k = 4, a
    planar quadrilateral counter-clockwise seen from outside the block; 2D, k = 2, an
    edge of the boundary, the edges in counter-clockwise order around the block. Convex
    pieces: 3D, k = 8, a hexahedron in VTK order (bottom quadrilateral counter-clockwise
    seen from the top, then the top quadrilateral above it point by point); 2D, k = 4, a
    counter-clockwise quadrilateral. Coordinates and volumes are written with 17
    significant digits (exact round trip).

Histogram (``write_histogram``)
    PNG of frequency against block volume (as in Edo (2016), Fig. 5.25) and CSV
    ``bin_lo,bin_hi,count``.

Section (``section_figure``)
    The blocks coloured by volume: 2D, all of them; 3D, their cut by a vertical plane.
"""

from __future__ import annotations

import dataclasses
import os
import xml.etree.ElementTree as ET
import zlib
from collections.abc import Mapping, Sequence
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from geofrac.blocks.model import Blocks
from geofrac.blocks.quality import block_points, block_volumes
from geofrac.model.scene import Units

if TYPE_CHECKING:
    from matplotlib.figure import Figure

__all__ = [
    "read_block_file",
    "section_figure",
    "write_block_file",
    "write_histogram",
    "write_pvtu",
    "write_vtu",
]

VTK_POLYGON = 7
VTK_POLYHEDRON = 42
#: Uncompressed bytes per zlib block of a compressed VTU array.
ZLIB_BLOCK = 1 << 20
#: zlib level: 1 keeps the writer near disk speed; higher levels gain a few per cent.
ZLIB_LEVEL = 1
_MAGIC = "geofrac-blocks"
_VTK_TYPES = {
    "int8": "Int8",
    "uint8": "UInt8",
    "int16": "Int16",
    "uint16": "UInt16",
    "int32": "Int32",
    "uint32": "UInt32",
    "int64": "Int64",
    "uint64": "UInt64",
    "float32": "Float32",
    "float64": "Float64",
    "bool": "UInt8",
}


def _vtk_type(values: np.ndarray) -> str:
    name = np.asarray(values).dtype.name
    if name not in _VTK_TYPES:
        raise ValueError(f"no VTK type for dtype {name}")
    return _VTK_TYPES[name]


def _cell_arrays(
    ids: np.ndarray, kind: np.ndarray, cell_data: Mapping[str, np.ndarray] | None
) -> list[tuple[str, np.ndarray]]:
    """``id``, ``kind`` and the caller's cell arrays, each shape=(num_blocks,) or (n, k)."""
    arrays = {"id": np.asarray(ids, dtype=np.int64), "kind": np.asarray(kind, dtype=np.int8)}
    for name, values in (cell_data or {}).items():
        v = np.asarray(values)
        arrays[name] = v.astype(np.uint8) if v.dtype == bool else v
    return list(arrays.items())


class _Appended:
    """Collects appended arrays: UInt64 byte count + little-endian data, or zlib blocks."""

    def __init__(self, *, compress: bool) -> None:
        self.compress = compress
        self.chunks: list[bytes | np.ndarray] = []
        self.offset = 0

    def add(self, parent: ET.Element, values: np.ndarray, **attrs: str) -> None:
        data = np.ascontiguousarray(values)
        data = data.astype(data.dtype.newbyteorder("<"), copy=False)
        ET.SubElement(
            parent,
            "DataArray",
            type=_vtk_type(data),
            format="appended",
            offset=str(self.offset),
            **attrs,  # type: ignore[arg-type]  # the stub fears a key named attrib; none is
        )
        raw = data.reshape(-1).view(np.uint8)
        if not self.compress:
            chunks: list[bytes | np.ndarray] = [np.array([raw.nbytes], dtype="<u8").tobytes(), raw]
        else:
            blocks = _compress_blocks(raw)
            last = raw.nbytes - (len(blocks) - 1) * ZLIB_BLOCK if blocks else 0
            sizes = [len(blocks), ZLIB_BLOCK, last] + [len(b) for b in blocks]
            chunks = [np.array(sizes, dtype="<u8").tobytes(), *blocks]
        self.chunks += chunks
        self.offset += sum(len(c) if isinstance(c, bytes) else c.nbytes for c in chunks)


def _compress_blocks(raw: np.ndarray) -> list[bytes]:
    """The zlib blocks of :data:`ZLIB_BLOCK` bytes of ``raw`` shape=(nbytes,) uint8.

    Compressed on as many threads as the process may use (zlib releases the GIL).
    """
    starts = range(0, raw.nbytes, ZLIB_BLOCK)
    if len(starts) < 2:
        return [zlib.compress(raw[i : i + ZLIB_BLOCK].data, ZLIB_LEVEL) for i in starts]
    workers = min(len(starts), len(os.sched_getaffinity(0)))
    with ThreadPoolExecutor(max_workers=workers) as pool:
        return list(
            pool.map(lambda i: zlib.compress(raw[i : i + ZLIB_BLOCK].data, ZLIB_LEVEL), starts)
        )


def _index_type(values: np.ndarray) -> np.ndarray:
    """Point ids, counts or offsets as int32 when they fit (half the bytes), else int64."""
    v = np.asarray(values)
    if v.dtype == np.int32:
        return v
    if not len(v) or (v.min() >= 0 and v.max() <= np.iinfo(np.int32).max):
        return v.astype(np.int32)
    return v


def _cell_streams(blocks: Blocks) -> dict[str, np.ndarray]:
    """Points used by the faces (padded to 3D) and the VTK cell arrays, renumbered."""
    faces = np.asarray(blocks.faces)
    # the points the faces use, renumbered in increasing order (as np.unique, without a sort)
    used = np.flatnonzero(np.bincount(faces.ravel(), minlength=len(blocks.points)))
    renumber = np.zeros(len(blocks.points), dtype=faces.dtype)
    renumber[used] = np.arange(len(used), dtype=faces.dtype)
    local = renumber[faces]
    x = np.zeros((len(used), 3))
    x[:, : blocks.dim] = np.asarray(blocks.points, dtype=float)[used]
    off = np.asarray(blocks.face_offsets, dtype=np.int64)
    n = blocks.num_blocks
    if blocks.dim == 2:
        return {
            "points": x,
            "connectivity": local[:, 0],
            "offsets": off[1:],
            "types": np.full(n, VTK_POLYGON, dtype=np.uint8),
        }
    pt_off, pt_ids = block_points(dataclasses.replace(blocks, points=x, faces=local))
    from geofrac.blocks.kernels import face_stream

    stream, ends = face_stream(local, off)
    return {
        "points": x,
        "connectivity": pt_ids,
        "offsets": pt_off[1:],
        "types": np.full(n, VTK_POLYHEDRON, dtype=np.uint8),
        "faces": stream,
        "faceoffsets": ends,
    }


def _write_xml(path: Path, root: ET.Element, appended: _Appended) -> None:
    ET.SubElement(root, "AppendedData", encoding="raw").text = "\n_"
    text = ET.tostring(root, encoding="unicode")
    head, tail = text.split("\n_", 1)
    with open(path, "wb") as f:
        f.write(b'<?xml version="1.0"?>\n')
        f.write(head.encode() + b"\n_")
        for chunk in appended.chunks:
            f.write(chunk if isinstance(chunk, bytes) else chunk.data)
        f.write(b"\n" + tail.encode() + b"\n")


def _root(kind: str) -> ET.Element:
    return ET.Element(
        "VTKFile",
        type=kind,
        version="1.0",
        byte_order="LittleEndian",
        header_type="UInt64",
    )


def write_vtu(
    path: str | os.PathLike,
    blocks: Blocks,
    cell_data: Mapping[str, np.ndarray] | None = None,
    *,
    compress: bool = True,
) -> Path:
    """Write the blocks as one VTU piece (format in the module docstring).

    Args:
        path: the ``.vtu`` file.
        blocks: the block set (may be empty).
        cell_data: name -> values per block, shape=(num_blocks,) or (num_blocks, k);
            ``id`` and ``kind`` are always written.
        compress: zlib-compress the arrays (ParaView and VTK read both).

    Returns:
        The path.
    """
    path = Path(path)
    streams = _cell_streams(blocks)
    arrays = _cell_arrays(blocks.ids, blocks.kind, cell_data)
    for name, values in arrays:
        if len(values) != blocks.num_blocks:
            raise ValueError(
                f"cell array {name!r}: {len(values)} values, {blocks.num_blocks} blocks"
            )
    root = _root("UnstructuredGrid")
    if compress:
        root.set("compressor", "vtkZLibDataCompressor")
    piece = ET.SubElement(
        ET.SubElement(root, "UnstructuredGrid"),
        "Piece",
        NumberOfPoints=str(len(streams["points"])),
        NumberOfCells=str(blocks.num_blocks),
    )
    app = _Appended(compress=compress)
    ET.SubElement(piece, "PointData")
    cells_data = ET.SubElement(piece, "CellData")
    for name, values in arrays:
        app.add(cells_data, values, Name=name, NumberOfComponents=str(_components(values)))
    app.add(ET.SubElement(piece, "Points"), streams["points"], NumberOfComponents="3")
    cells = ET.SubElement(piece, "Cells")
    for name in ("connectivity", "offsets", "types", "faces", "faceoffsets"):
        if name in streams:
            values = streams[name] if name == "types" else _index_type(streams[name])
            app.add(cells, values, Name=name)
    _write_xml(path, root, app)
    return path


def _components(values: np.ndarray) -> int:
    v = np.asarray(values)
    return 1 if v.ndim == 1 else int(np.prod(v.shape[1:]))


def write_pvtu(
    path: str | os.PathLike,
    pieces: Sequence[str | os.PathLike],
    cell_data: Mapping[str, np.ndarray] | None = None,
) -> Path:
    """Write the ``.pvtu`` index of VTU pieces written by ``write_vtu`` (one per rank).

    Each rank writes its own piece; rank 0 calls this once all pieces are written.

    Args:
        path: the ``.pvtu`` file.
        pieces: the piece files; paths relative to the ``.pvtu`` folder are stored as
            given, absolute ones made relative to it.
        cell_data: the same names -> arrays as given to ``write_vtu`` (only their dtype
            and number of components are used; any rank's arrays, even empty ones).

    Returns:
        The path.
    """
    path = Path(path)
    root = _root("PUnstructuredGrid")
    grid = ET.SubElement(root, "PUnstructuredGrid", GhostLevel="0")
    cells_data = ET.SubElement(grid, "PCellData")
    empty = np.zeros(0, dtype=np.int64)
    for name, values in _cell_arrays(empty, empty, cell_data):
        ET.SubElement(
            cells_data,
            "PDataArray",
            type=_vtk_type(values),
            Name=name,
            NumberOfComponents=str(_components(values)),
        )
    ET.SubElement(
        ET.SubElement(grid, "PPoints"), "PDataArray", type="Float64", NumberOfComponents="3"
    )
    for piece in pieces:
        p = Path(piece)
        source = os.path.relpath(p, path.parent) if p.is_absolute() else str(p)
        ET.SubElement(grid, "Piece", Source=source)
    ET.indent(root)
    path.write_text('<?xml version="1.0"?>\n' + ET.tostring(root, encoding="unicode") + "\n")
    return path


_BLOCK_CHUNK = 4096  # blocks formatted per pass: bounds the per-line strings in memory


def _lines(fmt: str, values: np.ndarray) -> list[str]:
    """One formatted line per row of ``values`` shape=(n, m), via one C-level % call."""
    if not len(values):
        return []
    return ((fmt + "\n") * len(values) % tuple(values.ravel().tolist())).splitlines()


def write_block_file(path: str | os.PathLike, blocks: Blocks) -> Path:
    """Write the blocks in the plain text block file format (module docstring).

    Numbers are formatted a chunk of blocks at a time with one C-level ``%`` call per
    record type; no Python loop over blocks, faces or vertices.

    Returns:
        The path.
    """
    path = Path(path)
    dim = blocks.dim
    x = np.asarray(blocks.points, dtype=float)
    faces = np.asarray(blocks.faces, dtype=np.int64)
    pieces = np.asarray(blocks.pieces, dtype=np.int64)
    piece_block = np.asarray(blocks.piece_block, dtype=np.int64)
    if np.any(np.diff(piece_block) < 0):  # the builders leave pieces in cell order
        order = np.argsort(piece_block, kind="stable")
        pieces, piece_block = pieces[order], piece_block[order]
        blocks = dataclasses.replace(blocks, pieces=pieces, piece_block=piece_block)
    f_off = np.asarray(blocks.face_offsets, dtype=np.int64)
    p_off = np.searchsorted(piece_block, np.arange(blocks.num_blocks + 1))
    v_off, v_ids = block_points(blocks, with_pieces=True)
    volumes = block_volumes(blocks)
    num_points = len(x)
    if dim == 2:
        ring = faces[:, 0]
        nxt = np.arange(1, len(ring) + 1)
        full = f_off[1:] > f_off[:-1]
        nxt[f_off[1:][full] - 1] = f_off[:-1][full]
        face_rows = np.column_stack([ring, ring[nxt]])
    else:
        face_rows = faces
    kf, kp = face_rows.shape[1], pieces.shape[1]
    head_fmt = "%d %d %d %d %d %.17g" + " %.17g" * dim
    vert_fmt = " ".join(["%.17g"] * dim)
    face_fmt = f"{kf} " + " ".join(["%d"] * kf)
    piece_fmt = f"{kp} " + " ".join(["%d"] * kp)
    with open(path, "w") as out:
        out.write(f"{_MAGIC} 1 {dim} {blocks.num_blocks}\n")
        for b0 in range(0, blocks.num_blocks, _BLOCK_CHUNK):
            b1 = min(b0 + _BLOCK_CHUNK, blocks.num_blocks)
            blk = np.arange(b0, b1)
            nv, nf, npc = np.diff(v_off)[blk], np.diff(f_off)[blk], np.diff(p_off)[blk]
            vs, fs = slice(v_off[b0], v_off[b1]), slice(f_off[b0], f_off[b1])
            ps = slice(p_off[b0], p_off[b1])
            v_owner = np.repeat(blk, nv)
            key = v_owner * num_points + v_ids[vs]  # sorted: block, then point
            f_owner, p_owner = np.repeat(blk, nf), np.repeat(blk, npc)
            first = v_off[blk] - v_off[b0]
            f_local = np.searchsorted(key, f_owner[:, None] * num_points + face_rows[fs])
            f_local -= first[f_owner - b0][:, None]
            p_local = np.searchsorted(key, p_owner[:, None] * num_points + pieces[ps])
            p_local -= first[p_owner - b0][:, None]
            head = np.column_stack(
                [blocks.ids[blk], blocks.kind[blk], nv, nf, npc, volumes[blk], blocks.seeds[blk]]
            ).astype(float)
            size = 1 + nv + nf + npc
            start = np.cumsum(size) - size
            lines = np.empty(int(size.sum()), dtype=object)
            lines[start] = _lines(head_fmt, head)
            lines[_positions(start + 1, nv)] = _lines(vert_fmt, x[v_ids[vs]])
            lines[_positions(start + 1 + nv, nf)] = _lines(face_fmt, f_local)
            lines[_positions(start + 1 + nv + nf, npc)] = _lines(piece_fmt, p_local)
            out.write("\n".join(lines.tolist()))
            out.write("\n")
    return path


def _positions(start: np.ndarray, count: np.ndarray) -> np.ndarray:
    """start[i] + 0 .. count[i] - 1 for every i, concatenated."""
    total = int(count.sum())
    return np.repeat(start - (np.cumsum(count) - count), count) + np.arange(total)


def read_block_file(path: str | os.PathLike) -> Blocks:
    """Read a block file (module docstring) back into a ``Blocks``.

    Blocks share no points in the file, so each block gets its own copies of its vertices
    (``points`` has shape=(sum of nv, dim)). The walk over block headers is a scalar loop
    (each header gives the next one's position); all data is gathered with numpy.
    """
    text = Path(path).read_text()
    first, _, rest = text.partition("\n")
    magic, version, dim_s, count_s = first.split()
    if magic != _MAGIC or version != "1":
        raise ValueError(f"{path}: not a {_MAGIC} version 1 file")
    dim, num_blocks = int(dim_s), int(count_s)
    t = np.fromstring(rest, sep=" ") if rest.strip() else np.zeros(0)
    kf, kp = (4, 8) if dim == 3 else (2, 4)
    head_len = 6 + dim
    heads = np.empty(num_blocks, dtype=np.int64)
    pos = 0
    for b in range(num_blocks):
        heads[b] = pos
        n_v, n_f, n_p = int(t[pos + 2]), int(t[pos + 3]), int(t[pos + 4])
        pos += head_len + n_v * dim + n_f * (kf + 1) + n_p * (kp + 1)
    if pos != len(t):
        raise ValueError(f"{path}: {len(t) - pos} numbers left over")
    h = t[heads[:, None] + np.arange(head_len)] if num_blocks else np.zeros((0, head_len))
    nv, nf, npc = (h[:, c].astype(np.int64) for c in (2, 3, 4))
    v_start = heads + head_len
    f_start = v_start + nv * dim
    p_start = f_start + nf * (kf + 1)
    points = t[_positions(v_start, nv * dim)].reshape(-1, dim)
    v_first = np.cumsum(nv) - nv
    f_rows = t[_positions(f_start, nf * (kf + 1))].reshape(-1, kf + 1).astype(np.int64)
    p_rows = t[_positions(p_start, npc * (kp + 1))].reshape(-1, kp + 1).astype(np.int64)
    if np.any(f_rows[:, 0] != kf) or np.any(p_rows[:, 0] != kp):
        raise ValueError(f"{path}: faces must have {kf} and pieces {kp} points")
    f_owner, p_owner = np.repeat(np.arange(num_blocks), nf), np.repeat(np.arange(num_blocks), npc)
    f_glob = f_rows[:, 1:] + v_first[f_owner][:, None]
    pieces = p_rows[:, 1:] + v_first[p_owner][:, None]
    faces = f_glob if dim == 3 else f_glob[:, :1]
    return Blocks(
        dim=dim,
        points=points,
        faces=faces,
        face_offsets=np.concatenate([[0], np.cumsum(nf)]).astype(np.int64),
        pieces=pieces,
        piece_block=p_owner,
        ids=h[:, 0].astype(np.int64),
        seeds=h[:, 6 : 6 + dim].copy(),
        kind=h[:, 1].astype(np.int8),
    )


def section_figure(blocks: Blocks, volumes: np.ndarray, *, name: str, units: Units) -> Figure:
    """``section.png``: the blocks coloured by volume; in 3D their cut by a vertical plane.

    2D: every block's polygon, coloured by its area. 3D: the convex pieces cut by the
    plane y = the median y of the moving blocks' seeds, seen from -y (x right, z up),
    each cut coloured by its block's volume, the blocks' faces cut into their outlines.
    Immobile blocks are grey (in 3D their cut outline), the picture framed on the moving
    blocks.

    Args:
        blocks: the whole set (rank 0).
        volumes: each block's volume (area in 2D), shape=(num_blocks,).
        name: the scene's name, for the title.
        units: the scene's units.
    """
    from geofrac.io import pictures

    moving = blocks.kind == 0
    if blocks.dim == 2:
        rings = np.split(blocks.points[blocks.faces[:, 0]], blocks.face_offsets[1:-1])
        polygons = [r for r, m in zip(rings, moving, strict=True) if m]
        background = [r for r, m in zip(rings, moving, strict=True) if not m]
        return pictures.section_figure(
            polygons=polygons,
            values=volumes[moving],
            background=background,
            axes_names=("x", "y"),
            quantity="area",
            title=f"{name}: {int(moving.sum())} blocks by area",
            units=units,
        )
    seeds = blocks.seeds[moving] if moving.any() else blocks.seeds
    at = float(np.median(seeds[:, 1]))
    if abs(at) < 1e-9 * float(np.ptp(blocks.points[:, 1])):
        at = 0.0  # the median of a symmetric set: round-off of 0
    cuts, which = pictures.section_polygons(blocks.points, blocks.pieces, axis=1, at=at)
    owner = blocks.piece_block[which]
    mine = moving[owner]
    face_moving = np.repeat(moving, np.diff(blocks.face_offsets))
    faces = blocks.faces
    return pictures.section_figure(
        polygons=[c for c, m in zip(cuts, mine, strict=True) if m],
        values=volumes[owner[mine]],
        background_lines=pictures.section_segments(
            blocks.points, faces[~face_moving], axis=1, at=at
        ),
        outlines=pictures.section_segments(blocks.points, faces[face_moving], axis=1, at=at),
        axes_names=("x", "z"),
        quantity="volume",
        title=f"{name}: section at y = {at:.4g} {units.length}".rstrip(),
        units=units,
    )


def write_histogram(
    path_png: str | os.PathLike,
    path_csv: str | os.PathLike,
    volumes: np.ndarray,
    *,
    bins: int | Sequence[float] | str = 30,
    unit: str = "",
    name: str = "",
) -> tuple[np.ndarray, np.ndarray]:
    """The block volume histogram as a PNG (frequency against volume) and a CSV.

    Args:
        path_png: the figure.
        path_csv: the table, columns ``bin_lo,bin_hi,count``.
        volumes: block volumes (areas in 2D), shape=(num_blocks,).
        bins: as ``numpy.histogram``.
        unit: volume unit for the axis label (empty: none declared, no unit shown).
        name: the scene's name, for the title.

    Returns:
        ``(counts, edges)``: shape=(num_bins,) and shape=(num_bins + 1,).
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    volumes = np.asarray(volumes, dtype=float)
    counts, edges = np.histogram(volumes, bins=bins)
    table = np.column_stack([edges[:-1], edges[1:], counts])
    np.savetxt(
        path_csv,
        table,
        fmt=["%.10g", "%.10g", "%d"],
        delimiter=",",
        header="bin_lo,bin_hi,count",
        comments="",
    )
    fig, ax = plt.subplots(figsize=(6, 4), constrained_layout=True)
    ax.stairs(counts, edges, fill=True, alpha=0.8, edgecolor="k", linewidth=0.5)
    ax.set_xlabel(f"block volume ({unit})" if unit else "block volume")
    ax.set_ylabel("frequency")
    head = f"{name}: " if name else ""
    ax.set_title(
        f"{head}{len(volumes)} blocks, mean volume {volumes.mean():.3g} {unit}".rstrip()
        if len(volumes)
        else f"{head}no blocks"
    )
    ax.grid(True, alpha=0.3)
    fig.savefig(path_png, dpi=120)
    plt.close(fig)
    return counts, edges
