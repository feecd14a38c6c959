"""The geometry kinds of the scenes (dolfinx_fretting.geometries): the registry against the schema, the import
direction, and what each kind accepts."""

from __future__ import annotations

import subprocess
import sys
import typing
from pathlib import Path

import pytest

from dolfinx_fretting.geometries import GEOMETRIES, Geometry
from dolfinx_fretting.scenes import GeometrySettings, SceneError, load_scene

ROOT = Path(__file__).resolve().parents[1]


def test_the_registry_covers_exactly_the_schema_kinds():
    """One registry entry per value of the schema's ``geometry.kind`` (a kind added to the Literal without its
    module, or a module without its name in the Literal, fails here), each a Geometry of its own module."""
    kinds = typing.get_args(GeometrySettings.model_fields["kind"].annotation)
    assert sorted(GEOMETRIES) == sorted(kinds)
    assert all(isinstance(geometry, Geometry) for geometry in GEOMETRIES.values())
    modules = [type(geometry).__module__ for geometry in GEOMETRIES.values()]
    assert len(set(modules)) == len(modules)
    assert all(module.startswith("dolfinx_fretting.geometries.") for module in modules)


def test_the_api_imports_neither_the_schema_nor_the_geometries():
    """The public API's modules sit below the scene layer: importing them loads no scene schema and no geometry
    kind (a fresh interpreter)."""
    api = ("problem", "operators", "loading", "state", "laws", "contact")
    code = (f"import sys; import {', '.join('dolfinx_fretting.' + name for name in api)}; "
            "print(sorted(m for m in sys.modules if m.startswith(('dolfinx_fretting.scenes', "
            "'dolfinx_fretting.geometries'))))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True, cwd=ROOT)
    assert out.stdout.strip() == "[]"


def test_a_sphere_on_the_elastic_flat_has_a_flat_body():
    """A sphere on the elastic flat may keep the flat plastic (the ball elastic) and give the flat its own wear
    coefficient, as a half-cylinder on it may; the refusals of both are for a rigid plane only."""
    plastic = ["material.model='elastoplastic'", "material.yield_stress=800.0", "material.hardening_modulus=1000.0",
               "material.plastic_body='flat'"]
    per_body = ["wear.k=none", "wear.k_slave=1e-8", "wear.k_master=3e-8"]
    assert load_scene("sphere-flat", plastic).material.plastic_body == "flat"
    assert load_scene("sphere-flat", per_body).wear.slave_share == pytest.approx(0.25)
    rigid = ["contact.obstacle='rigid_plane'"]
    with pytest.raises(SceneError, match=r"material.plastic_body = 'flat' .* 'rigid_plane' \(there is no flat body\)"):
        load_scene("sphere-flat", rigid + plastic)
    with pytest.raises(SceneError, match=r"wear.k_master = 3e-08 .* \(a rigid plane does not wear\)"):
        load_scene("sphere-flat", rigid + per_body)


def test_a_mesh_file_is_not_sized_as_the_rectangle():
    """The strain estimate of a rectangle's face (its width and height, 50 mm by default) is not applied to a mesh
    file whose contact surface happens to be called 'bottom': that body is not known before the file is read."""
    data = {"geometry": {"kind": "file", "path": "/nowhere/punch.msh"}, "boundary": {"fixed": ["top"]},
            "contact": {"surface": "bottom"}, "loading": {"normal_force": 1e6}}
    assert load_scene(data).loading.normal_force == 1e6
    data["geometry"] = {"kind": "rectangle"}
    data.pop("boundary")
    with pytest.raises(SceneError, match=r"loading.normal_force = 1000000.0 .*\(face length 50 mm"):
        load_scene(data)


def test_a_mesh_file_has_no_mesh_refinement_in_a_study():
    """The study refines a built-in mesh (a half-cylinder's or a sphere's contact_mesh_size, a rectangle's nx and
    ny); a mesh file's mesh is the user's, and geometry.nx or ny would change nothing in it."""
    from dolfinx_fretting.study import default_reference, default_sweep

    scene = load_scene({"geometry": {"kind": "file", "path": "/nowhere/punch.msh"}, "boundary": {"fixed": ["top"]},
                        "contact": {"surface": "face"}, "loading": {"normal_force": 1.0}})
    overrides = default_reference(scene) + [o for _, _, entry in default_sweep(scene) for o in entry]
    assert overrides and not [o for o in overrides if o.startswith("geometry.")]
    block = load_scene("stromberg-block")
    assert f"geometry.nx={2 * block.geometry.nx}" in default_reference(block)
