"""The bridge-type fretting-fatigue rig (plane strain): a cylindrical pad of ``geometry.radius`` pressed on a
specimen of ``geometry.specimen_thickness`` and ``geometry.specimen_length``, under a normal load P held, a
tangential load Q(t) and a bulk stress sigma_B(t) on the specimen's end (Hills & Nowell, *Mechanics of Fretting
Fatigue*, 1994; the ``pad-specimen`` scene).

The rig has two pads, one on each face of the specimen, loaded alike: the model holds the upper half of the
specimen (a roller on its mid-plane, y = -thickness/2) and one pad, the half-cylinder of the ``half_cylinder`` kind
on its elastic flat (:func:`dolfinx_fretting.meshes.cylinder_on_flat`, both bodies deformable, one material). The
pad's top is clamped (the bridge holds it); the specimen's left end is held along x (a roller: the grip), its right
end carries the bulk stress, the named load :data:`~dolfinx_fretting.scene_models.BULK_STRESS_LOAD` (factor: sigma_B
in MPa, positive in tension).
P and Q are the contact's total forces (force control through the relative rigid motion of the two bodies, as on
the elastic flat), so the specimen's grip reacts Q + sigma_B x thickness / 2.

Everything but the specimen (mesh sizes, Hertz reference, size estimate, study refinements) is the half-cylinder's.
"""

from __future__ import annotations

import time

import numpy as np
from mpi4py import MPI

from .. import meshes
from ..scene_models import (BULK_STRESS_LOAD, SceneModel, contact_surface, elastic_flat, elastic_model, pairing_text,
                            rigid_plane, roller, two_body_cells)
from .base import (MAX_ELASTIC_STRAIN, MIN_ELASTIC_STRAIN, MeshSize, check_no_boundary, check_plane_strain,
                   load_range_error, range_error)
from .half_cylinder import HalfCylinder

__all__ = ["PadSpecimen"]

_KIND = "pad_specimen"


class PadSpecimen(HalfCylinder):
    """``geometry.kind = "pad_specimen"``."""

    #: ``[fatigue]`` evaluates the specimen (the master flat), where fretting-fatigue cracks start.
    fatigue_body = "master"

    def refuse_own_keys(self, geometry: GeometrySettings) -> None:
        """``specimen_thickness`` and ``specimen_length`` are the rig's."""
        for key in ("specimen_thickness", "specimen_length"):
            if key in geometry.model_fields_set:
                raise range_error(f"geometry.{key}", getattr(geometry, key), f"unset unless geometry.kind = '{_KIND}'")

    def refuse_own_scene_keys(self, scene: Scene) -> None:
        """``loading.bulk_stress`` and ``loading.bulk_phase`` are the rig's."""
        for key in ("bulk_stress", "bulk_phase"):
            value = getattr(scene.loading, key)
            if value is not None:
                raise range_error(f"loading.{key}", value, f"unset unless geometry.kind = '{_KIND}' (the "
                                  "fretting-fatigue rig's specimen carries the bulk stress)")

    def check_geometry(self, geometry: GeometrySettings) -> None:
        """The half-cylinder's checks of the pad; the specimen's size is its own keys, not the flat's."""
        super().check_geometry(geometry)
        for key in ("flat_width", "flat_height"):
            if key in geometry.model_fields_set:
                raise range_error(f"geometry.{key}", getattr(geometry, key), f"unset with geometry.kind = '{_KIND}' "
                                  "(the specimen is geometry.specimen_length x geometry.specimen_thickness)")
        refined, h = geometry.refined_half_width, geometry.contact_mesh_size
        if geometry.specimen_length <= 2 * refined:
            raise range_error("geometry.specimen_length", geometry.specimen_length,
                              f"> 2 x the refined half-width {refined:g} mm")
        depth = min(max(refined / 4, 2 * h), geometry.radius / 2)
        if geometry.specimen_thickness / 2 <= depth:
            raise range_error("geometry.specimen_thickness", geometry.specimen_thickness,
                              f"> 2 x the refined depth {depth:g} mm (the model holds half the thickness)")

    def flat_size(self, geometry: GeometrySettings) -> tuple[float, float]:
        """The modelled half of the specimen: its length and half its thickness (mm)."""
        return geometry.specimen_length, geometry.specimen_thickness / 2

    def check_scene(self, scene: Scene) -> None:
        """Two deformable bodies (``contact.obstacle = "elastic_flat"``), no ``[boundary]``, no face pressure, a window
        within the radius, a 2D plane; a phase lag only with a cyclic bulk stress."""
        contact, loading = scene.contact, scene.loading
        if contact.obstacle != "elastic_flat":
            raise range_error("contact.obstacle", contact.obstacle, f"'elastic_flat' with geometry.kind = '{_KIND}' "
                              "(the pad and the specimen are both deformable)")
        check_no_boundary(scene)
        if loading.tangential_kind == "pressure":
            raise range_error("loading.tangential_pressure", loading.tangential_pressure,
                              f"unset with geometry.kind = '{_KIND}' (the specimen's end carries loading.bulk_stress; "
                              "rub the pad by loading.tangential_force or loading.tangential_displacement)")
        window = contact.candidate_half_width
        if window is not None and window > scene.geometry.radius:
            raise range_error("contact.candidate_half_width", window,
                              f"0 < candidate_half_width <= geometry.radius = {scene.geometry.radius} mm")
        check_plane_strain(scene)
        if loading.bulk_phase is not None and loading.bulk_stress is None:
            raise range_error("loading.bulk_phase", loading.bulk_phase, "unset without loading.bulk_stress")
        if loading.bulk_phase is not None and loading.cycles == 0:
            raise range_error("loading.bulk_phase", loading.bulk_phase, "unset with loading.cycles = 0 (a monotonic "
                              "load brings Q and the bulk stress up together)")

    def check_loads(self, scene: Scene) -> None:
        """The half-cylinder's Hertz strain of the normal load; the bulk stress's strain ``|sigma_B| / E`` 0 or within
        [MIN_ELASTIC_STRAIN, MAX_ELASTIC_STRAIN]."""
        super().check_loads(scene)
        stress, E = scene.loading.bulk_stress, scene.material.E
        if stress is not None and stress != 0 and not MIN_ELASTIC_STRAIN <= abs(stress) / E <= MAX_ELASTIC_STRAIN:
            raise load_range_error("loading.bulk_stress", stress, MIN_ELASTIC_STRAIN * E, MAX_ELASTIC_STRAIN * E,
                                   "MPa (either sign, or 0)", f"|sigma_B| / E with material.E = {E:g} MPa")

    def mesh_size(self, scene: Scene) -> MeshSize:
        """The half-cylinder's estimate on the elastic flat, with the specimen's keys as drivers."""
        size = super().mesh_size(scene)
        geometry = scene.geometry
        size.drivers.update({"geometry.specimen_length": geometry.specimen_length,
                             "geometry.specimen_thickness": geometry.specimen_thickness})
        return size

    def build(self, scene: Scene, comm: MPI.Comm) -> SceneModel:
        """The pad on the half specimen: pad top clamped, mid-plane and left end on rollers, bulk stress on the right
        end."""
        import ufl  # lazy: DOLFINx and UFL stay out of the schema's imports (see scene_models)
        from dolfinx import mesh as dmesh

        geometry, contact = scene.geometry, scene.contact
        zone, h = geometry.refined_half_width, geometry.contact_mesh_size
        length, half_thickness = self.flat_size(geometry)
        start = time.perf_counter()
        body = meshes.cylinder_on_flat(comm, geometry.radius, length, half_thickness, contact_mesh_size=h,
                                       contact_half_width=zone, coarse_mesh_size=geometry.coarse_mesh_size,
                                       quadrilateral=geometry.quadrilateral)
        mesh_s = time.perf_counter() - start
        V, form, von_mises, bcs, loads = elastic_model(scene, body, ["top"])
        msh = V.mesh
        fdim = msh.topology.dim - 1
        # The grip: the specimen's left end (the pad's arc never reaches y < 0, so y <= 0 keeps to the specimen).
        tol = 1e-9 * length
        left = dmesh.locate_entities_boundary(msh, fdim, lambda x: (np.abs(x[0] + length / 2) <= tol)
                                              & (x[1] <= tol))
        bcs += [roller(V, body.facets("flat_bottom"), 1), roller(V, left, 0)]
        # sigma_B on the right end: a unit traction +n on the specimen's sides where x > 0 (the right end alone).
        ds = ufl.Measure("ds", domain=msh, subdomain_data=body.facet_tags)
        right = ufl.conditional(ufl.gt(ufl.SpatialCoordinate(msh)[0], 0.0), 1.0, 0.0)
        loads[BULK_STRESS_LOAD] = right * ufl.dot(ufl.FacetNormal(msh), ufl.TestFunction(V)) * \
            ds(body.tags["flat_sides"])
        plane = rigid_plane(scene)
        window, automatic = self.candidate_window(scene, zone, h)
        display_cells, elastic_cells = two_body_cells(scene, body, "cylinder")
        obstacle = elastic_flat(scene, body, plane, zone, h)
        text = (f", each paired with the specimen ({pairing_text(obstacle, 2)}); "
                "specimen: half its thickness, mid-plane and left end on rollers, bulk stress on its right end")
        return SceneModel(body=body, V=V, form=form, bcs=bcs, surface=contact_surface(scene, body),
                          obstacle=obstacle, loads=loads, element_size=h,
                          window=window, window_limit=zone, window_automatic=automatic, window_edges_matter=True,
                          elastic_cells=elastic_cells, display_cells=display_cells,
                          hertz=(geometry.radius, scene.contact_modulus,
                                 "two identical elastic bodies: E* = E/(2(1-nu^2))"),
                          small_sliding=contact.sliding == "small", contact_text=text, von_mises=von_mises,
                          timings={"mesh_s": mesh_s})

