"""The geometry kinds of the scenes: what each accepts."""

from __future__ import annotations

import pytest

from dolfinx_fretting.scenes import SceneError, load_scene


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
