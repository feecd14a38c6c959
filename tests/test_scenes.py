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
        ("material.E=0", ["material.E = 0", "greater than or equal to 0.001", "<= 1e+07"]),
        ("material.E=-2e5", ["material.E", "greater than or equal to 0.001"]),
        # E so small that K's entries fall below MUMPS's null-pivot threshold: refused, with its range
        ("material.E=1e-300", ["material.E = 1e-300", ">= 0.001 and <= 1e+07"]),
        ("contact.mu=-0.1", ["contact.mu", "greater than or equal to 0"]),
        ("geometry.contact_mesh_size=0", ["geometry.contact_mesh_size = 0", ">= 1e-06"]),
        ("geometry.contact_mesh_size=-0.01", ["geometry.contact_mesh_size", ">= 1e-06"]),
        ("geometry.contact_mesh_size=8.0", ["geometry.contact_mesh_size", "< geometry.radius = 6.0 mm"]),
        ("geometry.radius=-1", ["geometry.radius = -1", ">= 1e-06"]),
        ("contact.candidate_half_width=10.0", ["contact.candidate_half_width", "geometry.radius = 6.0"]),
        ("material.Young=1", ["unknown key 'material.Young'", "allowed keys here: model, E, nu"]),
        ("geometri.radius=1", ["unknown key 'geometri'"]),
        ("material.E='steel'", ["material.E", "valid number"]),
        # no silent coercion: a quoted number is a string, a boolean is not a count, 2.0 is not an integer
        ("material.E='1e5'", ["material.E = '1e5'", "valid number", "allowed: a finite number >= 0.001"]),
        ("loading.normal_increments=true", ["loading.normal_increments = True", "valid integer"]),
        ("loading.tangential_increments=2.0", ["loading.tangential_increments = 2.0", "valid integer"]),
        ("output.xdmf=1", ["output.xdmf = 1", "valid boolean"]),
        # non-finite values, the user sweep's cases
        ("wear.k=inf", ["wear.k = inf", "finite number", ">= 0 and <= 1"]),
        ("loading.normal_force=inf", ["loading.normal_force = inf", "finite number"]),
        ("loading.tangential_force=nan", ["loading.tangential_force = nan", "finite number"]),
        ("contact.mu=inf", ["contact.mu = inf", "finite number", "<= 100"]),
        ("geometry.radius=inf", ["geometry.radius = inf", "finite number"]),
        ("wear.acceleration=inf", ["wear.acceleration = inf", "finite number"]),
        ("contact.plane_normal=[nan, 1.0]", ["contact.plane_normal[0] = nan", "finite number"]),
        ("output.snapshot_cycles=[1, 0]", ["output.snapshot_cycles[1] = 0", "greater than or equal to 1"]),
        ("output.track_positions=[0.0, -inf]", ["output.track_positions[1] = -inf", "finite number"]),
        # physical consistency before any work
        ("loading.tangential_force=179.316", ["loading.tangential_force = 179.316",
                                              "|Q| < contact.mu x loading.normal_force = 0.9 x 199.24"]),
        ("loading.tangential_force=-200.0", ["loading.tangential_force = -200.0", "|Q| < contact.mu"]),
        ("contact.mu=0.0", ["loading.tangential_force = 89.658", "0 with contact.mu = 0"]),
        ("material.E=100", ["loading.normal_force = 199.24", "Hertz strain", "material.E = 100"]),
        ("loading.normal_force=1e7", ["loading.normal_force = 10000000.0", "small-strain"]),
        ("wear.law='archard' wear.k=1e-3", []),  # accepted: a large but finite coefficient
        # a coefficient without a wear law was silently ignored before issue 27
        ("wear.k=1e-3", ["wear.k = 0.001 is given but wear.law = 'none'", "set wear.law = 'archard', or remove wear.k"]),
        ("wear.k=0.0", []),  # zero wears nothing: nothing ignored
        ("contact.mu=0.0 loading.tangential_force=0.0", []),  # frictionless, no tangential force: accepted
        ("geometry.contact_mesh_size=1e-6", ["geometry.contact_mesh_size = 1e-06",
                                             "elements along the refined contact zone"]),
        # PETSc options: only the factorisation's keys, each of its type and range
        ("solver.petsc_options={pc_type='jacobi'}", ["solver.petsc_options.pc_type = 'jacobi'", "'cholesky', 'lu'"]),
        ("solver.petsc_options={ksp_type='cg'}", ["unknown PETSc option solver.petsc_options.ksp_type",
                                                  "mat_mumps_icntl_<i>"]),
        ("solver.petsc_options={mat_mumps_icntl_99=1}", ["mat_mumps_icntl_99 = 1", "ICNTL(99) cannot be set"]),
        ("solver.petsc_options={mat_mumps_icntl_30=1}", ["ICNTL(30) cannot be set"]),
        ("solver.petsc_options={mat_mumps_icntl_14=-5}", ["mat_mumps_icntl_14 = -5", "an integer in [0, 10000]"]),
        ("solver.petsc_options={mat_mumps_icntl_14='50'}", ["mat_mumps_icntl_14 = '50'", "an integer in"]),
        ("solver.petsc_options={mat_mumps_icntl_24=true}", ["mat_mumps_icntl_24 = True", "an integer in [0, 1]"]),
        ("solver.petsc_options={mat_mumps_cntl_1=nan}", ["mat_mumps_cntl_1 = nan", "a finite number in [0, 1]"]),
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
    if not expected:
        load_scene("hertz", override.split())
        return
    with pytest.raises(SceneError) as info:
        load_scene("hertz", [override])
    for fragment in expected:
        assert fragment in str(info.value), str(info.value)


def test_per_body_wear_coefficients_without_a_wear_law_are_refused():
    """mccoll's k_slave and k_master with wear.law = 'none' (silently no wear before issue 27): refused, naming both."""
    with pytest.raises(SceneError) as info:
        load_scene("mccoll", ["wear.law='none'"])
    assert "wear.k_slave = 1.9e-08 is given but wear.law = 'none'" in str(info.value)
    assert "--set wear.k_slave=none --set wear.k_master=none" in str(info.value)
    assert load_scene("mccoll", ["wear.law='none'", "wear.k_slave=none", "wear.k_master=none"]).wear.coefficient_total == 0


def test_builtin_hertz_is_valid_and_overrides_apply():
    assert "hertz" in builtin_scenes()
    scene = load_scene("hertz", ["contact.mu=0.3", "loading.tangential_force=50.0", "geometry.contact_mesh_size=0.02",
                                 "wear.law=archard", "wear.k=1e-8"])
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


def _keys_of_type(kind):
    """Every ``section.key`` of a scene whose value (or list element) is of ``kind`` (float or int)."""
    import typing

    from dolfinx_fretting.scenes import Scene

    def base(annotation):
        origin, args = typing.get_origin(annotation), typing.get_args(annotation)
        if origin is typing.Annotated:
            return base(args[0])
        if origin in (typing.Union, __import__("types").UnionType):
            found = [base(a) for a in args if a is not type(None)]
            return found[0] if len(found) == 1 else None
        if origin is list:
            inner = base(args[0])
            return ("list", inner) if inner in (float, int) else None
        return annotation

    out = []
    for section, field in Scene.model_fields.items():
        model = field.annotation
        if not hasattr(model, "model_fields"):
            continue
        for name, f in model.model_fields.items():
            b = base(f.annotation)
            if b == kind or b == ("list", kind):
                out.append((f"{section}.{name}", isinstance(b, tuple)))
    return out


FLOAT_KEYS = _keys_of_type(float)
INT_KEYS = _keys_of_type(int)


def test_the_key_lists_are_complete():
    """The enumeration below covers the keys the user sweep named (so a new float key is covered too)."""
    names = {k for k, _ in FLOAT_KEYS}
    assert {"material.E", "contact.mu", "geometry.radius", "wear.k", "wear.acceleration", "loading.normal_force",
            "loading.tangential_force", "loading.tangential_pressure", "loading.tangential_displacement",
            "contact.plane_point", "contact.plane_normal", "output.track_positions",
            "output.checkpoint_interval"} <= names
    assert {"loading.cycles", "output.snapshot_cycles", "output.loop_cycles", "geometry.nx",
            "solver.local_max_iter"} <= {k for k, _ in INT_KEYS}


@pytest.mark.parametrize("key, is_list", FLOAT_KEYS)
@pytest.mark.parametrize("bad", ["inf", "-inf", "nan"])
def test_every_float_key_refuses_non_finite_values(key, is_list, bad):
    value = f"[0.0, {bad}]" if is_list else bad
    with pytest.raises(SceneError) as info:
        load_scene("hertz", [f"{key}={value}"])
    where = f"{key}[1]" if is_list else key
    assert f"{where} = {bad}" in str(info.value) and "finite number" in str(info.value), str(info.value)


@pytest.mark.parametrize("key, is_list", FLOAT_KEYS)
def test_every_float_key_refuses_a_string(key, is_list):
    value = "[0.0, '2.0']" if is_list else "'2.0'"
    with pytest.raises(SceneError) as info:
        load_scene("hertz", [f"{key}={value}"])
    assert "valid number" in str(info.value) and key in str(info.value), str(info.value)


@pytest.mark.parametrize("key, is_list", INT_KEYS)
@pytest.mark.parametrize("bad", ["true", "2.0", "'2'"])
def test_every_integer_key_refuses_booleans_floats_and_strings(key, is_list, bad):
    value = f"[1, {bad}]" if is_list else bad
    with pytest.raises(SceneError) as info:
        load_scene("hertz", [f"{key}={value}"])
    assert "valid integer" in str(info.value) and key in str(info.value), str(info.value)


def test_toml_integers_are_accepted_for_float_keys():
    scene = load_scene("hertz", ["material.E=200000", "contact.mu=1", "geometry.radius=6"])
    assert scene.material.E == 200000.0 and isinstance(scene.material.E, float)
    assert scene.contact.mu == 1.0 and isinstance(scene.contact.mu, float)


def test_empty_scene_needs_the_normal_load(tmp_path):
    """The README: every key is optional except the normal load. An empty file runs nothing."""
    f = tmp_path / "empty.toml"
    f.write_text("")
    with pytest.raises(SceneError) as info:
        load_scene(f)
    assert "missing section [loading]" in str(info.value)
    assert "loading.normal_force" in str(info.value) and "loading.normal_displacement" in str(info.value)
    with pytest.raises(SceneError, match="exactly one of loading.normal_displacement"):
        load_scene({"loading": {}})


def test_non_utf8_scene_file_names_the_file(tmp_path):
    f = tmp_path / "latin1.toml"
    f.write_bytes("name = 'Stromberg \u00e9'\n[loading]\nnormal_force = 10.0\n".encode("latin-1"))
    with pytest.raises(SceneError) as info:
        load_scene(f)
    assert str(f) in str(info.value) and "not a UTF-8 text file" in str(info.value) and "0xe9" in str(info.value)
    proc = subprocess.run([sys.executable, "-m", "dolfinx_fretting", "show", str(f)], capture_output=True,
                          text=True, timeout=120)
    assert proc.returncode == 2 and "Traceback" not in proc.stderr and "not a UTF-8" in proc.stderr


def test_scene_differences_names_the_changed_keys():
    from dolfinx_fretting.scenes import describe_differences, scene_differences

    a = load_scene("stromberg-block")
    b = load_scene("stromberg-block", ["material.E=200000", "loading.cycles=3", "solver.local_tol=1e-12",
                                       "contact.plane_point=[0.0, 1e-3]"])
    assert scene_differences(a, b) == ["contact.plane_point", "loading.cycles", "material.E", "solver.local_tol"]
    assert scene_differences(a, b, ignore=("solver", "output", "loading.cycles")) == ["contact.plane_point",
                                                                                     "material.E"]
    # dicts (a checkpoint's record of its scene) and scenes mix; a key present on one side only differs
    data = a.model_dump(mode="json")
    del data["wear"]["k"]
    assert scene_differences(data, a) == ["wear.k"]
    assert scene_differences(a, a.model_dump(mode="json")) == []
    text = describe_differences(a, b, ignore=("solver", "loading.cycles"), names=("checkpoint", "scene"))
    assert "material.E = 210000.0 (checkpoint), 200000.0 (scene)" in text
