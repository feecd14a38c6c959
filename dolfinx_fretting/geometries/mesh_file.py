"""A mesh file (``geometry.kind = "file"``, 2D): the user's gmsh ``.msh`` file with physical groups, or a DOLFINx
XDMF file with its facet meshtags, held by the conditions of the ``[boundary]`` section (by the names of its
groups) and pressed on a rigid plane; with several ``[[contact]]`` tables, one rigid plane per named facet group
(the only kind with several contact surfaces).

Nothing of the body is known before the file is read: no preset, no Hertz reference, no mesh refinement in a
study; its size estimate counts the nodes in the file's header. What the file must be is checked as it is read,
before DOLFINx sees it (:func:`~dolfinx_fretting.scene_models.read_msh`,
:func:`~dolfinx_fretting.scene_models.read_xdmf`: an existing, non-empty 2D mesh of one cell type with named
physical groups, an XDMF file with its ``.h5``); what the scene asks of it once it is read, before anything is
assembled (:func:`check_names`, :func:`check_surfaces`, :func:`check_strain`: every group the scene names is one of
the file's, one role per group, contact surfaces and pressed faces on the body's boundary, a contact surface with a
node free to move, loads in small strain on the file's geometry). Each refusal is a
:class:`~dolfinx_fretting.scene_models.MeshFileError` naming the file.
"""

from __future__ import annotations

import re
import time
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
from mpi4py import MPI

from ..meshes import BodyMesh
from ..scene_models import (BOUNDARY_DISPLACEMENT, BOUNDARY_PRESSURE, MeshFileError, SceneModel, axis_normal,
                            boundary_pressure, contact_surface, displacement_conditions, elastic_model, facet_length,
                            further_zones, read_msh, read_xdmf, rigid_plane, roller)
from .base import MAX_ELASTIC_STRAIN, Geometry, MeshSize, check_plane_strain, range_error

__all__ = ["MeshFile", "check_names", "check_surfaces", "check_strain", "msh_node_count", "xdmf_node_count"]


class MeshFile(Geometry):
    """``geometry.kind = "file"``."""

    def refuse_own_keys(self, geometry: GeometrySettings) -> None:
        """``path`` and ``groups`` are the mesh file's."""
        if geometry.path is not None or geometry.groups is not None:
            key, value = (("geometry.path", geometry.path) if geometry.path is not None
                          else ("geometry.groups", geometry.groups))
            raise range_error(key, value, f"unset with geometry.kind = {geometry.kind!r} (the mesh is built in); set "
                              "geometry.kind = 'file' to read a mesh file")

    def check_geometry(self, geometry: GeometrySettings) -> None:
        """A ``.msh`` or ``.xdmf`` path; names of the markers for an XDMF file only."""
        if geometry.path is None:
            raise ValueError("geometry.path (a gmsh .msh or an XDMF file) is required with geometry.kind = 'file'")
        if not geometry.path.endswith((".msh", ".xdmf")):
            raise range_error("geometry.path", geometry.path, "a gmsh .msh file (with physical groups) or a DOLFINx "
                              ".xdmf file (with facet meshtags)")
        if geometry.groups is not None and not geometry.path.endswith(".xdmf"):
            raise range_error("geometry.groups", geometry.groups, "unset with a .msh file (its physical groups "
                              "carry their names); only an .xdmf file's markers need names")
        named = {}
        for name, marker in (geometry.groups or {}).items():
            if marker in named:
                raise range_error(f"geometry.groups.{name}", marker, f"a marker no other name has (geometry.groups."
                                  f"{named[marker]} = {marker} too): one name per facet marker")
            named[marker] = name

    def check_scene(self, scene: Scene) -> None:
        """A ``[boundary]`` that holds the body, a rigid plane, displacement vectors of the plane's dimension, a 2D
        plane."""
        boundary, contact = scene.boundary, scene.contact
        if not (boundary.fixed or boundary.displacement):
            raise ValueError("boundary: a mesh file needs boundary.fixed or boundary.displacement (names of "
                             "its physical groups) to hold the body")
        if contact.obstacle != "rigid_plane":
            raise range_error("contact.obstacle", contact.obstacle, "'rigid_plane' with geometry.kind = 'file'")
        for name, vector in boundary.displacement.items():
            if len(vector) != len(contact.plane_normal):
                raise range_error(f"boundary.displacement.{name}", vector, f"a {len(contact.plane_normal)}-vector (mm)")
        check_plane_strain(scene)

    def check_loads(self, scene: Scene) -> None:
        """A ``boundary.pressure`` of at most MAX_ELASTIC_STRAIN x E (the loads on the file's geometry are checked
        once it is read: :func:`check_strain`)."""
        eps, E = MAX_ELASTIC_STRAIN, scene.material.E
        for name, pressure in scene.boundary.pressure.items():
            if abs(pressure) > eps * E:
                raise range_error(f"boundary.pressure.{name}", pressure, f"|p| <= {eps:g} x material.E = {eps * E:.4g} "
                                  "MPa (small-strain elasticity)")

    def mesh_size(self, scene: Scene) -> MeshSize:
        """The nodes in the file's header (None if it has none); the contacts are not counted (the surface is not
        read before meshing)."""
        path = scene.geometry.path
        nodes = xdmf_node_count(path) if path.endswith(".xdmf") else msh_node_count(path)
        notes = [f"nodes not estimated (no node count in the header of {path})"] if nodes is None else []
        notes.append("contacts not estimated (a mesh file's surface is not read before meshing): W not counted")
        return MeshSize(nodes, None, True, "gmsh", "quadrilateral", {"geometry.path": path},
                        window_default="the whole surface", notes=tuple(notes))

    def build(self, scene: Scene, comm: MPI.Comm) -> SceneModel:
        """The user's mesh file with the conditions of ``[boundary]`` by physical name: clamps, rollers on plane
        faces normal to an axis, displacements and pressures ramped with the preload; the contact element size is
        the median length of the contact surface's facets."""
        geometry, boundary = scene.geometry, scene.boundary
        start = time.perf_counter()
        if geometry.path.endswith(".xdmf"):
            body, _ = read_xdmf(geometry.path, comm, geometry.groups)
        else:
            body, _ = read_msh(geometry.path, comm)
        check_names(scene, body.tags)
        check_surfaces(scene, body)
        surface_extent = check_strain(scene, body)
        mesh_s = time.perf_counter() - start
        V, form, von_mises, bcs, loads = elastic_model(scene, body, list(boundary.fixed))
        for name in boundary.symmetry:
            bcs.append(roller(V, body.facets(name), axis_normal(V, body.facets(name), name)))
        prescribed = {}
        if boundary.displacement:
            prescribed[BOUNDARY_DISPLACEMENT] = displacement_conditions(V, body, boundary.displacement)
        if boundary.pressure:
            loads[BOUNDARY_PRESSURE] = boundary_pressure(V, body, boundary.pressure)
        surface = contact_surface(scene, body)
        h = facet_length(V, body.facets(scene.contact.surface))
        body = BodyMesh(body.mesh, body.facet_tags, body.cell_tags, body.tags, h, None, {}, body.regions)
        # A window the scene gives is watched as a built-in body's is: load on its outermost candidates means a
        # truncated contact, and the window grows (by half, at least three elements) up to the surface's extent,
        # where it holds the whole surface; without a window the whole surface is candidate and its ends are the
        # surface's own.
        window = scene.contact.candidate_half_width
        return SceneModel(body=body, V=V, form=form, bcs=bcs, surface=surface, obstacle=rigid_plane(scene),
                          loads=loads, element_size=h, window=window,
                          window_limit=max(surface_extent, window) if window is not None else None,
                          window_automatic=False, window_edges_matter=window is not None, elastic_cells=None,
                          display_cells=None, hertz=None, small_sliding=False, contact_text=", against a rigid plane",
                          von_mises=von_mises, timings={"mesh_s": mesh_s}, prescribed=prescribed,
                          ramped=[name for name in (BOUNDARY_DISPLACEMENT, BOUNDARY_PRESSURE)
                                  if name in prescribed or name in loads],
                          zones=further_zones(scene, body))


def _file(scene: Scene) -> str:
    """The mesh file's absolute path, for a message (a scene validated from a dict may hold a relative one)."""
    return str(Path(scene.geometry.path).resolve())


def _file_groups(scene: Scene, facet_names: dict[str, int]) -> str:
    """``"<file>; the file's boundary groups: a, b"`` for a refusal's message."""
    return (f"{_file(scene)}; the file's boundary groups: {', '.join(sorted(facet_names)) or 'none'}"
            + (" (an XDMF file's markers are named by geometry.groups, else by their numbers)"
               if scene.geometry.path.endswith(".xdmf") else ""))


def contact_keys(scene: Scene) -> list[tuple[str, str]]:
    """(key, group name) of every contact surface of the scene: ``contact.surface``, then ``contact[i].surface``."""
    return [("contact.surface", scene.contact.surface),
            *[(f"contact[{i}].surface", zone.surface) for i, zone in enumerate(scene.zones, start=1)]]


def check_names(scene: Scene, facet_names: dict[str, int]) -> None:
    """Every boundary name the scene uses must be a physical group of the file, and each group has one role: one
    contact zone or one boundary condition (once it is read, before any work).

    Raises:
        MeshFileError: naming the key, the name, the file and its groups.
    """
    used = [*contact_keys(scene), *scene.boundary.names]
    if scene.loading.tangential_kind == "pressure":
        used.append(("loading.pressure_face", scene.loading.pressure_face))
    for key, name in used:
        if name not in facet_names:
            raise MeshFileError(f"{key} = {name!r} is not a physical group of {_file_groups(scene, facet_names)}")
    role: dict[str, str] = {}
    for key, name in [*contact_keys(scene), *scene.boundary.names]:
        if name in role:
            raise MeshFileError(f"{key} = {name!r} is also {role[name]} = {name!r}: one role per group of "
                                f"{_file(scene)} (a contact surface held by a condition cannot touch its plane, "
                                "two conditions on one group contradict or repeat each other)")
        role[name] = key


def _owned(msh, facets: np.ndarray) -> np.ndarray:
    """The ones of ``facets`` (local indices) this rank owns: each facet counted once over the ranks."""
    fdim = msh.topology.dim - 1
    return facets[facets < msh.topology.index_map(fdim).size_local]


def check_surfaces(scene: Scene, body: BodyMesh) -> None:
    """Each contact surface (and pressed face) holds facets of the body's boundary, and some node of each contact
    surface is free to move (not all held by ``boundary.fixed`` or ``boundary.displacement``). Collective (the
    counts summed over ranks: the same answer everywhere).

    Raises:
        MeshFileError: naming the key, the group and the file.
    """
    from dolfinx import mesh as dmesh  # lazy: DOLFINx (the schema imports this module)

    msh, comm = body.mesh, body.mesh.comm
    tdim = msh.topology.dim
    fdim = tdim - 1
    msh.topology.create_connectivity(fdim, tdim)
    msh.topology.create_connectivity(fdim, 0)
    exterior = dmesh.exterior_facet_indices(msh.topology)
    pressed = [(f"boundary.pressure.{name}", name) for name in scene.boundary.pressure]
    if scene.loading.tangential_kind == "pressure":
        pressed.append(("loading.pressure_face", scene.loading.pressure_face))
    for key, name in [*contact_keys(scene), *pressed]:
        owned = _owned(msh, body.facets(name))
        total, inside = comm.allreduce(np.array([owned.size, np.setdiff1d(owned, exterior).size]))
        if total == 0:
            raise MeshFileError(f"{key} = {name!r}: the group holds no facet in {_file(scene)} (a physical "
                                "group of no mesh element: no contact candidate or loaded face)")
        if inside:
            raise MeshFileError(f"{key} = {name!r}: {inside} of its {total} facets in {_file(scene)} lie "
                                "inside the body, not on its boundary (a contact surface or a pressed face is a "
                                "boundary curve)")
    held = [*scene.boundary.fixed, *scene.boundary.displacement]
    vertex_map = msh.topology.index_map(0)
    to_vertices = msh.topology.connectivity(fdim, 0)

    def global_vertices(names: list[str]) -> np.ndarray:
        facets = np.concatenate([body.facets(n) for n in names] or [np.zeros(0, dtype=np.int32)])
        local = np.unique(np.concatenate([to_vertices.links(f) for f in facets] or [np.zeros(0, dtype=np.int32)]))
        return np.unique(np.concatenate(comm.allgather(vertex_map.local_to_global(local.astype(np.int32)))))

    held_vertices = global_vertices(held)
    for key, name in contact_keys(scene):
        free = np.setdiff1d(global_vertices([name]), held_vertices)
        if free.size == 0:
            raise MeshFileError(f"{key} = {name!r}: every node of the group is held by boundary.fixed or "
                                f"boundary.displacement ({', '.join(held)}) in {_file(scene)}: none can move "
                                "towards the plane")


def check_strain(scene: Scene, body: BodyMesh) -> float:
    """The loads' elastic strain estimated on the file's geometry, each at most MAX_ELASTIC_STRAIN (small-strain
    elasticity), as the built-in kinds check theirs before meshing: a normal force P over the contact surface's
    length L, ``P / (L E/(1-nu^2))`` (the mean pressure's strain: the peak's is higher); an approach d (and each
    further zone's) over the body's depth along the plane's normal; a prescribed ``boundary.displacement`` over the
    body's size. A mesh written in metres for a scene in millimetres is 1000 times too small and fails them by far:
    the message says so. Collective. Returns the contact surface's extent (mm: the diagonal of its nodes' box).

    Raises:
        MeshFileError: naming the key, the value, the estimate and the file's size.
    """
    from .. import _dolfinx as dfx  # lazy: DOLFINx (the schema imports this module)

    msh, comm = body.mesh, body.mesh.comm
    gdim, fdim = msh.geometry.dim, msh.topology.dim - 1
    x = msh.geometry.x[:, :gdim]
    material, loading, eps = scene.material, scene.loading, MAX_ELASTIC_STRAIN

    def box(points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The corners of the box of every rank's ``points``."""
        parts = comm.allgather((points.min(axis=0), points.max(axis=0)) if points.size else None)
        parts = [part for part in parts if part is not None]
        return np.min([low for low, _ in parts], axis=0), np.max([high for _, high in parts], axis=0)

    low, high = box(x)
    size = float(np.linalg.norm(high - low))
    owned = _owned(msh, body.facets(scene.contact.surface))
    nodes = dfx.entities_to_geometry(msh, fdim, owned) if owned.size else np.zeros((0, 2), dtype=np.int32)
    length = comm.allreduce(float(np.linalg.norm(x[nodes[:, 1]] - x[nodes[:, 0]], axis=1).sum()) if owned.size
                            else 0.0)
    surface_low, surface_high = box(x[nodes.ravel()])
    extent = float(np.linalg.norm(surface_high - surface_low))
    spans = " x ".join(f"{v:.4g}" for v in high - low)
    path = _file(scene)

    def refuse(key: str, value: float, bound: float, unit: str, estimate: str, strain: float) -> None:
        metres = strain / 1000.0 <= eps   # the mesh 1000 times larger (mm, not m) would pass
        hint = (f"; the body spans {spans} mm: is the mesh in metres? The scene's units are N, mm and MPa (scale the "
                "mesh by 1000)" if metres else f"; the body spans {spans} mm (the scene's units are N, mm and MPa)")
        raise MeshFileError(f"{key} = {value:g} is out of range on the mesh of {path}; allowed: <= {bound:.4g} {unit}: "
                            f"the estimated strain {estimate} = {strain:.3g} must stay <= {eps:g} (small-strain "
                            f"elasticity){hint}")

    E_plane = material.E / (1 - material.nu**2)
    normal = np.asarray(scene.contact.plane_normal, dtype=float)
    force, approach = loading.normal_force, loading.normal_displacement
    if force is not None and force / (length * E_plane) > eps:
        refuse("loading.normal_force", force, eps * length * E_plane, "N/mm",
               f"P / (contact surface {scene.contact.surface!r} length {length:.4g} mm x E/(1-nu^2) = "
               f"{E_plane:.4g} MPa)", force / (length * E_plane))
    depths = [("loading.normal_displacement", approach, normal)]
    depths += [(f"contact[{i}].approach", zone.approach, np.asarray(zone.plane_normal, dtype=float))
               for i, zone in enumerate(scene.zones, start=1)]
    for key, value, direction in depths:
        if value is None or value == 0:
            continue
        along = x @ (direction / np.linalg.norm(direction))
        top = comm.allreduce(float(along.max()) if along.size else -np.inf, op=MPI.MAX)
        depth = top - comm.allreduce(float(along.min()) if along.size else np.inf, op=MPI.MIN)
        if abs(value) / depth > eps:
            refuse(key, value, eps * depth, "mm", f"|d| / (the body's depth {depth:.4g} mm along the plane's normal)",
                   abs(value) / depth)
    for name, vector in scene.boundary.displacement.items():
        magnitude = float(np.linalg.norm(vector))
        if magnitude / size > eps:
            refuse(f"boundary.displacement.{name}", magnitude, eps * size, "mm (the vector's length)",
                   f"|u| / (the body's size {size:.4g} mm, its box's diagonal)", magnitude / size)
    return extent


def msh_node_count(path: str | Path) -> int | None:
    """The node count in a gmsh ``.msh`` file's ``$Nodes`` header (formats 2 and 4, ASCII or binary), without
    reading the nodes; None if the file has no readable header."""
    try:
        with open(path, "rb") as stream:
            head = stream.read(1 << 16)
            header = re.search(rb"\$MeshFormat\s+(\S+)\s+(\d)\s+(\d+)", head)
            if header is None:
                return None
            version, binary, size_t = float(header.group(1)), header.group(2) == b"1", int(header.group(3))
            buffer, offset = head, 0
            while b"$Nodes" not in buffer:  # the $Entities section may be long: read on in chunks
                chunk = stream.read(1 << 20)
                if not chunk:
                    return None
                offset += len(buffer) - 16
                buffer = buffer[-16:] + chunk
            start = buffer.index(b"$Nodes") + len(b"$Nodes")
            stream.seek(offset + start)
            rest = stream.read(4096)
    except OSError:
        return None
    rest = rest.lstrip(b"\r\n")
    if version >= 4 and binary:
        return int(np.frombuffer(rest[:4 * size_t], dtype=f"<u{size_t}")[1])
    fields = rest.split()
    try:
        return int(fields[1] if version >= 4 else fields[0])
    except (IndexError, ValueError):
        return None


def xdmf_node_count(path: str | Path) -> int | None:
    """The node count of an XDMF file's 2D mesh grid (its Geometry's dimensions), None if not found."""
    try:
        root = ET.parse(path).getroot()
    except (OSError, ET.ParseError):
        return None
    for grid in root.iter("Grid"):
        if grid.find("Attribute") is not None:
            continue  # a grid of markers
        item = grid.find("Geometry/DataItem")
        if item is not None and item.get("Dimensions"):
            return int(item.get("Dimensions").split()[0])
    return None
