"""The geometry kinds of the scenes: one module per ``geometry.kind``, one object per module, one registry.

Issue 25: a kind's branches were spread over the schema (``scenes``: its keys, what it accepts of the other
sections, its load checks, its preset values), the size estimate (``sizes``), the study (``study``) and the
builders (``scene_models``). Each kind is now one object with the protocol of
:class:`~dolfinx_fretting.geometries.base.Geometry`:

* schema checks, which the validators of :mod:`dolfinx_fretting.scenes` call with the section or the scene:
  ``refuse_own_keys`` (its keys, set under another kind), ``check_geometry`` (its ``[geometry]`` keys and sizes),
  ``check_scene`` (what it accepts of the obstacle, the loads, the plane, the surface, the window, ``[boundary]``),
  ``check_loads`` (the normal load's elastic strain on its body);
* ``preset_values``: its part of a numerics preset (``solver.preset``);
* ``contact_size``: its Hertz reference (line contact, sphere or none), the expected contact size before any mesh.

:data:`GEOMETRIES` maps each ``geometry.kind`` to its object; the modules that used to branch look the kind up
instead. A new geometry kind is one new module here (a :class:`~dolfinx_fretting.geometries.base.Geometry` with
the hooks it needs) and one line in :data:`GEOMETRIES`, plus its name in the schema's ``Literal``
(``tests/test_geometries.py`` checks that the two agree).

Why objects and not functions per concern: the laws of issue 25 (:mod:`dolfinx_fretting.laws`) are objects with a
small protocol, and a kind is the same idea; a base class gives the defaults (no hook: nothing to check, no
preset, no Hertz contact), so a kind writes only what it has.

Imports point down: the schema (``scenes``) imports this package; nothing here imports the schema, whose classes
are only named in annotations (see :mod:`~dolfinx_fretting.geometries.base`).
"""

from __future__ import annotations

from .base import Geometry
from .half_cylinder import HalfCylinder
from .mesh_file import MeshFile
from .rectangle import Rectangle
from .sphere import Sphere

__all__ = ["GEOMETRIES", "Geometry"]

#: Every geometry kind by its ``geometry.kind``: a new kind is one module and one line here.
GEOMETRIES: dict[str, Geometry] = {
    "half_cylinder": HalfCylinder(),
    "rectangle": Rectangle(),
    "sphere": Sphere(),
    "file": MeshFile(),
}
