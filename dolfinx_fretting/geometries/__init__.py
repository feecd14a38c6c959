"""The geometry kinds of the scenes: one module per ``geometry.kind``, one object per module, one registry.

Issue 25: a kind's branches were spread over the schema (``scenes``: its keys, what it accepts of the other
sections, its load checks, its preset values), the size estimate (``sizes``), the study (``study``) and the
builders (``scene_models``). Each kind is now one object with the protocol of
:class:`~dolfinx_fretting.geometries.base.Geometry`:

* schema checks, which the validators of :mod:`dolfinx_fretting.scenes` call with the section or the scene:
  ``refuse_own_keys`` (its keys, set under another kind), ``check_geometry`` (its ``[geometry]`` keys and sizes),
  ``check_scene`` (what it accepts of the obstacle, the loads, the plane, the surface, the window, ``[boundary]``),
  ``check_loads`` (the normal load's elastic strain on its body);
* ``preset_values``: its part of a numerics preset (``solver.preset``); ``finer`` and ``coarser``: the keys that
  refine its mesh in the speed-vs-accuracy study (``dolfinx_fretting.study``);
* ``contact_size``: its Hertz reference (line contact, sphere or none), the expected contact size before any mesh;
  ``element_size`` and ``model_fraction`` (a half model);
* ``mesh_size``: its part of the size estimate (:func:`dolfinx_fretting.sizes.estimate`): nodes, contacts, the keys
  that set them, counted without meshing;
* ``build``: its mesh and model (:class:`~dolfinx_fretting.scene_models.SceneModel`), written with the parts of
  :mod:`dolfinx_fretting.scene_models`; :func:`build_scene_model` looks the kind up.

:data:`GEOMETRIES` maps each ``geometry.kind`` to its object; the modules that used to branch look the kind up
instead. A new geometry kind is one new module here (a :class:`~dolfinx_fretting.geometries.base.Geometry` with
the hooks it needs) and one line in :data:`GEOMETRIES`, plus its name in the schema's ``Literal``
(``tests/test_geometries.py`` checks that the two agree).

Why objects and not functions per concern: the laws of issue 25 (:mod:`dolfinx_fretting.laws`) are objects with a
small protocol, and a kind is the same idea; a base class gives the defaults (no hook: nothing to check, no
preset, no mesh refinement, no Hertz contact), so a kind writes only what it has. Why an explicit dict and not
discovery (entry points, subclass registration): the registry is read in one place and checked against the
schema by a test. The obstacles (rigid plane, elastic flat) can follow the same pattern: one module each and a
registry.

Order of the checks: the schema asks every other kind to refuse its own keys, then the scene's kind checks its
section; a scene's checks run the kind's first, then those that hold for any kind (finite sliding, the elastic
flat's plane). A scene with two errors is told the first of them in that order.

Imports point down: the schema (``scenes``) imports this package, this package imports the parts of the model
(``scene_models``), the meshers (``meshes``, ``meshes_3d``) and the closed forms (``analytic``); nothing here
imports the schema, whose classes are only named in annotations (see :mod:`~dolfinx_fretting.geometries.base`).
None of these modules loads DOLFINx when imported (their functions do), so a scene is validated and sized without it.
"""

from __future__ import annotations

from mpi4py import MPI

from ..scene_models import SceneModel
from .base import Geometry
from .half_cylinder import HalfCylinder
from .mesh_file import MeshFile
from .pad_specimen import PadSpecimen
from .rectangle import Rectangle
from .sphere import Sphere

__all__ = ["GEOMETRIES", "Geometry", "build_scene_model"]

#: Every geometry kind by its ``geometry.kind``: a new kind is one module and one line here.
GEOMETRIES: dict[str, Geometry] = {
    "half_cylinder": HalfCylinder(),
    "rectangle": Rectangle(),
    "sphere": Sphere(),
    "file": MeshFile(),
    "pad_specimen": PadSpecimen(),
}


def build_scene_model(scene: Scene, comm: MPI.Comm = MPI.COMM_WORLD, *,
                      applies_model_fraction: bool = False) -> SceneModel:
    """Mesh the scene's geometry and write its model: the ``build`` of its kind. Collective.

    Args:
        scene: The validated scene.
        comm: Communicator of the mesh.
        applies_model_fraction: The caller prescribes :attr:`SceneModel.model_fraction
            <dolfinx_fretting.scene_models.SceneModel.model_fraction>` times the scene's forces and divides the
            totals it reports by it. A model of a fraction of the bodies (a half model) is refused to a caller that
            does not: its forces would be the whole contact's on part of it.

    Raises:
        ValueError: a name of the scene is not in the mesh (the message lists the names it holds), or a model of a
            fraction of the bodies for a caller that does not apply it.
    """
    geometry = GEOMETRIES[scene.geometry.kind]
    fraction = geometry.model_fraction(scene)
    if fraction != 1.0 and not applies_model_fraction:  # (the sphere's half model is the only such model)
        raise ValueError(f"geometry.half_model = true: this caller does not scale the scene's forces to the half "
                         f"model (SceneModel.model_fraction = {fraction:g}) yet; run the whole sphere with "
                         "geometry.half_model = false, or build the model with applies_model_fraction=True")
    return geometry.build(scene, comm)
