"""The half-cylinder (plane strain): the lower half of a disk of ``geometry.radius`` resting on y = 0, on a rigid
plane or on an elastic flat of the same material (the paper's Example 2: the ``hertz``, ``cylinder-flat`` and
``mccoll`` scenes).

Its mesh (:func:`dolfinx_fretting.meshes.half_cylinder`, :func:`~dolfinx_fretting.meshes.cylinder_on_flat`):
gmsh, ``contact_mesh_size`` along the refined arc and in a structured sector under it (half-width
``contact_half_width``, by default R/15), graded to ``coarse_mesh_size`` (R/10) far away. Its Hertz reference is
the line contact (``analytic.hertz_line_contact``).
"""

from __future__ import annotations

import math
import time
from typing import Any

import numpy as np
from mpi4py import MPI

from .. import meshes
from ..analytic import hertz_line_contact
from ..scene_models import (SceneModel, contact_surface, elastic_flat, elastic_model, pairing_text, rigid_plane,
                            two_body_cells)
from .base import (MAX_CONTACT_ELEMENTS, MAX_ELASTIC_STRAIN, MIN_ELASTIC_STRAIN, Geometry, MeshSize, Refinement,
                   check_no_boundary, check_plane_strain, coarser_contact_mesh, finer_contact_mesh, load_range_error,
                   mesher_default, range_error)
from .gmsh_nodes import ON_BOUNDARY, nodes_along, segment_distance, unstructured_nodes

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
                              f">= pi x radius / {MAX_CONTACT_ELEMENTS} = "
                              f"{math.pi * radius / MAX_CONTACT_ELEMENTS:.3g} mm")

    def flat_size(self, geometry: GeometrySettings) -> tuple[float, float]:
        """Width and height (mm) of the elastic flat under the cylinder (``flat_width``, ``flat_height``)."""
        return geometry.flat_width, geometry.flat_height

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
        """The Hertz strain ``sqrt(P / (pi R E*))`` of a normal force, ``sqrt(d / (2R))`` of an approach d (at most
        MAX_ELASTIC_STRAIN) and ``d / (2R)`` (at least MIN_ELASTIC_STRAIN)."""
        radius, loading, material = scene.geometry.radius, scene.loading, scene.material
        E_star, low, high = scene.contact_modulus, MIN_ELASTIC_STRAIN, MAX_ELASTIC_STRAIN
        force, approach = loading.normal_force, loading.normal_displacement
        if force is not None and not low <= math.sqrt(force / (math.pi * radius * E_star)) <= high:
            raise load_range_error("loading.normal_force", force, low**2 * math.pi * radius * E_star,
                                   high**2 * math.pi * radius * E_star, "N/mm",
                                   f"the Hertz strain sqrt(P / (pi R E*)) with geometry.radius = {radius:g} mm and "
                                   f"material.E = {material.E:g} MPa (E* = {E_star:.4g} MPa)")
        if approach is not None and not (low <= approach / (2 * radius) and math.sqrt(approach / (2 * radius)) <= high):
            raise load_range_error("loading.normal_displacement", approach, 2 * low * radius, 2 * high**2 * radius,
                                   "mm", f"the strain of an approach d on geometry.radius = {radius:g} mm (d / (2R) at "
                                   "least, sqrt(d / (2R)) at most)")

    def preset_values(self, scene: Scene, preset: dict[str, float]) -> dict[str, Any]:
        """Under a normal force, ``contact_mesh_size``: the Hertz half-width (against the rigid plane or the
        elastic flat) over the preset's ``contact_elements_per_half_width``; none under an approach."""
        if scene.loading.normal_force is None:
            return {}
        return {"geometry.contact_mesh_size":
                float(f"{self.contact_size(scene) / preset['contact_elements_per_half_width']:.3g}")}

    def finer(self, scene: Scene) -> list[str]:
        """``contact_mesh_size`` half the :meth:`element_size`."""
        return finer_contact_mesh(self.element_size(scene))

    def coarser(self, scene: Scene, factor: int) -> Refinement:
        """``contact_mesh_size`` ``factor`` times the :meth:`element_size`."""
        return coarser_contact_mesh(self.element_size(scene), factor)

    def contact_size(self, scene: Scene) -> float:
        """Hertz's half-width a under a normal force; under an approach d, the geometric ``sqrt(2 R d)``."""
        radius, loading = scene.geometry.radius, scene.loading
        if loading.normal_force is not None:
            return float(hertz_line_contact(loading.normal_force, radius, scene.contact_modulus)[0])
        return float(np.sqrt(2.0 * radius * loading.normal_displacement))

    def element_size(self, scene: Scene) -> float:
        """``geometry.contact_mesh_size``."""
        return scene.geometry.contact_mesh_size

    def mesh_size(self, scene: Scene) -> MeshSize:
        """The structured sectors under the contact counted exactly (quadrilaterals), the rest of the cylinder (and
        of the flat) by gmsh's node density under the size field (:mod:`~dolfinx_fretting.geometries.gmsh_nodes`),
        from the meshers' own sizing rules (``meshes._cylinder_sizes``, ``meshes._refined_depth``); the candidates:
        the arc's nodes within the window."""
        geometry = scene.geometry
        R, h, a, H = meshes._cylinder_sizes(geometry.radius, geometry.contact_mesh_size, geometry.refined_half_width,
                                            geometry.coarse_mesh_size)
        t = meshes._refined_depth(R, h, a)
        growth = mesher_default(meshes.half_cylinder, "growth")
        cell = "quadrilateral" if geometry.quadrilateral else "triangle"
        theta = math.asin(a / R)
        # The structured sectors (meshes._half_cylinder_geometry, _flat_geometry): equal segments along the refined
        # arc (each half R theta long) and the flat's refined segment (each half a long), layers through t.
        n_arc, n_flat, n_layers = max(1, round(R * theta / h)), max(1, round(a / h)), max(1, round(t / h))
        structured = geometry.quadrilateral

        def body(regions, boundary, r_max: float, n_along: int) -> float:
            exact = (2 * n_along + 1) * (n_layers + 1) if structured else 0
            return exact + unstructured_nodes(regions, boundary, r_max, h, H, growth, cell,
                                              include_sector=not structured)

        nodes = body(lambda x, y: _cylinder_regions(x, y, R, a, t), _cylinder_boundary(R), math.sqrt(2) * R, n_arc)
        if scene.contact.obstacle == "elastic_flat":
            width, height = self.flat_size(geometry)
            nodes += body(lambda x, y: _flat_regions(x, y, width, height, a, t), _flat_boundary(width, height),
                          math.hypot(width / 2, height), n_flat)
        window, _ = self.candidate_window(scene, geometry.refined_half_width, geometry.contact_mesh_size)
        # Candidates: the arc's nodes within the window of the lowest one (measured along the plane).
        k = np.arange(n_arc + 1)
        within = R * np.sin(k * theta / n_arc) <= window * (1 + 1e-12)
        contacts = 2 * int(within.sum()) - 1
        if window > a:  # beyond the refined arc the spacing grows with the distance from it
            length = R * (math.asin(min(window, R) / R) - theta)
            contacts += 2 * int(nodes_along(length, h, H, growth))
        coarse = geometry.coarse_mesh_size if geometry.coarse_mesh_size is not None else geometry.radius / 10
        drivers = {"geometry.contact_mesh_size": geometry.contact_mesh_size,
                   "geometry.contact_half_width": geometry.refined_half_width, "geometry.coarse_mesh_size": coarse}
        return MeshSize(int(round(nodes)), contacts, False, "gmsh", cell, drivers)

    def build(self, scene: Scene, comm: MPI.Comm) -> SceneModel:
        """A half-cylinder on a rigid plane, or on an elastic flat (two bodies, one mesh)."""
        geometry, contact = scene.geometry, scene.contact
        two_body = contact.obstacle == "elastic_flat"
        zone, h = geometry.refined_half_width, geometry.contact_mesh_size
        start = time.perf_counter()
        mesher = meshes.cylinder_on_flat if two_body else meshes.half_cylinder
        flat = self.flat_size(geometry) if two_body else ()
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
            text = f", each paired with the elastic flat ({pairing_text(obstacle, 2)})"
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


# The regions of the gmsh size field (pure NumPy) -----------------------------------------------------------------
def _cylinder_regions(x, y, R: float, a: float, t: float):
    """Inside the half-cylinder (lowest point at the origin), inside its refined sector, distance to the sector.
    Points on a boundary (within :data:`~dolfinx_fretting.geometries.gmsh_nodes.ON_BOUNDARY` R) are inside it."""
    rho = np.hypot(x, R - y)
    phi = np.arctan2(x, R - y)  # from the downward vertical, positive towards +x
    theta = math.asin(a / R)
    tol = ON_BOUNDARY * R
    inside = (rho <= R + tol) & (y <= R + tol)
    sector = inside & (rho >= R - t - tol) & (np.abs(phi) <= theta + ON_BOUNDARY)
    side = np.sign(phi) * theta
    ux, uy = np.sin(side), -np.cos(side)
    d_side = segment_distance(x, y, (R - t) * ux, R + (R - t) * uy, R * ux, R + R * uy)
    d = np.where(np.abs(phi) <= theta, np.maximum(R - t - rho, 0.0), d_side)
    return inside, sector, d


def _flat_regions(x, y, width: float, height: float, a: float, t: float):
    """Inside the flat (top at y = 0, centred), inside its refined sector, distance to the sector. Points on a
    boundary (within :data:`~dolfinx_fretting.geometries.gmsh_nodes.ON_BOUNDARY` of the width) are inside it."""
    tol = ON_BOUNDARY * width
    inside = (np.abs(x) <= width / 2 + tol) & (y <= tol) & (y >= -height - tol)
    sector = inside & (np.abs(x) <= a + tol) & (y >= -t - tol)
    d = np.hypot(np.maximum(np.abs(x) - a, 0.0), np.maximum(-t - y, 0.0))
    return inside, sector, d


def _cylinder_boundary(R: float, n: int = 20000):
    """Points and lengths of the half-cylinder's boundary (the arc and the top face)."""
    phi = (np.arange(n) + 0.5) * np.pi / n - np.pi / 2
    x = np.concatenate([R * np.sin(phi), (np.arange(n) + 0.5) * 2 * R / n - R])
    y = np.concatenate([R - R * np.cos(phi), np.full(n, R)])
    return x, y, np.concatenate([np.full(n, np.pi * R / n), np.full(n, 2 * R / n)])


def _flat_boundary(width: float, height: float, n: int = 20000):
    """Points and lengths of the flat's boundary (top, bottom, sides)."""
    u = (np.arange(n) + 0.5) / n
    x = np.concatenate([(u - 0.5) * width, (u - 0.5) * width, np.full(n, -width / 2), np.full(n, width / 2)])
    y = np.concatenate([np.zeros(n), np.full(n, -height), -u * height, -u * height])
    return x, y, np.concatenate([np.full(2 * n, width / n), np.full(2 * n, height / n)])
