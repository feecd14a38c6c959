"""A mesh file (``geometry.kind = "file"``, 2D): the user's gmsh ``.msh`` file with physical groups, or a DOLFINx
XDMF file with its facet meshtags, held by the conditions of the ``[boundary]`` section (by the names of its
groups) and pressed on a rigid plane.

Nothing of the body is known before the file is read: no load check, no preset, no Hertz reference, no mesh
refinement in a study; its size estimate counts the nodes in the file's header.
"""

from __future__ import annotations

from .base import Geometry, check_plane_strain, range_error

__all__ = ["MeshFile"]


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
