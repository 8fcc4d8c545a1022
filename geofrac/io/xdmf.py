"""XDMF + HDF5 output that ParaView, meshio and pyvista all read.

DOLFINx's :class:`~dolfinx.io.XDMFFile` writes the heavy data in parallel, but it puts
every function in its own temporal collection and shares the mesh through
``xi:include``; meshio then sees only one function and VTK's XDMF reader (pyvista)
crashes. After DOLFINx has written, rank 0 rewrites only the small XML part into one
temporal collection whose steps carry every field, referring to the same HDF5
datasets. See :func:`regroup_xdmf`.

XDMF stores node data at the nodes of the mesh geometry: on straight cells the vertices,
on curved cells (a second-order gmsh geometry) the vertices and edge midpoints, written as
``Triangle_6`` / ``Tetrahedron_10`` cells that ParaView draws curved. :func:`on_geometry`
brings each continuous field to the degree of the geometry; cell (DG0) fields are written
as they are.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from collections.abc import Sequence
from pathlib import Path

import dolfinx_solver  # noqa: F401  (orders MPI before the DOLFINx bindings)

import dolfinx
from dolfinx.io import XDMFFile

from geofrac.io.series import write_xml

__all__ = ["on_geometry", "regroup_xdmf", "write_fields", "write_meshtags", "write_steps"]


def on_geometry(fn: dolfinx.fem.Function) -> dolfinx.fem.Function:
    """``fn`` as XDMF can store it: a Lagrange field of the mesh's geometry degree.

    A DG0 field, or a Lagrange field of that degree, is returned as it is. Another
    Lagrange field is interpolated into Lagrange of the geometry degree with the same
    value shape and name: a P2 or P3 displacement on straight cells goes to P1 (its
    vertex values); a P1 nodal average on curved cells goes to P2 exactly (P1 is linear
    in the reference cell, which P2 contains).

    Raises:
        ValueError: a discontinuous field of degree > 0 (no node data to write).
    """
    space = fn.function_space
    mesh = space.mesh
    geometry_degree = mesh.geometry.cmaps[0].degree
    element = space.ufl_element()
    degree = element.embedded_superdegree
    if element.discontinuous:
        if degree != 0:
            raise ValueError(f"XDMF cannot store '{fn.name}': discontinuous of degree {degree}")
        return fn
    if degree == geometry_degree:
        return fn
    target = dolfinx.fem.functionspace(mesh, ("Lagrange", geometry_degree, space.value_shape))
    out = dolfinx.fem.Function(target, name=fn.name)
    out.interpolate(fn)
    return out


def write_fields(
    path: Path,
    mesh: dolfinx.mesh.Mesh,
    functions: Sequence[dolfinx.fem.Function],
    *,
    t: float = 0.0,
) -> Path:
    """Write ``functions`` at time ``t`` to ``path`` (.xdmf) and its sibling ``.h5``.

    Functions are Lagrange (node data, brought to the geometry degree by
    :func:`on_geometry`) or DG0 (cell data) on ``mesh``.

    Returns:
        ``path``.
    """
    with XDMFFile(mesh.comm, str(path), "w") as f:
        f.write_mesh(mesh)
        for fn in functions:
            f.write_function(on_geometry(fn), t)
    mesh.comm.barrier()
    if mesh.comm.rank == 0:
        regroup_xdmf(path)
    mesh.comm.barrier()
    return path


def write_steps(
    path: Path,
    mesh: dolfinx.mesh.Mesh,
    steps: Sequence[Sequence[dolfinx.fem.Function]],
) -> Path:
    """Write one time step per entry of ``steps`` (time = its index), as :func:`write_fields`.

    Every step has functions of the same names (a staged run's displacement and stresses
    after each stage).

    Returns:
        ``path``.
    """
    with XDMFFile(mesh.comm, str(path), "w") as f:
        f.write_mesh(mesh)
        for t, functions in enumerate(steps):
            for fn in functions:
                f.write_function(on_geometry(fn), float(t))
    mesh.comm.barrier()
    if mesh.comm.rank == 0:
        regroup_xdmf(path)
    mesh.comm.barrier()
    return path


def write_meshtags(
    path: Path, mesh: dolfinx.mesh.Mesh, tags: Sequence[dolfinx.mesh.MeshTags]
) -> Path:
    """Write the entities of ``tags`` as one grid with one cell field per tag set.

    All ``tags`` must tag the same entities in the same order (e.g. the fracture facets,
    once with their fracture number and once with their set); each is named by its
    ``name``. DOLFINx writes the mesh and one grid per tag set; rank 0 then rewrites the
    XML as a single-step temporal collection of the tagged entities carrying every tag
    as a cell field, which ParaView, pyvista and meshio all read (see
    :func:`regroup_xdmf` for why). The triangle mesh stays in the HDF5 file.

    Returns:
        ``path``.
    """
    tdim = mesh.topology.dim
    with XDMFFile(mesh.comm, str(path), "w") as f:
        f.write_mesh(mesh)
        for t in tags:
            mesh.topology.create_connectivity(t.dim, tdim)
            f.write_meshtags(
                t, mesh.geometry, geometry_xpath=f"/Xdmf/Domain/Grid[@Name='{mesh.name}']/Geometry"
            )
    mesh.comm.barrier()
    if mesh.comm.rank == 0:
        _tags_as_collection(path, mesh.name, [t.name for t in tags])
    mesh.comm.barrier()
    return path


def _tags_as_collection(path: Path, mesh_name: str, names: Sequence[str]) -> None:
    tree = ET.parse(path)
    domain = tree.getroot().find("Domain")
    assert domain is not None
    grids = {g.get("Name"): g for g in domain.findall("Grid")}
    geometry = grids[mesh_name].find("Geometry")
    topology = grids[names[0]].find("Topology")
    assert topology is not None
    if topology.get("TopologyType") == "PolyLine":  # XDMF readers uppercase; meshio wants this
        topology.set("TopologyType", "Polyline")
    root = ET.Element("Xdmf", Version="3.0")
    series = ET.SubElement(
        ET.SubElement(root, "Domain"),
        "Grid",
        Name=names[0],
        GridType="Collection",
        CollectionType="Temporal",
    )
    grid = ET.SubElement(series, "Grid", Name=f"{names[0]}_step_0", GridType="Uniform")
    grid.append(topology)
    grid.append(geometry)  # type: ignore[arg-type]
    ET.SubElement(grid, "Time", Value="0")
    for name in names:
        grid.append(grids[name].find("Attribute"))  # type: ignore[arg-type]
    write_xml(root, path)


def regroup_xdmf(path: Path) -> None:
    """Rewrite a DOLFINx XDMF file as one temporal collection with all fields per step.

    Only XML is touched; the HDF5 datasets stay where DOLFINx wrote them.
    """
    tree = ET.parse(path)
    domain = tree.getroot().find("Domain")
    assert domain is not None
    grids = domain.findall("Grid")
    mesh_grid = next(g for g in grids if g.get("GridType") == "Uniform")
    topology, geometry = mesh_grid.find("Topology"), mesh_grid.find("Geometry")
    steps: dict[str, list[ET.Element]] = {}
    for collection in grids:
        if collection.get("GridType") != "Collection":
            continue
        for step in collection.findall("Grid"):
            time = step.find("Time")
            key = time.get("Value", "0") if time is not None else "0"
            steps.setdefault(key, []).extend(step.findall("Attribute"))
    root = ET.Element("Xdmf", Version="3.0")
    new_domain = ET.SubElement(root, "Domain")
    series = ET.SubElement(
        new_domain, "Grid", Name="results", GridType="Collection", CollectionType="Temporal"
    )
    for i, (time_value, attributes) in enumerate(
        sorted(steps.items(), key=lambda kv: float(kv[0]))
    ):
        grid = ET.SubElement(series, "Grid", Name=f"step_{i}", GridType="Uniform")
        grid.append(topology)  # type: ignore[arg-type]
        grid.append(geometry)  # type: ignore[arg-type]
        ET.SubElement(grid, "Time", Value=time_value)
        for attribute in attributes:
            grid.append(attribute)
    write_xml(root, path)
