"""The half-cylinder (plane strain): the lower half of a disk of ``geometry.radius`` resting on y = 0, on a rigid
plane or on an elastic flat of the same material (the paper's Example 2: the ``hertz``, ``cylinder-flat`` and
``mccoll`` scenes).

Its mesh (:func:`dolfinx_fretting.meshes.half_cylinder`, :func:`~dolfinx_fretting.meshes.cylinder_on_flat`):
gmsh, ``contact_mesh_size`` along the refined arc and in a structured sector under it (half-width
``contact_half_width``, by default R/15), graded to ``coarse_mesh_size`` (R/10) far away. Its Hertz reference is
the line contact (:func:`dolfinx_fretting.analytic.hertz_line_contact`).
"""

from __future__ import annotations

import math
import time
from typing import Any

import numpy as np
from mpi4py import MPI

from .. import meshes
from ..analytic import hertz_line_contact
from ..scene_models import (PAIRING, SceneModel, contact_surface, elastic_flat, elastic_model, rigid_plane,
                            two_body_cells)
from .base import MAX_CONTACT_ELEMENTS, MAX_ELASTIC_STRAIN, Geometry, check_no_boundary, check_plane_strain, range_error

__all__ = ["HalfCylinder"]


class HalfCylinder(Geometry):
    """``geometry.kind = "half_cylinder"``."""

    def check_geometry(self, geometry: GeometrySettings) -> None:
        """The refined zone, the coarse size and the element counts against the radius."""
        radius, h = geometry.radius, geometry.contact_mesh_size
        half_width, coarse = geometry.contact_half_width, geometry.coarse_mesh_size
        if h >= radius:
            raise range_error("geometry.contact_mesh_size", h, f"0 < contact_mesh_size < geometry.radius = {radius} mm")
        if half_width is not None and half_width >= radius:
            raise range_error("geometry.contact_half_width", half_width,
                              f"0 < contact_half_width < geometry.radius = {radius} mm")
        if half_width is not None and half_width < h:
            raise range_error("geometry.contact_half_width", half_width,
                              f"contact_mesh_size = {h} <= contact_half_width < radius = {radius} mm")
        if coarse is not None and coarse >= radius:
            raise range_error("geometry.coarse_mesh_size", coarse,
                              f"0 < coarse_mesh_size < geometry.radius = {radius} mm")
        if coarse is not None and coarse < h:
            raise range_error("geometry.coarse_mesh_size", coarse,
                              f"geometry.contact_mesh_size = {h} <= coarse_mesh_size < radius = {radius} mm")
        # The mesh's size: elements along the refined zone and along the arc (a hang otherwise, not a run).
        refined = geometry.refined_half_width
        if 2 * refined / h > MAX_CONTACT_ELEMENTS:
            raise range_error("geometry.contact_mesh_size", h,
                              f">= 2 x refined half-width {refined:g} mm / {MAX_CONTACT_ELEMENTS} "
                              f"= {2 * refined / MAX_CONTACT_ELEMENTS:.3g} mm (at most "
                              f"{MAX_CONTACT_ELEMENTS} elements along the refined contact zone)")
        coarse = coarse if coarse is not None else radius / 10
        if math.pi * radius / coarse > MAX_CONTACT_ELEMENTS:
            raise range_error("geometry.coarse_mesh_size", coarse,
                              f">= pi x radius / {MAX_CONTACT_ELEMENTS} = {math.pi * radius / MAX_CONTACT_ELEMENTS:.3g} mm")

    def check_scene(self, scene: Scene) -> None:
        """No ``[boundary]``, no face pressure (its faces are the fixed top and the contact surface), a window within
        the radius, a 2D plane; on the elastic flat, a flat wider and deeper than the refined zone."""
        geometry, contact, loading = scene.geometry, scene.contact, scene.loading
        check_no_boundary(scene)
        if loading.tangential_kind == "pressure":
            # a half-cylinder's faces are its fixed top and the contact surface: neither may carry a face pressure
            raise range_error("loading.tangential_pressure", loading.tangential_pressure,
                              "unset with geometry.kind = 'half_cylinder' (its faces are the fixed top and the "
                              "contact surface; rub it by loading.tangential_displacement or "
                              "loading.tangential_force)")
        window = contact.candidate_half_width
        if window is not None and window > geometry.radius:
            raise range_error("contact.candidate_half_width", window,
                              f"0 < candidate_half_width <= geometry.radius = {geometry.radius} mm")
        check_plane_strain(scene)
        if contact.obstacle == "elastic_flat":
            refined = geometry.refined_half_width
            if geometry.flat_width <= 2 * refined:
                raise range_error("geometry.flat_width", geometry.flat_width,
                                  f"> 2 x the refined half-width {refined} mm")
            depth = min(max(refined / 4, 2 * geometry.contact_mesh_size), geometry.radius / 2)
            if geometry.flat_height <= depth:
                raise range_error("geometry.flat_height", geometry.flat_height, f"> the refined depth {depth:g} mm")

    def check_loads(self, scene: Scene) -> None:
        """The Hertz strain ``sqrt(P / (pi R E*))`` of a normal force, ``sqrt(d / (2R))`` of an approach."""
        radius, loading, material = scene.geometry.radius, scene.loading, scene.material
        E_star, eps = scene.contact_modulus, MAX_ELASTIC_STRAIN
        force, approach = loading.normal_force, loading.normal_displacement
        if force is not None and math.sqrt(force / (math.pi * radius * E_star)) > eps:
            force_max = eps**2 * math.pi * radius * E_star
            raise range_error("loading.normal_force", force,
                              f"<= {force_max:.4g} N/mm: the Hertz strain sqrt(P / (pi R E*)) with geometry.radius "
                              f"= {radius:g} mm and material.E = {material.E:g} MPa (E* = {E_star:.4g} MPa) must stay "
                              f"<= {eps:g} (small-strain elasticity)")
        if approach is not None and approach > 2 * eps**2 * radius:
            raise range_error("loading.normal_displacement", approach,
                              f"<= {2 * eps**2 * radius:.4g} mm: the strain sqrt(d / (2R)) of an approach d "
                              f"on geometry.radius = {radius:g} mm must stay <= {eps:g} (small-strain "
                              "elasticity)")

    def preset_values(self, scene: Scene, preset: dict[str, float]) -> dict[str, Any]:
        """Under a normal force, ``contact_mesh_size``: the Hertz half-width (against the rigid plane or the
        elastic flat) over the preset's ``contact_elements_per_half_width``; none under an approach."""
        if scene.loading.normal_force is None:
            return {}
        return {"geometry.contact_mesh_size":
                float(f"{self.contact_size(scene) / preset['contact_elements_per_half_width']:.3g}")}

    def contact_size(self, scene: Scene) -> float:
        """Hertz's half-width a under a normal force; under an approach d, the geometric ``sqrt(2 R d)``."""
        radius, loading = scene.geometry.radius, scene.loading
        if loading.normal_force is not None:
            return float(hertz_line_contact(loading.normal_force, radius, scene.contact_modulus)[0])
        return float(np.sqrt(2.0 * radius * loading.normal_displacement))

    def element_size(self, scene: Scene) -> float:
        """``geometry.contact_mesh_size``."""
        return scene.geometry.contact_mesh_size

    def build(self, scene: Scene, comm: MPI.Comm) -> SceneModel:
        """A half-cylinder on a rigid plane, or on an elastic flat (two bodies, one mesh)."""
        geometry, contact = scene.geometry, scene.contact
        two_body = contact.obstacle == "elastic_flat"
        zone, h = geometry.refined_half_width, geometry.contact_mesh_size
        start = time.perf_counter()
        mesher = meshes.cylinder_on_flat if two_body else meshes.half_cylinder
        flat = (geometry.flat_width, geometry.flat_height) if two_body else ()
        body = mesher(comm, geometry.radius, *flat, contact_mesh_size=h, contact_half_width=zone,
                      coarse_mesh_size=geometry.coarse_mesh_size, quadrilateral=geometry.quadrilateral)
        mesh_s = time.perf_counter() - start
        V, form, von_mises, bcs, loads = elastic_model(scene, body, ["top", "flat_bottom"] if two_body else ["top"])
        plane = rigid_plane(scene)
        window, automatic = self.candidate_window(scene, zone, h)
        if two_body:
            obstacle = elastic_flat(scene, body, plane, zone, h)
            display_cells, elastic_cells = two_body_cells(scene, body, "cylinder")
            label = "two identical elastic bodies: E* = E/(2(1-nu^2))"
            text = f", each paired with a point of the elastic flat (node-to-segment, {PAIRING[contact.sliding]})"
        else:
            obstacle, display_cells, elastic_cells = plane, None, None
            label = "rigid plane, frictionless: E* = E/(1-nu^2)"
            text = ", against a rigid plane"
        return SceneModel(body=body, V=V, form=form, bcs=bcs, surface=contact_surface(scene, body), obstacle=obstacle,
                          loads=loads, element_size=h, window=window, window_limit=zone, window_automatic=automatic,
                          window_edges_matter=True, elastic_cells=elastic_cells, display_cells=display_cells,
                          hertz=(geometry.radius, scene.contact_modulus, label),
                          small_sliding=two_body and contact.sliding == "small", contact_text=text,
                          von_mises=von_mises, timings={"mesh_s": mesh_s})
