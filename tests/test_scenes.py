"""Scene validation: bad input stops before any work with a message naming the key and the range."""

import subprocess
import sys

import pytest

from dolfinx_fretting.scenes import SceneError, apply_overrides, builtin_scenes, load_scene


@pytest.mark.parametrize(
    "override, expected",
    [
        ("material.nu=0.5", ["material.nu", "less than 0.5"]),
        ("material.nu=0.7", ["material.nu", "less than 0.5"]),
        ("material.E=0", ["material.E", "greater than 0"]),
        ("material.E=-2e5", ["material.E", "greater than 0"]),
        ("contact.mu=-0.1", ["contact.mu", "greater than or equal to 0"]),
        ("geometry.contact_mesh_size=0", ["geometry.contact_mesh_size", "greater than 0"]),
        ("geometry.contact_mesh_size=-0.01", ["geometry.contact_mesh_size", "greater than 0"]),
        ("geometry.contact_mesh_size=8.0", ["geometry.contact_mesh_size", "< geometry.radius = 6.0 mm"]),
        ("geometry.radius=-1", ["geometry.radius", "greater than 0"]),
        ("contact.candidate_half_width=10.0", ["contact.candidate_half_width", "geometry.radius = 6.0"]),
        ("material.Young=1", ["unknown key 'material.Young'", "allowed keys here: model, E, nu"]),
        ("geometri.radius=1", ["unknown key 'geometri'"]),
        ("material.E='steel'", ["material.E", "valid number"]),
        ("loading.normal_displacement=0.008", ["exactly one of loading.normal_displacement"]),
        ("loading.tangential_displacement=0.001", ["at most one of loading.tangential_displacement"]),
        ("loading.normal_increments=0", ["loading.normal_increments", "greater than or equal to 1"]),
        ("loading.increments_per_cycle=3", ["loading.increments_per_cycle", "greater than or equal to 4"]),
        ("loading.cycles=-1", ["loading.cycles", "greater than or equal to 0"]),
        ("wear.law='archard'", ["wear.k", "k > 0"]),
        ("wear.acceleration=0.5", ["wear.acceleration", "greater than or equal to 1"]),
        ("loading.tangential_pressure=10.0", ["at most one of", "tangential_pressure"]),
        ("output.history_every=0", ["output.history_every", "greater than or equal to 1"]),
        ("solver.local_tol=2", ["solver.local_tol", "less than 1"]),
        ("contact.plane_normal=[0.0, 0.0]", ["contact.plane_normal", "non-zero"]),
        ("material.model='plastic'", ["material.model", "'elastic'"]),
    ],
)
def test_bad_values_name_the_key_and_range(override, expected):
    with pytest.raises(SceneError) as info:
        load_scene("hertz", [override])
    for fragment in expected:
        assert fragment in str(info.value), str(info.value)


def test_builtin_hertz_is_valid_and_overrides_apply():
    assert "hertz" in builtin_scenes()
    scene = load_scene("hertz", ["contact.mu=0.3", "geometry.contact_mesh_size=0.02", "wear.law=archard",
                                 "wear.k=1e-8"])
    assert scene.contact.mu == 0.3
    assert scene.geometry.contact_mesh_size == 0.02
    assert scene.wear.law == "archard"
    assert scene.material.E == 115000.0 and scene.material.nu == 0.342


def test_cyclic_loading_checks():
    with pytest.raises(SceneError, match="a multiple of 4"):
        load_scene("hertz", ["loading.cycles=2", "loading.increments_per_cycle=10"])
    base = {"loading": {"normal_force": 10.0, "cycles": 3}}
    with pytest.raises(SceneError, match="needs its amplitude"):
        load_scene(base)
    with pytest.raises(SceneError, match="loading.pressure_face = 'top'"):
        load_scene({"geometry": {"kind": "rectangle"}, "contact": {"surface": "bottom"},
                    "loading": {"normal_displacement": 1e-4, "tangential_pressure": 10.0, "pressure_face": "top"}})
    scene = load_scene({"loading": {"normal_force": 10.0, "cycles": 3, "tangential_displacement": 0.001}})
    assert scene.loading.tangential_kind == "displacement" and scene.loading.tangential_amplitude == 0.001


def test_override_syntax_and_unknown_scene():
    with pytest.raises(SceneError, match="expected section.key=value"):
        apply_overrides({}, ["contact.mu"])
    with pytest.raises(SceneError, match="neither a built-in scene"):
        load_scene("no-such-scene")


def test_toml_file_errors_name_file(tmp_path):
    f = tmp_path / "bad.toml"
    f.write_text("[material]\nE = 1e5\nnu = 0.5\n[loading]\nnormal_force = 10.0\n")
    with pytest.raises(SceneError) as info:
        load_scene(f)
    assert str(f) in str(info.value) and "material.nu" in str(info.value)
    f.write_text("[material\n")
    with pytest.raises(SceneError, match="not valid TOML"):
        load_scene(f)


def test_cli_rejects_bad_input_before_any_work(tmp_path):
    """The CLI exits with code 2 and the message, without creating the output folder."""
    out = tmp_path / "out"
    proc = subprocess.run([sys.executable, "-m", "dolfinx_fretting", "run", "hertz", "--out", str(out),
                           "--set", "material.nu=0.5"], capture_output=True, text=True, timeout=120)
    assert proc.returncode == 2
    assert "material.nu" in proc.stderr and "less than 0.5" in proc.stderr
    assert not out.exists()
