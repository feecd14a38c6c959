"""A mesh file (``geometry.kind = "file"``, 2D): the user's gmsh ``.msh`` file with physical groups, or a DOLFINx
XDMF file with its facet meshtags, held by the conditions of the ``[boundary]`` section (by the names of its
groups) and pressed on a rigid plane; with several ``[[contact]]`` tables, one rigid plane per named facet group
(the only kind with several contact surfaces).

Nothing of the body is known before the file is read: no load check, no preset, no Hertz reference, no mesh
refinement in a study; its size estimate counts the nodes in the file's header.
"""

from __future__ import annotations

import re
import time
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
from mpi4py import MPI

from ..meshes import BodyMesh
from ..scene_models import (BOUNDARY_DISPLACEMENT, BOUNDARY_PRESSURE, SceneModel, axis_normal, boundary_pressure,
                            contact_surface, displacement_conditions, elastic_model, facet_length, further_zones,
                            read_msh, read_xdmf, rigid_plane, roller)
from .base import Geometry, MeshSize, check_plane_strain, range_error

__all__ = ["MeshFile", "check_names", "msh_node_count", "xdmf_node_count"]


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
        return SceneModel(body=body, V=V, form=form, bcs=bcs, surface=surface, obstacle=rigid_plane(scene),
                          loads=loads, element_size=h, window=scene.contact.candidate_half_width, window_limit=None,
                          window_automatic=False, window_edges_matter=False, elastic_cells=None, display_cells=None,
                          hertz=None, small_sliding=False, contact_text=", against a rigid plane",
                          von_mises=von_mises, timings={"mesh_s": mesh_s}, prescribed=prescribed,
                          ramped=[name for name in (BOUNDARY_DISPLACEMENT, BOUNDARY_PRESSURE)
                                  if name in prescribed or name in loads],
                          zones=further_zones(scene, body))


def check_names(scene: Scene, facet_names: dict[str, int]) -> None:
    """Every boundary name the scene uses must be a physical group of the file (once it is read, before any work).

    Raises:
        ValueError: naming the key, the name and the file's groups.
    """
    used = [("contact.surface", scene.contact.surface),
            *[(f"contact[{i}].surface", zone.surface) for i, zone in enumerate(scene.zones, start=1)],
            *scene.boundary.names]
    if scene.loading.tangential_kind == "pressure":
        used.append(("loading.pressure_face", scene.loading.pressure_face))
    for key, name in used:
        if name not in facet_names:
            raise ValueError(f"{key} = {name!r} is not a physical group of {scene.geometry.path}; the file's "
                             f"boundary groups: {', '.join(sorted(facet_names)) or 'none'}"
                             + (" (an XDMF file's markers are named by geometry.groups, else by their numbers)"
                                if scene.geometry.path.endswith(".xdmf") else ""))


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
