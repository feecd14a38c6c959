"""What a geometry kind is: the protocol :class:`Geometry` every kind implements (with the defaults of a kind
that needs no hook), and what the kinds' checks share with the scene schema (the limits, the message of a value
out of range, the checks every built-in kind makes).

The scene classes (``Scene``, ``GeometrySettings`` of :mod:`dolfinx_fretting.scenes`) are named in the
annotations here and in the kinds' modules but not imported: the schema imports this package to call the
checks from its validators, and an import back, even one for type checkers only, would close a circle.
"""

from __future__ import annotations

import inspect
from abc import ABCMeta, abstractmethod
from dataclasses import dataclass, field
from typing import Any, Callable

from mpi4py import MPI

from ..scene_models import SceneModel

__all__ = ["Geometry", "MeshSize", "Refinement", "range_error", "check_no_boundary", "check_plane_strain",
           "mesher_default", "finer_contact_mesh", "coarser_contact_mesh", "MAX_ELASTIC_STRAIN", "MIN_ELASTIC_STRAIN",
           "load_range_error",
           "MAX_CONTACT_ELEMENTS", "MAX_CELLS"]

#: Largest elastic strain a load may produce (estimated before any work, each kind's
#: :meth:`Geometry.check_loads`): the model is small-strain linear elasticity; past a few percent its answer is
#: meaningless (and past the elastic limit of any real solid). Estimates: half-cylinder under a normal force P,
#: the Hertz peak p0/E* = sqrt(P / (pi R E*)); under an approach d, sqrt(d / (2R)) (from the geometric
#: half-width sqrt(2Rd), an overestimate); a sphere, (6 P / (pi^3 R^2 E*))^(1/3) or sqrt(d / R); a rectangle,
#: P / (width E') or d / height; a face pressure s, ``|s| / E``.
MAX_ELASTIC_STRAIN = 0.1
#: Smallest elastic strain a load may produce (the same estimates; for an approach d, d over the body's size, the
#: strain of a displacement d across it). A strain of 1e-8 is below any measured elastic strain (strain gauges resolve
#: ~1e-7) and a contact pressure of 1e-8 E (2 kPa on steel); far below it the problem degenerates in double precision
#: (measured on the half-cylinder, R = 6 mm: under a force the load control finds no approach at a Hertz strain of
#: 6e-19, P = 1e-30 N/mm, and the local solver gets non-finite data at P = 1e-200; an approach of 1.7e-17 R gives a
#: force 1 % off and 1.7e-19 R no contact at all: it is lost in the rounding of the node coordinates). 1e-8 leaves six
#: decades between the smallest accepted load and the first measured degeneracy.
MIN_ELASTIC_STRAIN = 1e-8
#: Largest half-cylinder: elements along its refined contact zone (and along its arc at the coarse size). Beyond,
#: the mesh generator and the factorisation run for hours or exhaust memory (a hang, not a run): 206k dofs
#: factorise in ~2 s here, and the cost grows faster than linearly.
MAX_CONTACT_ELEMENTS = 20_000
#: Largest rectangle, in cells (for the same reason); also the bound of ``geometry.nx`` and ``ny``.
MAX_CELLS = 4_000_000


def range_error(key: str, value: Any, allowed: str) -> ValueError:
    """The schema's message of a value out of range: ``"<key> = <value> is out of range; allowed: <allowed>"``."""
    return ValueError(f"{key} = {value!r} is out of range; allowed: {allowed}")


def load_range_error(key: str, value: float, low: float, high: float, unit: str, estimate: str) -> ValueError:
    """A load whose estimated elastic strain is outside [MIN_ELASTIC_STRAIN, MAX_ELASTIC_STRAIN]: its range
    ``low``..``high`` (``unit``) and the estimate that gives it (``estimate``: the formula with the scene's values)."""
    low_strain, high_strain = MIN_ELASTIC_STRAIN, MAX_ELASTIC_STRAIN
    return range_error(key, value, f"{low:.4g} to {high:.4g} {unit}: {estimate} must stay within "
                                   f"[{low_strain:g}, {high_strain:g}] (below {low_strain:g} the load is degenerate: no "
                                   "measurable strain, its displacements lost in the rounding of the coordinates; "
                                   f"above {high_strain:g} small-strain elasticity fails)")


def check_no_boundary(scene: Scene) -> None:
    """A built-in geometry fixes its own faces: a ``[boundary]`` section is refused."""
    names = scene.boundary.names
    if names:
        raise range_error(names[0][0], names[0][1], "no [boundary] section with a built-in geometry (its faces are "
                          "fixed by the scene); set geometry.kind = 'file'")


def check_plane_strain(scene: Scene) -> None:
    """A two-dimensional (plane-strain) kind takes a rigid plane of two components."""
    normal = scene.contact.plane_normal
    if len(normal) != 2:
        raise range_error("contact.plane_normal", normal, "a 2-vector: the geometries built in are two-dimensional "
                          "(plane strain), but the sphere (geometry.kind = 'sphere')")


def mesher_default(mesher: Callable, name: str) -> Any:
    """The default of a mesher's keyword argument (an estimate counts with the mesher's own defaults)."""
    return inspect.signature(mesher).parameters[name].default


@dataclass(frozen=True)
class MeshSize:
    """What a kind's mesh will hold, counted before meshing: the kind's part of
    :func:`dolfinx_fretting.sizes.estimate` (which adds the memory of the factorisation, W and the rest).

    Attributes:
        nodes: Mesh nodes (both bodies), or None when the kind cannot count them cheaply.
        contacts: Contact candidates, or None.
        exact: The count follows from the mesh's construction (structured); otherwise a model of the mesher.
        mesher: The memory class of the mesh per dof (a key of :data:`dolfinx_fretting.sizes.MESH_BYTES_PER_DOF`).
        cell: The cells' Gauss-point family of an elastic-plastic body: ``"quadrilateral"``, ``"triangle"`` or
            ``"hexahedron"``.
        drivers: The scene keys that set the mesh's size, with their values (for a refusal's message).
        window_default: What an unset ``contact.candidate_half_width`` means, in words.
        notes: What was not counted, and why.
        sizing: How the kind sized its contact zone from the scene, in words ("" if from the scene's keys alone).
    """

    nodes: int | None
    contacts: int | None
    exact: bool
    mesher: str
    cell: str
    drivers: dict[str, Any] = field(default_factory=dict)
    window_default: str = "automatic"
    notes: tuple[str, ...] = ()
    sizing: str = ""


#: A mesh point of the speed-vs-accuracy study: (the swept key, its value as text, the overrides that make it).
Refinement = tuple[str, str, list[str]]


def finer_contact_mesh(h: float) -> list[str]:
    """The study's reference of a kind meshed by ``geometry.contact_mesh_size``: its element size h halved."""
    return [f"geometry.contact_mesh_size={h / 2:.10g}"]


def coarser_contact_mesh(h: float, factor: int) -> Refinement:
    """The study's point of a kind meshed by ``geometry.contact_mesh_size``: ``factor`` times its element size h."""
    value = f"{h * factor:.6g}"
    return "geometry.contact_mesh_size", value, [f"geometry.contact_mesh_size={value}"]


class Geometry(metaclass=ABCMeta):
    """The protocol of a geometry kind: one object per ``geometry.kind`` in
    :data:`dolfinx_fretting.geometries.GEOMETRIES`.

    Schema checks (called by the validators of :mod:`dolfinx_fretting.scenes`; each raises a ``ValueError`` whose
    message names the key): :meth:`refuse_own_keys`, :meth:`refuse_own_scene_keys`, :meth:`check_geometry`, :meth:`check_scene`,
    :meth:`check_loads`. Numerics: :meth:`preset_values` (``solver.preset``), :meth:`finer` and :meth:`coarser`
    (the keys that refine its mesh in a study, ``dolfinx_fretting.study``). Before any mesh:
    :meth:`contact_size` (the Hertz reference), :meth:`element_size`, :meth:`model_fraction`, :meth:`mesh_size`
    (the size estimate). The model:
    :meth:`build`. The defaults are those of a kind without the hook: no checks, no preset, no mesh refinement, no
    Hertz contact, the whole bodies.
    """

    #: The body a scene's ``[fatigue]`` evaluates unless ``fatigue.body`` names one: the contact set's slave (the
    #: body of the contact nodes, the only one against a rigid obstacle); the fretting-fatigue rig's is the master.
    fatigue_body: str = "slave"

    def refuse_own_keys(self, geometry: GeometrySettings) -> None:
        """Refuse the ``[geometry]`` keys only this kind reads, set while another kind is chosen."""

    def refuse_own_scene_keys(self, scene: Scene) -> None:
        """Refuse the keys of the other sections (``[loading]``, ...) only this kind reads, set while another kind is
        chosen."""

    def check_geometry(self, geometry: GeometrySettings) -> None:
        """Check the ``[geometry]`` section of this kind alone: which keys it takes, the sizes against the body."""

    def check_scene(self, scene: Scene) -> None:
        """Check what this kind accepts of the other sections: the obstacle, the loads, the rigid plane, the contact
        surface and window, a ``[boundary]`` section."""

    def check_loads(self, scene: Scene) -> None:
        """Check that the normal load's estimated elastic strain on this body is at most
        :data:`~dolfinx_fretting.geometries.base.MAX_ELASTIC_STRAIN` (none: the body is not known before meshing)."""

    def preset_values(self, scene: Scene, preset: dict[str, float]) -> dict[str, Any]:
        """The ``geometry.*`` values of a numerics preset (an entry of :data:`dolfinx_fretting.scenes.PRESETS`)."""
        return {}

    def finer(self, scene: Scene) -> list[str]:
        """The overrides that halve the contact elements: the study's reference (none: the mesh is kept)."""
        return []

    def coarser(self, scene: Scene, factor: int) -> Refinement | None:
        """The study's point with contact elements ``factor`` times larger (None: no mesh point)."""
        return None

    def contact_size(self, scene: Scene) -> float | None:
        """The Hertz reference of the kind: the expected contact half-width (2D) or radius (3D) in mm before any
        mesh, Hertz's under a normal force, the geometric one under an approach; None without a curved body."""
        return None

    def element_size(self, scene: Scene) -> float | None:
        """The contact element size (mm) the mesh will have, if known before meshing."""
        return None

    def model_fraction(self, scene: Scene) -> float:
        """The fraction of the bodies the model holds (:attr:`SceneModel.model_fraction
        <dolfinx_fretting.scene_models.SceneModel.model_fraction>`)."""
        return 1.0

    @abstractmethod
    def mesh_size(self, scene: Scene) -> MeshSize:
        """Nodes, contacts and the keys that set them, counted without meshing (pure: no DOLFINx)."""

    @abstractmethod
    def build(self, scene: Scene, comm: MPI.Comm) -> SceneModel:
        """Mesh (or read) the body and write its model with the parts of :mod:`dolfinx_fretting.scene_models`.
        Collective."""

    def candidate_window(self, scene: Scene, zone: float, h: float) -> tuple[float, bool]:
        """The initial candidate half-width (mm) of a kind with a :meth:`contact_size`, and whether it is automatic.

        Automatic for elastic bodies without ``contact.candidate_half_width`` (an elastic-plastic body cannot grow
        its window, and plasticity widens the contact beyond the elastic estimate, so it keeps the refined zone):
        ``1.5 a + 3 h`` with a the :meth:`contact_size`, at most the refined ``zone``. Finite sliding cannot grow its
        window either (its surface compliance is built for one): the zone, or the given width if wider.

        Args:
            scene: The scene.
            zone: Half-width of the mesh's refined (uniform) contact zone (mm).
            h: Contact element size (mm).
        """
        given = scene.contact.candidate_half_width
        if scene.contact.sliding == "finite":  # the surface compliance is built for one window: the whole zone
            return float(max(zone, given or 0.0)), False
        automatic = given is None and scene.material.model == "elastic"
        if automatic:
            return float(min(zone, 1.5 * self.contact_size(scene) + 3 * h)), True
        return (given if given is not None else zone), False
