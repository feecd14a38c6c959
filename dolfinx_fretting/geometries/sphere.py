"""The sphere (3D): a ball's cap of ``geometry.radius``, its lowest point at the origin, on a rigid plane or on an
elastic flat of the same material, sliding along x (the ``sphere-flat`` scene).

Its mesh (:func:`dolfinx_fretting.meshes_3d.sphere_on_flat`): structured hexahedra, cubes of edge h under the
contact graded away from it, sized from the Hertz contact radius a (h = a/10 unless ``contact_mesh_size`` is set;
from ``GRADED_FROM`` elements across a the layers under the contact faces grow with depth, ``DEPTH_GRADING``);
by default half of it (and of the flat) about the plane y = 0, with a roller there. Its Hertz reference is the
sphere's (``analytic.hertz_sphere``).

The uniform zone of cubes (where the candidate window may grow) is sized from the largest contact radius the run
expects: Hertz's a, or the radius the sphere wears to over the scene's cycles (:meth:`Sphere.worn_contact_radius`:
Archard's worn volume bounded from the stroke, ``analytic.worn_sphere_contact_radius``), whichever is larger;
``geometry.contact_half_width`` sets it by hand. The size estimate (:meth:`Sphere.mesh_size`) and the build use the
same :meth:`Sphere.mesh_options`.
"""

from __future__ import annotations

import math
import time
from typing import Any

import numpy as np
from mpi4py import MPI

from .. import meshes_3d
from ..analytic import (hertz_sphere, mindlin_deresiewicz_energy, mindlin_shear_modulus, worn_sphere_contact_radius,
                        worn_sphere_volume)
from ..scene_models import (SceneModel, contact_surface, elastic_flat, elastic_model, pairing_text, rigid_plane, roller,
                            two_body_cells)
from .base import (MAX_ELASTIC_STRAIN, MIN_ELASTIC_STRAIN, Geometry, MeshSize, Refinement, check_no_boundary,
                   coarser_contact_mesh, finer_contact_mesh, load_range_error, mesher_default, range_error)

__all__ = ["Sphere"]

#: Keys of the 2D geometries a sphere does not use (its mesh is sized from the expected contact radius).
NOT_FOR_SPHERE = ("coarse_mesh_size", "width", "height", "nx", "ny", "quadrilateral", "flat_width", "flat_height")
#: The uniform zone's half-width over the largest contact radius the run expects (Sphere.worn_contact_radius):
#: the mesher's default over Hertz's a. Measured on ``sphere-flat`` (a/4 cubes): the window's edge at 1.02 times
#: the loaded area's equivalent radius already carries load (cycle 4769 of 10^4 on the 1.5 a zone), so the
#: margin must exceed about one element; 1.5 leaves 50 % for the estimate's error (0.5 % measured at 4768 cycles,
#: analytic.worn_sphere_volume) and for shapes the uniform-pressure model does not describe (partial slip).
ZONE_OVER_CONTACT = 1.5
#: The bodies' lateral half-size, cap height and flat depth over the uniform zone's half-width, at least: 3, the
#: mesher's default 9 a over its 1.5 a zone (a cap 9 a high is within 0.05 % of a large body on Hertz's peak
#: pressure, 4.5 a +0.25 %: ../shared/notes/3d-contact.md), so a zone grown for wear keeps the body as deep in
#: zone widths as Hertz's.
EXTENT_OVER_ZONE = 3.0
#: Elements across Hertz's contact radius a of the default mesh (h = a / ELEMENTS_PER_RADIUS unless
#: ``geometry.contact_mesh_size`` is set): the resolution a tribologist reads a contact map at (issue 26).
ELEMENTS_PER_RADIUS = 10
#: From this many elements across a (a/h, the given or default h) the bodies are depth-graded
#: (:func:`~dolfinx_fretting.meshes_3d.sphere_on_flat`'s ``depth_growth``, ``coarsening``, ``field_cell``): the same
#: contact face as the cubes h deep down to depth a, fewer dofs under it (100 cycles at a/h = 10: 69 372 dofs
#: against 128 592). Below it the cubes as before: the coarser meshes the validation tests and earlier measurements
#: were made on (a/h = 2 to 8, tests/test_sphere_scene.py) stay as measured, and the saving is smaller there (14 %
#: at a/h = 8, benchmarks/results/contacts_3d.md).
GRADED_FROM = 9.0
#: The depth grading used from ``GRADED_FROM``: layers growing by 1.5 from h at the face, at most a/4 thick down to
#: depth a (Hertz's peak +0.35 / +0.64 % at a/h = 8 / 12 against the cubes' +0.06 / +0.07 %,
#: benchmarks/results/contacts_3d.md), one lateral 3:1 coarsening (two would round the zone up to 9 cubes: 520
#: contacts instead of 370 for 100 cycles; benchmarks/results/sphere_resolution.md).
DEPTH_GRADING = {"depth_growth": 1.5, "coarsening": 1, "field_cell": 0.25}


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
                             "hexahedra is sized from the expected contact radius: geometry.radius, "
                             "geometry.contact_mesh_size, geometry.contact_half_width, geometry.half_model)")
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
        E_star, low, high = scene.contact_modulus, MIN_ELASTIC_STRAIN, MAX_ELASTIC_STRAIN
        force, approach = loading.normal_force, loading.normal_displacement
        if force is not None and not low <= (6 * force / (math.pi**3 * radius**2 * E_star)) ** (1 / 3) <= high:
            scale = math.pi**3 * radius**2 * E_star / 6
            raise load_range_error("loading.normal_force", force, low**3 * scale, high**3 * scale, "N",
                                   f"the Hertz strain p0/E* = (6 P / (pi^3 R^2 E*))^(1/3) with geometry.radius = "
                                   f"{radius:g} mm and material.E = {material.E:g} MPa (E* = {E_star:.4g} MPa)")
        if approach is not None and not (low <= approach / radius and math.sqrt(approach / radius) <= high):
            raise load_range_error("loading.normal_displacement", approach, low * radius, high**2 * radius, "mm",
                                   f"the strain of an approach d on geometry.radius = {radius:g} mm (d / R at least, "
                                   "sqrt(d / R) at most)")
        self._check_zone(scene)

    def _check_zone(self, scene: Scene) -> None:
        """The uniform zone holds the unworn contact and a whole element, and the mesh around it
        (``EXTENT_OVER_ZONE`` zones wide) stays on the sphere: the cap's corner ``sqrt(2)`` times its half-size
        from the axis is inside the radius."""
        geometry = scene.geometry
        a, h = self.contact_size(scene), self.element_size(scene)
        zone = self.zone_half_width(scene)
        given = "contact_half_width" in geometry.model_fields_set
        if given and not max(a, h) <= zone:
            raise range_error("geometry.contact_half_width", zone,
                              f">= {max(a, h):.4g} mm: the sphere's uniform zone holds the Hertz contact radius a = "
                              f"{a:.4g} mm and at least one contact element (h = {h:.4g} mm)")
        largest = geometry.radius / (math.sqrt(2.0) * EXTENT_OVER_ZONE) * (1 - 1e-9)
        if zone * (1 + 1e-9) < largest:
            return
        if given:
            raise range_error("geometry.contact_half_width", zone,
                              f"< {largest:.4g} mm: the mesh around the uniform zone is {EXTENT_OVER_ZONE:g} zones "
                              f"wide and must stay on the sphere (geometry.radius = {geometry.radius:g} mm)")
        cycles, volume = scene.loading.cycles, self.worn_volume_bound(scene)
        most = math.floor(cycles * self.worn_volume_at(scene, largest / ZONE_OVER_CONTACT) / volume)
        raise range_error("loading.cycles", cycles,
                          f"<= {most} with these loads and wear.k: the sphere wears to a contact radius of "
                          f"{self.worn_contact_radius(scene):.4g} mm over {cycles} cycles (worn volume <= "
                          f"{volume:.3g} mm^3), and the mesh sized for it ({ZONE_OVER_CONTACT:g} x that radius, "
                          f"{EXTENT_OVER_ZONE:g} times wider around) would not fit on the sphere of geometry.radius "
                          f"= {geometry.radius:g} mm; or set geometry.contact_half_width below {largest:.4g} mm and "
                          "the run stops when the scar reaches its edge")

    def preset_values(self, scene: Scene, preset: dict[str, float]) -> dict[str, Any]:
        """Under a normal force, ``contact_mesh_size``: a quarter of the preset's elements per contact radius
        (balanced: a/h = 4, the default before ``ELEMENTS_PER_RADIUS``; measured on Hertz: the peak pressure within
        0.2 % from a/h = 3, tests/test_sphere.py); none under an approach."""
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
        the contact radius a (:meth:`contact_size`) over ``ELEMENTS_PER_RADIUS``; at most a."""
        geometry = scene.geometry
        a = self.contact_size(scene)
        h = geometry.contact_mesh_size if "contact_mesh_size" in geometry.model_fields_set else a / ELEMENTS_PER_RADIUS
        return min(h, a)

    def model_fraction(self, scene: Scene) -> float:
        """0.5 for a half model (``geometry.half_model``), else 1."""
        return 0.5 if scene.geometry.half_model else 1.0

    def worn_volume_bound(self, scene: Scene) -> float:
        """An upper bound of the volume (mm^3, the wear gap's, the whole contact) worn over the scene's cycles.

        Archard's wear gap grows by ``k p |slip|`` (k: ``wear.k``, or ``k_slave + k_master``, times
        ``wear.acceleration``), so the volume worn in a cycle is k times the normal force times the slip distance
        where it slides. Under a stroke ``+-delta`` (``loading.tangential_displacement``) no point slides more than
        ``4 delta`` a cycle: ``V <= 4 k P delta N`` for N cycles (measured on ``sphere-flat``: the dissipated energy
        is 89-90 % of ``4 mu P delta``, the rest taken by the contact's elastic compliance before it slips). Under a
        tangential force ``+-Q`` (partial slip, ``|Q| < mu P``) the slip is the Mindlin-Deresiewicz loop's: the
        volume is ``k / mu`` times its energy (``analytic.mindlin_deresiewicz_energy``; the wear-energy identity of
        tests/test_sphere.py). Under an approach d the force is Hertz's of ``a = sqrt(R d)`` (an overestimate). 0
        without wear or cycles.
        """
        wear, loading, contact = scene.wear, scene.loading, scene.contact
        if (wear.law == "none" or loading.cycles == 0 or loading.tangential_kind == "none"
                or loading.tangential_amplitude == 0):
            return 0.0
        k = wear.rate_coefficient(contact.mu) * wear.acceleration  # energy law: alpha mu
        P, a = self._normal_force(scene), self.contact_size(scene)
        if loading.tangential_kind == "displacement":
            return 4.0 * k * P * abs(loading.tangential_amplitude) * loading.cycles
        m = scene.material
        two_body = contact.obstacle == "elastic_flat"
        G_star = mindlin_shear_modulus(m.E, m.nu, m.E if two_body else None, m.nu if two_body else None)
        energy = mindlin_deresiewicz_energy(abs(loading.tangential_amplitude), contact.mu, P, a, G_star)
        return k / contact.mu * energy * loading.cycles

    def _normal_force(self, scene: Scene) -> float:
        """The normal force (N): the scene's, or Hertz's ``4 E* a^3 / (3 R)`` of an approach's
        :meth:`contact_size`."""
        if scene.loading.normal_force is not None:
            return float(scene.loading.normal_force)
        return 4.0 * scene.contact_modulus * self.contact_size(scene) ** 3 / (3.0 * scene.geometry.radius)

    def worn_contact_radius(self, scene: Scene) -> float:
        """The contact radius (mm) the sphere wears to over the scene's cycles, at least :meth:`contact_size`:
        ``analytic.worn_sphere_contact_radius`` of :meth:`worn_volume_bound` (the worn sphere's flat scar under a
        uniform pressure, with the surfaces' elastic sag). Under an approach d at most ``sqrt(2 R d)``, where the
        undeformed bodies overlap: wear only opens the gap and the contact's pressure only pushes the surfaces
        apart."""
        radius, a = scene.geometry.radius, self.contact_size(scene)
        volume = self.worn_volume_bound(scene)
        if volume == 0.0:
            return a
        worn = worn_sphere_contact_radius(volume, self._normal_force(scene), radius, scene.contact_modulus)
        if scene.loading.normal_displacement is not None:
            worn = min(worn, math.sqrt(2.0 * radius * scene.loading.normal_displacement))
        return max(a, worn)

    def worn_volume_at(self, scene: Scene, c: float) -> float:
        """The worn volume (mm^3) at which the worn contact reaches a radius ``c`` (inverse of
        :meth:`worn_contact_radius` past Hertz's radius)."""
        return worn_sphere_volume(c, self._normal_force(scene), scene.geometry.radius, scene.contact_modulus)

    def zone_half_width(self, scene: Scene) -> float:
        """The uniform zone's half-width (mm) before its rounding to whole cubes: ``geometry.contact_half_width``
        if the scene sets it, else ``ZONE_OVER_CONTACT`` times the larger of Hertz's contact radius and the
        :meth:`worn_contact_radius`."""
        geometry = scene.geometry
        if "contact_half_width" in geometry.model_fields_set:
            return float(geometry.contact_half_width)
        return ZONE_OVER_CONTACT * self.worn_contact_radius(scene)

    def candidate_window(self, scene: Scene, zone: float, h: float) -> tuple[float, bool]:
        """The base rule (``1.5 a + 3 h``, at most the uniform ``zone``), with the :meth:`worn_contact_radius` in
        place of ``1.5 a`` where the cycles wear the contact wider: a window that grows during the run rebuilds W
        on 1.5 times as many rings of contacts (2.25 times the candidates), so it starts where the run expects the
        contact to end, three elements on (the bound overestimates the worn radius: 0.329 mm for 0.317 mm
        measured after 10^4 cycles)."""
        window, automatic = super().candidate_window(scene, zone, h)
        if not automatic:
            return window, automatic
        expected = max(1.5 * self.contact_size(scene), self.worn_contact_radius(scene))
        return float(min(zone, expected + 3.0 * h)), True

    def mesh_options(self, scene: Scene) -> dict[str, float]:
        """The keyword arguments ``zone``, ``depth_zone``, ``extent``, ``growth`` and the depth grading's
        ``depth_growth``, ``coarsening``, ``field_cell`` of :func:`~dolfinx_fretting.meshes_3d.sphere_on_flat`
        (lengths over Hertz's a): the mesher's defaults, with the uniform zone of :meth:`zone_half_width`, the bodies
        at least ``EXTENT_OVER_ZONE`` zones wide (the defaults' 1.5 and 9 a while Hertz's radius is the largest
        expected) and, from ``GRADED_FROM`` elements across a, ``DEPTH_GRADING`` (below it the mesher's default: no
        depth grading). The size estimate and the build both read them."""
        options = {name: mesher_default(meshes_3d.sphere_on_flat, name)
                   for name in ("zone", "depth_zone", "extent", "growth", "depth_growth", "coarsening", "field_cell")}
        a = self.contact_size(scene)
        zone = self.zone_half_width(scene) / a
        options.update(zone=zone, extent=max(options["extent"], EXTENT_OVER_ZONE * zone))
        if a / self.element_size(scene) >= GRADED_FROM * (1 - 1e-9):
            options.update(DEPTH_GRADING)
        return options

    def sizing(self, scene: Scene, zone: float) -> str:
        """How the uniform zone of half-width ``zone`` (mm, rounded to whole cubes) was sized, in words (the
        size estimate's ``sizing``: the run's log and ``summary.json``)."""
        geometry, loading = scene.geometry, scene.loading
        a, worn = self.contact_size(scene), self.worn_contact_radius(scene)
        text = f"uniform contact zone {zone:.4g} mm"
        if "contact_half_width" in geometry.model_fields_set:
            text += " (geometry.contact_half_width)"
        else:
            text += f" = {ZONE_OVER_CONTACT:g} x the largest contact radius expected, {worn:.4g} mm"
        volume = self.worn_volume_bound(scene)
        if volume > 0:
            cycles = loading.cycles * scene.wear.acceleration
            text += (f"; Archard's worn radius for {cycles:g} cycles {worn:.4g} mm (worn volume <= {volume:.3g} mm^3), "
                     f"Hertz's {a:.4g} mm")
        else:
            text += f"; Hertz's contact radius {a:.4g} mm (no wear)"
        return text

    def mesh_size(self, scene: Scene) -> MeshSize:
        """Exact: the nodes of :func:`~dolfinx_fretting.meshes_3d.sphere_on_flat` (``grid_node_count`` of
        :meth:`mesh_options`, as the build's); the candidates: the contact face's grid points within the window."""
        geometry = scene.geometry
        a, h = self.contact_size(scene), self.element_size(scene)
        options = self.mesh_options(scene)
        two_body = scene.contact.obstacle == "elastic_flat"
        nodes = meshes_3d.grid_node_count(a, h, **options, half=geometry.half_model, flat=two_body)
        x, y, _ = meshes_3d._grid_axes(a, h, **options, half=geometry.half_model)
        # the uniform zone's half-width, as sphere_on_flat_grid rounds it
        levels = options["coarsening"] if options["depth_growth"] is not None else 0
        zone = meshes_3d.uniform_zone_steps(a, h, options["zone"], levels) * h
        window, _ = self.candidate_window(scene, zone, h)
        X, Y = np.meshgrid(x, y, indexing="ij")
        contacts = int(np.count_nonzero(np.hypot(X, Y) <= window * (1 + 1e-12)))
        given = "contact_mesh_size" in geometry.model_fields_set
        drivers = {"geometry.contact_mesh_size": geometry.contact_mesh_size if given else
                   f"a/{ELEMENTS_PER_RADIUS:g} (default)",
                   "geometry.radius": geometry.radius, "geometry.half_model": geometry.half_model}
        if "contact_half_width" in geometry.model_fields_set:
            drivers["geometry.contact_half_width"] = geometry.contact_half_width
        elif self.worn_contact_radius(scene) > a:  # the zone grown for the wear the cycles make drives the size too
            drivers["loading.cycles"] = scene.loading.cycles
        return MeshSize(int(nodes), contacts, True, "hexahedra", "hexahedron", drivers,
                        sizing=self.sizing(scene, zone))

    def build(self, scene: Scene, comm: MPI.Comm) -> SceneModel:
        """A sphere's cap on an elastic flat of the same material (two bodies, one mesh) or on a rigid plane: a half
        model about y = 0 by default, a roller there (u_y = 0 on both bodies' faces). ``hertz`` is None: the
        summary's Hertz reference is the line contact's, not the sphere's."""
        geometry, contact = scene.geometry, scene.contact
        two_body = contact.obstacle == "elastic_flat"
        a, h = self.contact_size(scene), self.element_size(scene)
        start = time.perf_counter()
        body = meshes_3d.sphere_on_flat(comm, geometry.radius, a, h, **self.mesh_options(scene),
                                        half=geometry.half_model, flat=two_body)
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
            text = f", each paired with the elastic flat's faces ({pairing_text(obstacle, 3)})"
        else:
            obstacle, display_cells, elastic_cells = plane, None, None
            text = ", against a rigid plane"
        text += ", half model (roller on y = 0)" if geometry.half_model else ""
        text += f"; {self.sizing(scene, zone)}"
        return SceneModel(body=body, V=V, form=form, bcs=bcs, surface=contact_surface(scene, body), obstacle=obstacle,
                          loads=loads, element_size=h, window=window, window_limit=zone, window_automatic=automatic,
                          window_edges_matter=True, elastic_cells=elastic_cells, display_cells=display_cells,
                          hertz=None, small_sliding=two_body and contact.sliding == "small", contact_text=text,
                          von_mises=von_mises, timings={"mesh_s": mesh_s}, model_fraction=self.model_fraction(scene),
                          held_tangential=(2,) if geometry.half_model else ())
