"""The rectangle (plane strain): a block of ``geometry.width`` by ``height``, its top fixed, pressed on a rigid plane
by one of its faces (the paper's Example 1: the ``stromberg-block`` scene).

Its mesh (:func:`dolfinx_fretting.meshes.rectangle`): structured, ``nx`` by ``ny`` cells, quadrilaterals or
triangles. No Hertz reference: the contact is the whole face.
"""

from __future__ import annotations

import time
from typing import Any

from mpi4py import MPI

from .. import meshes
from ..scene_models import SceneModel, contact_surface, elastic_model, rigid_plane
from .base import (MAX_CELLS, MAX_ELASTIC_STRAIN, MIN_ELASTIC_STRAIN, Geometry, MeshSize, Refinement, check_no_boundary,
                   check_plane_strain, load_range_error, range_error)

__all__ = ["Rectangle"]

#: The faces of the rectangle (:data:`dolfinx_fretting.meshes.RECTANGLE_TAGS`).
FACES = ("bottom", "right", "top", "left")


class Rectangle(Geometry):
    """``geometry.kind = "rectangle"``."""

    def check_geometry(self, geometry: GeometrySettings) -> None:
        """At most :data:`~dolfinx_fretting.geometries.base.MAX_CELLS` cells."""
        if geometry.nx * geometry.ny > MAX_CELLS:
            raise range_error("geometry.nx", geometry.nx, f"geometry.nx x geometry.ny <= {MAX_CELLS} cells "
                              f"(ny = {geometry.ny})")

    def check_scene(self, scene: Scene) -> None:
        """No ``[boundary]``; a face pressure on a face that is neither the fixed top nor the contact surface; a 2D
        plane; a rigid plane only (the elastic flat needs a curved body on it)."""
        contact, loading = scene.contact, scene.loading
        check_no_boundary(scene)
        if loading.tangential_kind == "pressure":
            free = [face for face in FACES if face not in ("top", contact.surface)]
            if loading.pressure_face not in free:
                raise range_error("loading.pressure_face", loading.pressure_face,
                                  f"{', '.join(free)} (a face of the rectangle that is neither the fixed top nor "
                                  f"the contact surface {contact.surface!r})")
        check_plane_strain(scene)
        if contact.obstacle == "elastic_flat":
            raise range_error("contact.obstacle", contact.obstacle,
                              "'rigid_plane' with geometry.kind = 'rectangle' ('elastic_flat' needs a "
                              "half_cylinder or a sphere on it)")

    def check_loads(self, scene: Scene) -> None:
        """The mean strain ``P / (face length E')`` of a normal force, ``d / depth`` of an approach, on the contact
        face."""
        geometry, contact, loading, material = scene.geometry, scene.contact, scene.loading, scene.material
        if contact.surface not in FACES:
            return
        E_plane, low, high = material.E / (1 - material.nu**2), MIN_ELASTIC_STRAIN, MAX_ELASTIC_STRAIN
        face, depth = ((geometry.width, geometry.height) if contact.surface in ("bottom", "top")
                       else (geometry.height, geometry.width))
        force, approach = loading.normal_force, loading.normal_displacement
        if force is not None and not low <= force / (face * E_plane) <= high:
            raise load_range_error("loading.normal_force", force, low * face * E_plane, high * face * E_plane, "N/mm",
                                   f"the mean strain P / (face length {face:g} mm x E/(1-nu^2) = {E_plane:.4g} MPa)")
        if approach is not None and not low <= approach / depth <= high:
            raise load_range_error("loading.normal_displacement", approach, low * depth, high * depth, "mm",
                                   f"the strain d / ({depth:g} mm, the body's depth under contact.surface = "
                                   f"{contact.surface!r})")

    def preset_values(self, scene: Scene, preset: dict[str, float]) -> dict[str, Any]:
        """``nx``: the preset's ``rectangle_cells``; ``ny`` in proportion to the height."""
        geometry = scene.geometry
        nx = int(preset["rectangle_cells"])
        return {"geometry.nx": nx, "geometry.ny": max(1, round(nx * geometry.height / geometry.width))}

    def finer(self, scene: Scene) -> list[str]:
        """``nx`` and ``ny`` doubled."""
        geometry = scene.geometry
        return [f"geometry.nx={2 * geometry.nx}", f"geometry.ny={2 * geometry.ny}"]

    def coarser(self, scene: Scene, factor: int) -> Refinement:
        """``nx`` and ``ny`` divided by ``factor`` together (at least 1), swept as ``geometry.nx``."""
        geometry = scene.geometry
        nx, ny = max(1, geometry.nx // factor), max(1, geometry.ny // factor)
        return "geometry.nx", f"{nx}", [f"geometry.nx={nx}", f"geometry.ny={ny}"]

    def mesh_size(self, scene: Scene) -> MeshSize:
        """Exact: ``(nx + 1) (ny + 1)`` nodes; the candidates: the contact face's nodes within the window."""
        geometry, contact = scene.geometry, scene.contact
        nodes = (geometry.nx + 1) * (geometry.ny + 1)
        horizontal = contact.surface in ("bottom", "top")
        along = geometry.nx if horizontal else geometry.ny
        step = (geometry.width / geometry.nx) if horizontal else (geometry.height / geometry.ny)
        contacts = along + 1
        if contact.candidate_half_width is not None:
            contacts = min(contacts, 2 * int(contact.candidate_half_width * (1 + 1e-12) / step) + 1)
        cell = "quadrilateral" if geometry.quadrilateral else "triangle"
        drivers = {"geometry.nx": geometry.nx, "geometry.ny": geometry.ny}
        return MeshSize(nodes, contacts, True, "rectangle", cell, drivers, window_default="the whole surface")

    def build(self, scene: Scene, comm: MPI.Comm) -> SceneModel:
        """A block on a rigid plane (the paper's Example 1), its top fixed; the window: the scene's, or the whole
        contact face."""
        geometry = scene.geometry
        start = time.perf_counter()
        body = meshes.rectangle(comm, geometry.width, geometry.height, geometry.nx, geometry.ny,
                                quadrilateral=geometry.quadrilateral)
        mesh_s = time.perf_counter() - start
        V, form, von_mises, bcs, loads = elastic_model(scene, body, ["top"])
        return SceneModel(body=body, V=V, form=form, bcs=bcs, surface=contact_surface(scene, body),
                          obstacle=rigid_plane(scene), loads=loads, element_size=body.contact_mesh_size,
                          window=scene.contact.candidate_half_width, window_limit=None, window_automatic=False,
                          window_edges_matter=False, elastic_cells=None, display_cells=None, hertz=None,
                          small_sliding=False, contact_text=", against a rigid plane", von_mises=von_mises,
                          timings={"mesh_s": mesh_s})
