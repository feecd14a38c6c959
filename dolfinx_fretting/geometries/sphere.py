"""The sphere (3D): a ball's cap of ``geometry.radius``, its lowest point at the origin, on a rigid plane or on an
elastic flat of the same material, sliding along x (the ``sphere-flat`` scene).

Its mesh (:func:`dolfinx_fretting.meshes_3d.sphere_on_flat`): structured hexahedra, cubes of edge h under the
contact graded away from it, sized from the Hertz contact radius a (h = a/4 unless ``contact_mesh_size`` is set);
by default half of it (and of the flat) about the plane y = 0, with a roller there. Its Hertz reference is the
sphere's (``analytic.hertz_sphere``).
"""

from __future__ import annotations

import math
import time
from typing import Any

import numpy as np
from mpi4py import MPI

from .. import meshes_3d
from ..analytic import hertz_sphere
from ..scene_models import (PAIRING, SceneModel, contact_surface, elastic_flat, elastic_model, rigid_plane, roller,
                            two_body_cells)
from .base import (MAX_ELASTIC_STRAIN, Geometry, MeshSize, Refinement, check_no_boundary, coarser_contact_mesh,
                   finer_contact_mesh, mesher_default, range_error)

__all__ = ["Sphere"]

#: Keys of the 2D geometries a sphere does not use (its mesh is sized from the Hertz contact radius).
NOT_FOR_SPHERE = ("contact_half_width", "coarse_mesh_size", "width", "height", "nx", "ny", "quadrilateral",
                  "flat_width", "flat_height")


class Sphere(Geometry):
    """``geometry.kind = "sphere"``."""

    def refuse_own_keys(self, geometry: GeometrySettings) -> None:
        """``half_model`` is the sphere's."""
        if "half_model" in geometry.model_fields_set:
            raise range_error("geometry.half_model", geometry.half_model, "unset unless geometry.kind = 'sphere'")

    def check_geometry(self, geometry: GeometrySettings) -> None:
        """No key of the 2D geometries; cubes finer than R/20 under the contact."""
        unused = [key for key in NOT_FOR_SPHERE if key in geometry.model_fields_set]
        if unused:
            raise ValueError(f"geometry.{unused[0]} is not a key of geometry.kind = 'sphere' (its mesh of "
                             "hexahedra is sized from the Hertz contact radius: geometry.radius, "
                             "geometry.contact_mesh_size, geometry.half_model)")
        if "contact_mesh_size" in geometry.model_fields_set and geometry.contact_mesh_size >= geometry.radius / 20:
            raise range_error("geometry.contact_mesh_size", geometry.contact_mesh_size,
                              f"< geometry.radius / 20 = {geometry.radius / 20:g} mm")

    def check_scene(self, scene: Scene) -> None:
        """No ``[boundary]``; the plane z = 0 under the sphere's lowest point, its normal +z; no face pressure; the
        contact surface is the sphere's face."""
        contact, loading = scene.contact, scene.loading
        check_no_boundary(scene)
        if [float(x) for x in contact.plane_normal] != [0.0, 0.0, 1.0]:
            raise range_error("contact.plane_normal", contact.plane_normal,
                              "[0, 0, 1] with geometry.kind = 'sphere' (the sphere's axis is z, its lowest "
                              "point the origin; it slides along x)")
        if len(contact.plane_point) != 3 or contact.plane_point[2] > 0:
            raise range_error("contact.plane_point", contact.plane_point, "[x, y, z] with z <= 0 (the sphere's "
                              "lowest point is the origin)")
        if loading.tangential_kind == "pressure":
            raise range_error("loading.tangential_pressure", loading.tangential_pressure,
                              "unset with geometry.kind = 'sphere' (rub it by loading.tangential_displacement "
                              "or loading.tangential_force)")
        if contact.surface != "surface":
            raise range_error("contact.surface", contact.surface, "'surface' (the sphere's face) with a sphere")

    def check_loads(self, scene: Scene) -> None:
        """Hertz (Johnson §4.2): the strain ``p0 / E* = (6 P / (pi^3 R^2 E*))^(1/3)`` of a normal force; an
        approach d: ``a = sqrt(R d)``, the strain ``a / R``."""
        radius, loading, material = scene.geometry.radius, scene.loading, scene.material
        E_star, eps = scene.contact_modulus, MAX_ELASTIC_STRAIN
        force, approach = loading.normal_force, loading.normal_displacement
        if force is not None and (6 * force / (math.pi**3 * radius**2 * E_star)) ** (1 / 3) > eps:
            force_max = eps**3 * math.pi**3 * radius**2 * E_star / 6
            raise range_error("loading.normal_force", force,
                              f"<= {force_max:.4g} N: the Hertz strain p0/E* = (6 P / (pi^3 R^2 E*))^(1/3) with "
                              f"geometry.radius = {radius:g} mm and material.E = {material.E:g} MPa (E* = "
                              f"{E_star:.4g} MPa) must stay <= {eps:g} (small-strain elasticity)")
        if approach is not None and math.sqrt(approach / radius) > eps:
            raise range_error("loading.normal_displacement", approach,
                              f"<= {eps**2 * radius:.4g} mm: the strain sqrt(d / R) of an approach d on "
                              f"geometry.radius = {radius:g} mm must stay <= {eps:g} (small-strain elasticity)")

    def preset_values(self, scene: Scene, preset: dict[str, float]) -> dict[str, Any]:
        """Under a normal force, ``contact_mesh_size``: a quarter of the preset's elements per contact radius
        (balanced: a/h = 4, the built-in default; measured on Hertz: the peak pressure within 0.2 % from a/h = 3,
        tests/test_sphere.py); none under an approach."""
        if scene.loading.normal_force is None:
            return {}
        elements = preset["contact_elements_per_half_width"] / 2.5
        return {"geometry.contact_mesh_size": float(f"{self.contact_size(scene) / elements:.3g}")}

    def finer(self, scene: Scene) -> list[str]:
        """``contact_mesh_size`` half the :meth:`element_size`."""
        return finer_contact_mesh(self.element_size(scene))

    def coarser(self, scene: Scene, factor: int) -> Refinement:
        """``contact_mesh_size`` ``factor`` times the :meth:`element_size`."""
        return coarser_contact_mesh(self.element_size(scene), factor)

    def contact_size(self, scene: Scene) -> float:
        """Hertz's contact radius a under a normal force; under an approach d, the geometric ``sqrt(R d)`` (against
        the flat the two bodies share d, and ``sqrt(R d / 2)`` would be right: the mesh's uniform zone, 1.5 a,
        holds either)."""
        radius, loading = scene.geometry.radius, scene.loading
        if loading.normal_force is not None:
            return float(hertz_sphere(loading.normal_force, radius, scene.contact_modulus)[0])
        return float(np.sqrt(radius * loading.normal_displacement))

    def element_size(self, scene: Scene) -> float:
        """The edge h (mm) of the cubes under the contact: ``geometry.contact_mesh_size`` if the scene sets it, else
        a quarter of the contact radius a (:meth:`contact_size`); at most a."""
        geometry = scene.geometry
        a = self.contact_size(scene)
        h = geometry.contact_mesh_size if "contact_mesh_size" in geometry.model_fields_set else a / 4.0
        return min(h, a)

    def model_fraction(self, scene: Scene) -> float:
        """0.5 for a half model (``geometry.half_model``), else 1."""
        return 0.5 if scene.geometry.half_model else 1.0

    def mesh_size(self, scene: Scene) -> MeshSize:
        """Exact: the tensor grid of :func:`~dolfinx_fretting.meshes_3d.sphere_on_flat` (its axes from the mesher's
        own defaults), once per body; the candidates: the grid's points within the window."""
        geometry = scene.geometry
        a, h = self.contact_size(scene), self.element_size(scene)
        options = {name: mesher_default(meshes_3d.sphere_on_flat, name)
                   for name in ("zone", "depth_zone", "extent", "growth")}
        x, y, depth = meshes_3d._grid_axes(a, h, **options, half=geometry.half_model)
        bodies = 2 if scene.contact.obstacle == "elastic_flat" else 1
        nodes = bodies * x.size * y.size * depth.size
        zone = math.ceil(options["zone"] * a / h - 1e-9) * h  # the uniform zone's half-width (sphere_on_flat_grid)
        window, _ = self.candidate_window(scene, zone, h)
        X, Y = np.meshgrid(x, y, indexing="ij")
        contacts = int(np.count_nonzero(np.hypot(X, Y) <= window * (1 + 1e-12)))
        given = "contact_mesh_size" in geometry.model_fields_set
        drivers = {"geometry.contact_mesh_size": geometry.contact_mesh_size if given else "a/4 (default)",
                   "geometry.radius": geometry.radius, "geometry.half_model": geometry.half_model}
        return MeshSize(int(nodes), contacts, True, "hexahedra", "hexahedron", drivers)

    def build(self, scene: Scene, comm: MPI.Comm) -> SceneModel:
        """A sphere's cap on an elastic flat of the same material (two bodies, one mesh) or on a rigid plane: a half
        model about y = 0 by default, a roller there (u_y = 0 on both bodies' faces). ``hertz`` is None: the
        summary's Hertz reference is the line contact's, not the sphere's."""
        geometry, contact = scene.geometry, scene.contact
        two_body = contact.obstacle == "elastic_flat"
        a, h = self.contact_size(scene), self.element_size(scene)
        start = time.perf_counter()
        body = meshes_3d.sphere_on_flat(comm, geometry.radius, a, h, half=geometry.half_model, flat=two_body)
        mesh_s = time.perf_counter() - start
        V, form, von_mises, bcs, loads = elastic_model(scene, body, ["top", "flat_bottom"] if two_body else ["top"])
        if geometry.half_model:  # the symmetry plane y = 0
            faces = np.concatenate([body.facets(name) for name in body.tags if name.endswith("symmetry")])
            bcs.append(roller(V, faces, 1))
        plane = rigid_plane(scene)
        zone = body.contact_half_width
        window, automatic = self.candidate_window(scene, zone, h)
        if two_body:
            obstacle = elastic_flat(scene, body, plane, zone, h)
            display_cells, elastic_cells = two_body_cells(scene, body, "sphere")
            text = (", each paired with the closest point of the elastic flat's faces (node-to-face, "
                    f"{PAIRING[contact.sliding]})")
        else:
            obstacle, display_cells, elastic_cells = plane, None, None
            text = ", against a rigid plane"
        text += ", half model (roller on y = 0)" if geometry.half_model else ""
        return SceneModel(body=body, V=V, form=form, bcs=bcs, surface=contact_surface(scene, body), obstacle=obstacle,
                          loads=loads, element_size=h, window=window, window_limit=zone, window_automatic=automatic,
                          window_edges_matter=True, elastic_cells=elastic_cells, display_cells=display_cells,
                          hertz=None, small_sliding=two_body and contact.sliding == "small", contact_text=text,
                          von_mises=von_mises, timings={"mesh_s": mesh_s}, model_fraction=self.model_fraction(scene),
                          held_tangential=(2,) if geometry.half_model else ())
