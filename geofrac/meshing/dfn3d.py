"""Conforming tetrahedral mesh of a box cut by disc fractures (gmsh, OpenCASCADE kernel).

One process, no MPI, no DOLFINx: :func:`mesh_discs` builds the model in the current gmsh
session and meshes it; :mod:`geofrac.meshing.distribute` can then hand it to DOLFINx.

Steps (each timed in the report):

1. ``clean``: :func:`geofrac.dfn3d.clean.clean_discs` with the tolerance (default a
   quarter of the fracture element size), so that no gap, sliver or intersection is
   smaller than the tolerance.
2. ``build``: an OCC box and one OCC disk per fracture (``occ.addDisk`` with the disc's
   normal as its z axis). Disks are much cheaper than polygons: for the 1,000 discs of
   the bench, build and fragment took 0.09 s and 0.9 s with disks, 0.9 s and 22 s with
   16-gons, 1.7 s and 85 s with 32-gons (every polygon side is an edge to intersect). A
   disk's edge is a circle with one vertex, its seam, which stays a vertex after the
   fragment: it is put in the middle of the widest gap between the points where other
   discs and the box faces cross the edge
   (:func:`~geofrac.dfn3d.clean.seam_directions`), so that it never leaves a curve a
   hair long (and flat tetrahedra) next to a junction.
3. ``fragment``: ``occ.fragment`` of the box with all disks: the disks cut each other
   along their intersection lines and the box along their chords; every piece of a disk
   is mapped back to its fracture through the fragment's output map. Pieces outside the
   box are removed. A fracture cutting the box in two splits the rock into volumes that
   share that piece; all other pieces are embedded in the rock (gmsh does that itself:
   the fragment leaves them inside the volume), so the tetrahedra have faces on them.
4. ``mesh``: curves and surfaces (``generate(2)``) at ``fracture_mesh_size`` on every
   fracture piece (a mesh size on their points, extended over the surfaces) and graded
   to ``mesh_size`` on the box faces; then the volume (``generate(3)``) under a
   Distance/Threshold field: ``fracture_mesh_size`` within that distance of a fracture,
   growing linearly to ``mesh_size`` over ``transition``. The Distance field samples each
   piece on a grid of spacing <= ``fracture_mesh_size`` (pieces binned by size, one
   Distance field per bin, their minimum taken; at most 512 points a side). The field is
   set only for the volume: integrating it along thousands of curves made the 1D mesh
   60 to 200 times slower (6-18 s instead of 0.1 s for 1,000 discs). Delaunay or HXT
   only: Frontal ignores embedded surfaces. The report checks that every fracture
   triangle is a face of exactly two tetrahedra.

Physical groups: ``rock`` (3D, all volumes), ``xmin``, ``xmax``, ``ymin``, ``ymax``,
``zmin``, ``zmax`` (2D, the pieces of each box face), ``fractures`` (2D, every fracture
piece inside the box) and one 2D group per fracture set, named by the set, holding that
set's pieces (the set groups partition ``fractures``, so each fracture triangle is in
two 2D groups; :func:`~geofrac.meshing.distribute.build_mesh` keeps both). Sets with no
piece inside the box get no group.

Cost and failure: gmsh calls cannot be interrupted from Python; what bounds them is the
model size. Measured on one core (``geofrac bench dfn3d``, 1,000 discs, P32 ≈ 5 in a
unit cube): clean 0.05 s, build 0.1 s, fragment 1-1.2 s, surfaces 1-3 s, volume 14-23 s
for 0.26-0.33 million tetrahedra and 70-112 s for 0.9-1.3 million (HXT-Delaunay), i.e.
80-90 s per million tetrahedra. A failed fragment or mesh, or a mesh that does not
conform to the fractures, raises :class:`ValueError` naming the step, gmsh's message
and, when gmsh names surfaces, their fractures (input numbers). gmsh's terminal output
stays off (``General.Terminal`` 0) unless ``verbose``.
"""

from __future__ import annotations

import math
import re
import time
from collections.abc import Sequence
from types import ModuleType
from typing import Any

import numpy as np

from geofrac.dfn3d.clean import clean_discs, seam_directions
from geofrac.dfn3d.network import DiscNetwork
from geofrac.meshing.quality import tetrahedron_quality, triangle_angles

__all__ = [
    "ALGORITHMS_3D",
    "FACE_GROUPS",
    "FRACTURE_GROUP",
    "ROCK_GROUP",
    "mesh_discs",
]

#: gmsh ``Mesh.Algorithm3D`` numbers by name (HXT is multi-threaded). Frontal (4) is not
#: offered: it ignores embedded surfaces (measured: none of 33,309 fracture triangles of
#: a 1,000-disc network was a face of its tetrahedra).
ALGORITHMS_3D = {"delaunay": 1, "hxt": 10}
#: Physical group names.
ROCK_GROUP = "rock"
FRACTURE_GROUP = "fractures"
#: Box face group names: face (axis k, lower/upper) is FACE_GROUPS[2 k + upper].
FACE_GROUPS = ("xmin", "xmax", "ymin", "ymax", "zmin", "zmax")
#: Largest Distance-field sampling (points per direction) of one piece.
_MAX_SAMPLING = 512


def _gmsh_error(gmsh: ModuleType, exc: BaseException) -> str:
    """Gmsh's message for ``exc``, with the errors it logged if the logger runs."""
    text = str(exc).strip()
    try:
        logged = [line for line in gmsh.logger.get() if line.startswith("Error")]
    except Exception:  # no logger, or the session is gone
        logged = []
    extra = [line for line in logged[-5:] if line not in text]
    return "; ".join([text, *extra]) if extra else text


def _named_fractures(message: str, surface_fracture: dict[int, int]) -> list[int]:
    """Fractures whose surfaces gmsh's ``message`` names ("surface 12", "facet ... #12")."""
    tags = {int(t) for t in re.findall(r"(?:[Ss]urface|#)\s*(\d+)", message)}
    return sorted({surface_fracture[t] for t in tags if t in surface_fracture})


def _fail(step: str, message: str, fractures: Sequence[int] = ()) -> ValueError:
    named = f" (fractures {', '.join(map(str, fractures))})" if fractures else ""
    return ValueError(f"gmsh {step} failed{named}: {message or 'no message from gmsh'}")


class _Model:
    """The OCC model of a box and its discs, after the fragment."""

    def __init__(
        self, gmsh: ModuleType, network: DiscNetwork, *, box: np.ndarray, kept: np.ndarray
    ) -> None:
        self.gmsh, self.network, self.box = gmsh, network, box
        self.kept = kept  # input number of each row of ``network``
        self.disks: list[int] = []
        self.volumes: list[int] = []
        self.piece_fracture: dict[int, int] = {}  # surface tag -> row of ``network``
        self.outside = 0
        self.shared = 0

    def build(self) -> None:
        """The box and one disk per fracture (not synchronised)."""
        occ = self.gmsh.model.occ
        lo, hi = self.box
        self.volumes = [occ.addBox(*lo, *(hi - lo))]
        net = self.network
        seam = seam_directions(net, box=self.box)
        self.disks = [
            occ.addDisk(
                *net.centre[k],
                net.radius[k],
                net.radius[k],
                zAxis=net.normal[k].tolist(),
                xAxis=seam[k].tolist(),
            )
            for k in range(net.size)
        ]

    def fragment(self) -> None:
        """Fragment the box with the disks, map the pieces, remove those outside."""
        gmsh = self.gmsh
        occ = gmsh.model.occ
        if self.disks:
            tools = [(2, t) for t in self.disks]
            try:
                _, out_map = occ.fragment([(3, self.volumes[0])], tools)
            except Exception as exc:
                raise _fail("fragment", _gmsh_error(gmsh, exc)) from exc
            self.volumes = [t for d, t in out_map[0] if d == 3]
            occ.synchronize()
            self._classify(out_map[1:])
        occ.synchronize()

    def _classify(self, pieces: list[list[tuple[int, int]]]) -> None:
        """Keep the pieces inside the box in ``piece_fracture``; remove the others.

        Inside means in the rock's topology: embedded in a volume, or on the boundary of
        a volume but not of the box (a piece splitting the rock). No geometric test: a
        piece outside may be an annulus whose centre of mass lies in the box.
        """
        model = self.gmsh.model
        vols = [(3, v) for v in self.volumes]
        inside = {t for v in self.volumes for d, t in model.mesh.getEmbedded(3, v) if d == 2}
        walls = {abs(t) for _, t in model.getBoundary(vols, combined=False, oriented=False)}
        outer = {abs(t) for _, t in model.getBoundary(vols, combined=True, oriented=False)}
        inside |= walls - outer
        outside: list[tuple[int, int]] = []
        seen: set[int] = set()
        for k, dimtags in enumerate(pieces):
            for d, tag in dimtags:
                if d != 2:
                    continue
                if tag in seen:  # a piece two coplanar disks share: the first keeps it
                    self.shared += 1
                    continue
                seen.add(tag)
                if tag in inside:
                    self.piece_fracture[tag] = k
                elif tag not in outer:  # a piece on a box face stays a face
                    outside.append((2, tag))
        self.outside = len(outside)
        if outside:
            model.occ.remove(outside, recursive=True)

    def box_faces(self) -> list[list[int]]:
        """Surface tags of each box face (order of :data:`FACE_GROUPS`)."""
        model = self.gmsh.model
        lo, hi = self.box
        eps = 1e-6 * float(np.max(hi - lo))
        faces: list[list[int]] = [[] for _ in FACE_GROUPS]
        bounds = model.getBoundary([(3, v) for v in self.volumes], combined=True, oriented=False)
        for _, tag in bounds:
            bb = np.array(model.getBoundingBox(2, abs(tag))).reshape(2, 3)
            for axis in range(3):
                if bb[1, axis] - bb[0, axis] > eps:
                    continue
                mid = 0.5 * (bb[0, axis] + bb[1, axis])
                upper = abs(mid - hi[axis]) < abs(mid - lo[axis])
                faces[2 * axis + upper].append(abs(tag))
        return faces

    def groups(self) -> dict[str, tuple[int, list[int]]]:
        """Physical group name -> (dimension, entity tags), made in the model."""
        model = self.gmsh.model
        net = self.network
        groups: dict[str, tuple[int, list[int]]] = {ROCK_GROUP: (3, list(self.volumes))}
        for name, tags in zip(FACE_GROUPS, self.box_faces(), strict=True):
            groups[name] = (2, tags)
        pieces = sorted(self.piece_fracture)
        if pieces:
            groups[FRACTURE_GROUP] = (2, pieces)
        for s, name in enumerate(net.set_names):
            tags = [p for p in pieces if net.set_index[self.piece_fracture[p]] == s]
            if tags:
                groups[name] = (2, tags)
        for name, (dim, tags) in groups.items():
            if tags:
                model.addPhysicalGroup(dim, tags, name=name)
        return groups


def _size_field(
    gmsh: ModuleType, pieces: list[int], *, fine: float, coarse: float, transition: float
) -> int:
    """Threshold field on binned Distance fields to ``pieces``; returns its tag (0: none)."""
    if not pieces or fine >= coarse:
        return 0
    model = gmsh.model
    field = model.mesh.field
    bins: dict[int, list[int]] = {}
    for tag in pieces:
        low, high = model.getParametrizationBounds(2, tag)
        extent = float(np.max(np.asarray(high) - np.asarray(low)))
        need = math.ceil(extent / fine) + 1
        sampling = min(max(4, 1 << max(need - 1, 1).bit_length()), _MAX_SAMPLING)
        bins.setdefault(sampling, []).append(tag)
    distances = []
    for sampling, tags in sorted(bins.items()):
        distance = field.add("Distance")
        field.setNumbers(distance, "SurfacesList", tags)
        field.setNumber(distance, "Sampling", sampling)
        distances.append(distance)
    nearest = distances[0]
    if len(distances) > 1:
        nearest = field.add("Min")
        field.setNumbers(nearest, "FieldsList", distances)
    threshold = field.add("Threshold")
    field.setNumber(threshold, "InField", nearest)
    field.setNumber(threshold, "SizeMin", fine)
    field.setNumber(threshold, "SizeMax", coarse)
    field.setNumber(threshold, "DistMin", fine)  # every fracture point is < fine from a sample
    field.setNumber(threshold, "DistMax", fine + transition)
    field.setAsBackgroundMesh(threshold)
    return threshold


def _node_index(gmsh: ModuleType) -> tuple[np.ndarray, np.ndarray]:
    """(node coordinates, shape=(num_nodes, 3); tag -> row, shape=(max tag + 1,))."""
    tags, coords, _ = gmsh.model.mesh.getNodes()
    tags = tags.astype(np.int64)
    index = np.full(int(tags.max()) + 1 if len(tags) else 1, -1, dtype=np.int64)
    index[tags] = np.arange(len(tags))
    return coords.reshape(-1, 3), index


def _tet_faces_per_triangle(tets: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    """How many tetrahedra have each triangle as a face.

    Args:
        tets: node rows of the tetrahedra, shape=(n, 4).
        triangles: node rows of the triangles, shape=(m, 3).

    Returns:
        shape=(m,).
    """
    faces = np.sort(tets[:, [[1, 2, 3], [0, 2, 3], [0, 1, 3], [0, 1, 2]]].reshape(-1, 3), axis=1)
    tri = np.sort(triangles, axis=1)
    n = int(max(faces.max(initial=0), tri.max(initial=0))) + 1
    if n**3 < 2**63:  # one int64 key per node triple: sort and search, no row-wise unique
        face_key = np.sort((faces[:, 0] * n + faces[:, 1]) * n + faces[:, 2])
        tri_key = (tri[:, 0] * n + tri[:, 1]) * n + tri[:, 2]
        return np.searchsorted(face_key, tri_key, "right") - np.searchsorted(face_key, tri_key)
    _, inverse = np.unique(np.concatenate([faces, tri]), axis=0, return_inverse=True)
    inverse = inverse.ravel()
    counts = np.bincount(inverse[: len(faces)], minlength=int(inverse.max()) + 1)
    return counts[inverse[len(faces) :]]


def _mesh_report(gmsh: ModuleType, model: _Model, faces: list[list[int]]) -> dict[str, Any]:
    """Counts and quality of the meshed model."""
    mesh = gmsh.model.mesh
    x, index = _node_index(gmsh)
    _, tet_nodes = mesh.getElementsByType(4)
    tets = index[tet_nodes.astype(np.int64)].reshape(-1, 4)
    tri: list[np.ndarray] = []
    empty = []
    for tag, k in sorted(model.piece_fracture.items()):
        _, nodes = mesh.getElementsByType(2, tag)
        if len(nodes) == 0:
            empty.append(int(model.kept[k]))
        tri.append(index[nodes.astype(np.int64)].reshape(-1, 3))
    if empty:
        raise _fail("mesh", "fracture pieces without triangles", sorted(set(empty)))
    if len(tets) == 0:
        raise _fail("mesh", "no tetrahedra")
    triangles = np.concatenate(tri) if tri else np.zeros((0, 3), dtype=np.int64)
    shared = _tet_faces_per_triangle(tets, triangles)
    if np.any(shared != 2):
        owner = np.repeat(
            [model.kept[k] for _, k in sorted(model.piece_fracture.items())], [len(t) for t in tri]
        )
        bad = sorted({int(f) for f in owner[shared != 2]})
        raise _fail(
            "mesh",
            f"{int(np.sum(shared != 2))} of {len(triangles)} fracture triangles are not a face "
            "of exactly two tetrahedra (a 3D algorithm that ignores embedded surfaces?)",
            bad,
        )
    corners = x[triangles]
    area = 0.5 * np.linalg.norm(
        np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0]), axis=1
    )
    boundary = sum(len(mesh.getElementsByType(2, t)[1]) // 3 for tags in faces for t in tags)
    return {
        "nodes": len(x),
        "max_node_tag": len(index) - 1,
        "tetrahedra": len(tets),
        "fracture_triangles": len(triangles),
        "boundary_triangles": boundary,
        "fracture_area": float(area.sum()),
        **tetrahedron_quality(x[tets]),
        "fracture_min_angle_deg": float(np.min(triangle_angles(corners)))
        if len(triangles)
        else 180.0,
    }


def mesh_discs(
    gmsh: ModuleType,
    network: DiscNetwork,
    *,
    box: np.ndarray | Sequence[Sequence[float]],
    mesh_size: float,
    fracture_mesh_size: float,
    algorithm3d: str = "hxt",
    tolerance: float | None = None,
    transition: float | None = None,
    min_radius: float | None = None,
    clean: bool = True,
    threads: int = 1,
    verbose: bool = False,
) -> dict[str, Any]:
    """Build, fragment and mesh a box cut by ``network`` in the current gmsh session.

    Args:
        gmsh: the gmsh module, initialised. A model ``dfn3d`` is added and left current:
            synchronised, meshed (first-order tetrahedra), with the physical groups of
            this module's docstring and the size field; node tags are 1..``nodes``.
        network: the discs (any may lie partly or wholly outside the box).
        box: lower and upper corner, shape=(2, 3).
        mesh_size: element size away from the fractures.
        fracture_mesh_size: element size on the fractures (<= ``mesh_size``).
        algorithm3d: a key of :data:`ALGORITHMS_3D`. HXT by default: on the bench's
            1,000 discs it was 1.6 times faster than Delaunay and its worst tetrahedron
            better (minimum dihedral angle 2.4° against 1.4°; 2.8° against 0.01° at half
            the fracture element size).
        tolerance: the cleaning tolerance (default ``fracture_mesh_size / 4``).
        transition: distance over which the size grows from ``fracture_mesh_size`` to
            ``mesh_size`` (default ``mesh_size``).
        min_radius: smallest disc kept by the cleaning (default: the tolerance).
        clean: False to mesh ``network`` as given (already cleaned; the report's
            ``cleaning`` is then None).
        threads: gmsh threads (``General.NumThreads``; HXT uses them, 1 = one core).
        verbose: let gmsh write to the terminal.

    Returns:
        A JSON-ready report: ``fractures`` (input), ``fractures_cleaned`` (after the
        cleaning), ``fractures_inside`` (with a piece in the box), ``fractures_dropped``,
        ``pieces`` (fracture surfaces in the box), ``pieces_removed`` (outside the box),
        ``shared_pieces``, ``volumes``, ``cleaning`` (the cleaning report's ``as_dict``),
        ``groups`` (name -> [dimension, number of entities]), ``surface_fracture``
        ([surface tag, input fracture number] per piece), ``nodes``, ``max_node_tag``,
        ``tetrahedra``, ``fracture_triangles``, ``boundary_triangles``, ``fracture_area``,
        ``min_dihedral_deg``, ``max_dihedral_deg``, ``max_aspect_ratio``,
        ``mean_aspect_ratio``, ``min_volume``, ``fracture_min_angle_deg``, the inputs
        (``mesh_size``, ``fracture_mesh_size``, ``tolerance``, ``transition``,
        ``algorithm3d``, ``threads``) and the times ``time_clean_s``, ``time_build_s``,
        ``time_fragment_s``, ``time_mesh_surface_s``, ``time_mesh_volume_s``,
        ``time_mesh_s`` (surface + volume), ``time_quality_s``.

    Raises:
        ValueError: bad sizes or algorithm, a set named like a box face or group, or
            gmsh failed (the step, its message, the fractures it named).
    """
    box_arr = np.asarray(box, dtype=float).reshape(2, 3)
    if not (0 < fracture_mesh_size <= mesh_size and math.isfinite(mesh_size)):
        raise ValueError(
            f"need 0 < fracture_mesh_size <= mesh_size, got {fracture_mesh_size!r}, {mesh_size!r}"
        )
    if algorithm3d not in ALGORITHMS_3D:
        raise ValueError(f"unknown 3D algorithm {algorithm3d!r}; choose from {list(ALGORITHMS_3D)}")
    reserved = {ROCK_GROUP, FRACTURE_GROUP, *FACE_GROUPS} & set(network.set_names)
    if reserved:
        raise ValueError(f"fracture set names {sorted(reserved)} clash with group names")
    tol = fracture_mesh_size / 4 if tolerance is None else float(tolerance)
    grow = mesh_size if transition is None else float(transition)
    times: dict[str, float] = {}
    start = time.perf_counter()
    cleaned, report = network, None
    kept = np.arange(network.size)
    if clean:
        cleaned, report = clean_discs(network, box=box_arr, tolerance=tol, min_radius=min_radius)
        kept = report.kept
    times["clean"] = time.perf_counter() - start

    option = gmsh.option
    option.setNumber("General.Terminal", 1 if verbose else 0)
    option.setNumber("General.NumThreads", threads)
    gmsh.model.add("dfn3d")
    model = _Model(gmsh, cleaned, box=box_arr, kept=kept)
    start = time.perf_counter()
    model.build()
    times["build"] = time.perf_counter() - start
    start = time.perf_counter()
    model.fragment()
    times["fragment"] = time.perf_counter() - start
    groups = model.groups()
    surface_fracture = {t: int(kept[k]) for t, k in model.piece_fracture.items()}
    pieces = sorted(model.piece_fracture)

    option.setNumber("Mesh.MeshSizeMax", mesh_size)
    option.setNumber("Mesh.MeshSizeFromCurvature", 0)
    option.setNumber("Mesh.MeshSizeFromPoints", 1)
    option.setNumber("Mesh.MeshSizeExtendFromBoundary", 1)
    option.setNumber("Mesh.Algorithm3D", ALGORITHMS_3D[algorithm3d])
    option.setNumber("Mesh.ElementOrder", 1)
    if pieces:
        points = gmsh.model.getBoundary(
            [(2, t) for t in pieces], combined=False, oriented=False, recursive=True
        )
        gmsh.model.mesh.setSize(points, fracture_mesh_size)
    mesh = gmsh.model.mesh
    try:
        start = time.perf_counter()
        mesh.generate(2)
        times["mesh_surface"] = time.perf_counter() - start
        start = time.perf_counter()
        option.setNumber("Mesh.MeshSizeExtendFromBoundary", 0)
        _size_field(gmsh, pieces, fine=fracture_mesh_size, coarse=mesh_size, transition=grow)
        mesh.generate(3)
        times["mesh_volume"] = time.perf_counter() - start
    except Exception as exc:
        message = _gmsh_error(gmsh, exc)
        raise _fail("mesh", message, _named_fractures(message, surface_fracture)) from exc
    start = time.perf_counter()
    faces = [groups[name][1] for name in FACE_GROUPS]
    quality = _mesh_report(gmsh, model, faces)
    times["quality"] = time.perf_counter() - start
    inside = len(set(model.piece_fracture.values()))
    return {
        "fractures": network.size,
        "fractures_cleaned": cleaned.size,
        "fractures_inside": inside,
        "fractures_dropped": network.size - inside,
        "pieces": len(pieces),
        "pieces_removed": model.outside,
        "shared_pieces": model.shared,
        "volumes": len(model.volumes),
        "cleaning": report.as_dict() if report is not None else None,
        "groups": {name: [dim, len(tags)] for name, (dim, tags) in groups.items() if tags},
        "surface_fracture": [[t, f] for t, f in sorted(surface_fracture.items())],
        **quality,
        "mesh_size": mesh_size,
        "fracture_mesh_size": fracture_mesh_size,
        "tolerance": tol,
        "transition": grow,
        "algorithm3d": algorithm3d,
        "threads": threads,
        **{f"time_{k}_s": v for k, v in times.items()},
        "time_mesh_s": times["mesh_surface"] + times["mesh_volume"],
    }
