"""The trade study (dolfinx_fretting.study) and the numerics presets (solver.preset)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from dolfinx_fretting.analytic import hertz_line_contact, plane_strain_modulus
from dolfinx_fretting.cli import main
from dolfinx_fretting.scenes import PRESETS, SceneError, load_scene
from dolfinx_fretting.study import (ERROR_FIELDS, map_l2_error, parse_point, parse_sweep, plan_study,
                                    profile_l2_error, read_study_csv, run_study, wear_l2_error)

#: A coarse, short cylinder-flat (17 contacts, 2 cycles): every run takes about a second.
TINY = ["loading.cycles=2", "geometry.contact_mesh_size=0.04", "geometry.coarse_mesh_size=1.0"]
TINY_REFERENCE = ["loading.increments_per_cycle=16", "solver.local_tol=1e-12", "solver.force_tol=1e-10"]


def _csv(path):
    return np.genfromtxt(path, names=True, delimiter=",", dtype=None, encoding="utf-8")


def _hand_outcome(folder):
    """Max wear, peak pressure of the last cycle, physical-cycle energy and the final wear profile, read
    straight from the run's files (independently of study._outcome)."""
    import json

    s = json.loads((folder / "summary.json").read_text())
    prof = _csv(folder / "contact_profiles.csv")
    last = prof["cycle"] == prof["cycle"].max()
    final = last & (prof["step"] == prof["step"][last].max())
    order = np.argsort(prof["position"][final])
    cyc = _csv(folder / "cycles.csv")
    e_cycles = float(np.sum(np.atleast_1d(cyc["dissipated_energy"])))
    energy = s["dissipated_energy"] - e_cycles + s["wear_acceleration"] * e_cycles
    return (s["max_wear_depth"], float(prof["pressure"][last].max()), energy,
            prof["position"][final][order], prof["wear"][final][order])


@pytest.fixture(scope="module")
def tiny_study(tmp_path_factory):
    out = tmp_path_factory.mktemp("study")
    plan = plan_study("cylinder-flat", TINY, TINY_REFERENCE,
                      [("loading.increments_per_cycle", ["8"]), ("wear.acceleration", ["2"]),
                       ("solver.local_max_iter", ["1"])])
    rows = run_study(plan, out, quiet=True, warm_up=False)
    return out, rows


def test_study_reference_row_has_zero_error(tiny_study):
    out, rows = tiny_study
    assert [r["label"] for r in rows] == ["reference", "increments_per_cycle=8", "acceleration=2",
                                          "local_max_iter=1"]
    ref = rows[0]
    for k in ERROR_FIELDS:
        assert ref[k] == 0.0, k  # the reference against itself: exactly zero
    assert ref["speedup"] == 1.0
    # the files: the same rows back from study.csv, and the table and the picture exist
    back = read_study_csv(out / "study.csv")
    assert [r["label"] for r in back] == [r["label"] for r in rows]
    for a, b in zip(back, rows):
        for k in ERROR_FIELDS:
            assert a[k] == pytest.approx(b[k], rel=1e-5, nan_ok=True)  # 6 significant digits in the CSV
    assert "**reference**" in (out / "study.md").read_text()
    assert (out / "study.png").stat().st_size > 10_000


def test_study_errors_by_hand(tiny_study):
    out, rows = tiny_study
    ref_dir = out / "runs" / "reference"
    w_r, p_r, e_r, x_r, prof_r = _hand_outcome(ref_dir)
    for row in rows[1:3]:
        w, p, e, x, prof = _hand_outcome(out / "runs" / row["label"])
        assert row["err_max_wear"] == pytest.approx(abs(w - w_r) / w_r, rel=1e-12)
        assert row["err_peak_pressure"] == pytest.approx(abs(p - p_r) / p_r, rel=1e-12)
        assert row["err_energy"] == pytest.approx(abs(e - e_r) / e_r, rel=1e-12)
        # same mesh here: the common abscissa is the nodes themselves, the L2 norm a trapezoid sum
        assert np.allclose(x, x_r)
        trapezoid = lambda f: np.sum(0.5 * (f[1:] + f[:-1]) * np.diff(x_r))  # noqa: E731 (np.trapz is gone in numpy 2)
        l2 = math.sqrt(trapezoid((prof - prof_r) ** 2) / trapezoid(prof_r**2))
        assert row["err_wear_l2"] == pytest.approx(l2, rel=1e-12)
        assert row["err_max_wear"] > 0  # the points do differ from the reference
    # equal physical cycles: acceleration 2 simulates one of the two cycles
    acc = rows[2]
    assert acc["cycles"] == 1 and acc["equivalent_cycles"] == 2.0
    assert rows[1]["cycles"] == 2


def test_study_keeps_a_failed_point(tiny_study):
    # one sweep per Uzawa solve cannot meet 1e-12: the run stops, the study goes on and says why
    out, rows = tiny_study
    failed = rows[3]
    assert failed["converged"] is False
    assert "local solver did not converge" in failed["error"]
    assert all(math.isnan(failed[k]) for k in ERROR_FIELDS)
    assert "failed" in (out / "study.md").read_text()


def test_study_survives_a_point_that_crashes(tmp_path, monkeypatch):
    """A point whose run ends in an exception the runner does not turn into a SimulationError (before issue 27:
    "RuntimeError: ValueError on rank 0: q: contains non-finite values" of loading.normal_force = 1e-300) is a failed
    row with its message; the finished reference and the later point are kept, table and picture written. Before,
    the exception left the study with no table at all."""
    import dolfinx_fretting.simulation as simulation

    real_run = simulation.run_scene

    def crashing(scene, folder, *args, **kwargs):
        if folder.name == "increments_per_cycle=8":
            raise RuntimeError("ValueError on rank 0: q: contains non-finite values")
        return real_run(scene, folder, *args, **kwargs)

    monkeypatch.setattr(simulation, "run_scene", crashing)
    plan = plan_study("cylinder-flat", TINY, TINY_REFERENCE,
                      [("loading.increments_per_cycle", ["8"]), ("wear.acceleration", ["2"])])
    rows = run_study(plan, tmp_path, quiet=True, warm_up=False)
    assert [r["label"] for r in rows] == ["reference", "increments_per_cycle=8", "acceleration=2"]
    assert [r["converged"] for r in rows] == [True, False, True]
    assert rows[1]["error"] == "RuntimeError: ValueError on rank 0: q: contains non-finite values"
    assert all(math.isnan(rows[1][k]) for k in ERROR_FIELDS) and rows[2]["err_max_wear"] > 0
    back = read_study_csv(tmp_path / "study.csv")
    assert [r["converged"] for r in back] == [True, False, True] and "q: contains" in back[1]["error"]
    assert "failed: RuntimeError" in (tmp_path / "study.md").read_text()
    assert (tmp_path / "study.png").stat().st_size > 10_000


def test_study_cli_exit_code_says_a_point_failed(tmp_path, capsys):
    """The table of a study with a failed point is written and printed, and the exit code is 1 with one line naming
    the failed point (before issue 27: 0, as if the study were whole)."""
    args = ["study", "cylinder-flat", "--out", str(tmp_path), "--no-warm-up", "--quiet",
            *[f"--set={o}" for o in TINY], *[f"--reference={o}" for o in TINY_REFERENCE],
            "--sweep", "solver.local_max_iter=1"]
    assert main(args) == 1
    captured = capsys.readouterr()
    assert "failed" in captured.out and "local_max_iter" in captured.out  # the table, with the failed row
    assert "1 of 2 runs failed (local_max_iter=1)" in captured.err
    assert [r["converged"] for r in read_study_csv(tmp_path / "study.csv")] == [True, False]


def test_profile_l2_error_closed_forms():
    # w = 2x against w_ref = x on [0, 1], different nodes: piecewise linear on the union grid, so the
    # relative L2 error is |2x - x| / |x| = 1 exactly
    assert profile_l2_error(np.array([0.0, 1.0]), np.array([0.0, 2.0]),
                            np.array([0.0, 0.5, 1.0]), np.array([0.0, 0.5, 1.0])) == pytest.approx(1.0, rel=1e-14)
    # a profile known on [0, 0.5] only is zero beyond it: union grid {0, 0.5, 1}, difference (0, 0, 1),
    # trapezoid: sqrt(0.25 / 1) = 0.5
    assert profile_l2_error(np.array([0.0, 0.5]), np.array([1.0, 1.0]),
                            np.array([0.0, 1.0]), np.array([1.0, 1.0])) == pytest.approx(0.5, rel=1e-14)
    # unsorted nodes are sorted first
    assert profile_l2_error(np.array([1.0, 0.0]), np.array([1.0, 0.0]),
                            np.array([0.0, 1.0]), np.array([0.0, 1.0])) == 0.0


def _grid_points(nx, ny):
    x, y = np.meshgrid(np.linspace(-0.3, 0.3, nx), np.linspace(0.0, 0.3, ny))
    return np.column_stack([x.ravel(), y.ravel()])


def test_wear_map_l2_error_of_a_3d_contact():
    # A 3D contact's wear is a map over the plane (half model: y >= 0). The same linear map on two node sets
    # of one rectangle is the same map: linear interpolation is exact, error 0 to rounding. Treated as a
    # profile along x (what the study did), the nodes sharing an x carry different values and the two
    # sets disagree.
    coarse, fine = _grid_points(7, 4), _grid_points(13, 7)
    def linear(p):
        return 1.0 + 2.0 * p[:, 0] + 5.0 * p[:, 1]
    assert wear_l2_error(coarse, linear(coarse), fine, linear(fine)) < 1e-12
    assert profile_l2_error(coarse[:, 0], linear(coarse), fine[:, 0], linear(fine)) > 0.05
    # twice the map: error 1 exactly; zero everywhere against zero: 0; against a zero reference: NaN
    assert map_l2_error(fine, 2 * linear(fine), coarse, linear(coarse)) == pytest.approx(1.0, rel=1e-12)
    assert map_l2_error(fine, 0 * linear(fine), coarse, 0 * linear(coarse)) == 0.0
    assert math.isnan(map_l2_error(fine, linear(fine), coarse, 0 * linear(coarse)))
    # a map known on half of the rectangle is zero beyond it (no contact node, no wear)
    half = coarse[coarse[:, 0] <= 0.0]
    err = map_l2_error(half, np.ones(len(half)), coarse, np.ones(len(coarse)))
    assert err == pytest.approx(np.sqrt(0.5), rel=0.01)
    # 2D positions (shape (m,)) still go to the profile error
    x = np.array([0.0, 1.0])
    assert wear_l2_error(x, 2 * x, x, x) == profile_l2_error(x, 2 * x, x, x) == pytest.approx(1.0)


def test_study_plan_validation():
    # an acceleration that does not divide the physical cycles: refused before any run, naming the key
    with pytest.raises(SceneError, match="wear.acceleration = 3 does not divide"):
        plan_study("cylinder-flat", TINY, TINY_REFERENCE, [("wear.acceleration", ["3"])])
    # a bad value of a swept key: the scene's own message, naming the point
    with pytest.raises(SceneError, match="(?s)sweep point loading.increments_per_cycle=10.*multiple of 4"):
        plan_study("cylinder-flat", TINY, TINY_REFERENCE, [("loading.increments_per_cycle", ["10"])])
    with pytest.raises(SceneError, match="unknown key 'solver.no_such_key'"):
        plan_study("cylinder-flat", TINY, TINY_REFERENCE, [("solver.no_such_key", ["1"])])
    with pytest.raises(SceneError, match="expected section.key=value"):
        parse_sweep(["solver.local_tol"])
    with pytest.raises(SceneError, match="swept twice"):
        parse_sweep(["solver.local_tol=1e-6", "solver.local_tol=1e-8"])
    assert parse_sweep(["output.snapshot_cycles=[1, 2],[3]"]) == [("output.snapshot_cycles", ["[1, 2]", "[3]"])]
    assert parse_point("solver.local_tol=1e-6 solver.force_tol=1e-4") == ["solver.local_tol=1e-6",
                                                                          "solver.force_tol=1e-4"]
    # default plan: reference (finer), then the default sweep; accelerations divide the cycle count
    plan = plan_study("cylinder-flat", TINY)
    ref = plan[0].scene
    assert ref.geometry.contact_mesh_size == 0.02 and ref.loading.increments_per_cycle == 160
    assert ref.solver.local_tol == 1e-12 and ref.solver.force_tol == 1e-10
    accs = [p for p in plan if p.key == "wear.acceleration"]
    assert [p.value for p in accs] == ["2"] and accs[0].scene.loading.cycles == 1


def test_study_default_plan_of_a_sphere():
    # The sphere's mesh is sized from its Hertz contact radius a (cubes of a/10 unless the scene sets
    # contact_mesh_size; it has no nx, ny): the default reference halves that size and the default sweep takes
    # 2x and 4x the reference's. Before, both wrote geometry.nx, which a sphere refuses.
    from dolfinx_fretting.analytic import hertz_sphere

    plan = plan_study("sphere-flat", ["loading.cycles=2"])
    scene = load_scene("sphere-flat")
    a, _ = hertz_sphere(scene.loading.normal_force, scene.geometry.radius, scene.contact_modulus)
    ref = plan[0].scene
    assert ref.geometry.contact_mesh_size == pytest.approx(a / 20, rel=1e-9)
    assert ref.loading.increments_per_cycle == 2 * scene.loading.increments_per_cycle
    sizes = [p.scene.geometry.contact_mesh_size for p in plan if p.key == "geometry.contact_mesh_size"]
    assert sizes == pytest.approx([a / 10, a / 5], rel=1e-5)


def test_study_cli_bad_input(capsys, tmp_path):
    assert main(["study", "cylinder-flat", "--out", str(tmp_path), "--sweep", "loading.increments_per_cycle=6"]) == 2
    assert "multiple of 4" in capsys.readouterr().err
    assert not (tmp_path / "runs").exists()  # refused before any run


# Presets --------------------------------------------------------------------------------------------------
def test_preset_supplies_unset_numerics_keys():
    s = load_scene("hertz", ["solver.preset=fast", "geometry.contact_mesh_size=none", "solver.local_tol=none"])
    p = PRESETS["fast"]
    a, _ = hertz_line_contact(199.24, 6.0, plane_strain_modulus(115000.0, 0.342))  # the scene's load and body
    assert s.geometry.contact_mesh_size == pytest.approx(a / p["contact_elements_per_half_width"], rel=5e-3)
    assert s.solver.local_tol == p["local_tol"]
    assert s.solver.force_tol == pytest.approx(p["local_tol"] * p["force_tol_factor"])
    assert s.loading.increments_per_cycle == p["increments_per_cycle"]
    r = load_scene("stromberg-block", ["solver.preset=accurate", "geometry.nx=none", "geometry.ny=none",
                                       "solver.local_tol=none", "loading.increments_per_cycle=none"])
    assert (r.geometry.nx, r.geometry.ny) == (PRESETS["accurate"]["rectangle_cells"],) * 2  # square block
    assert r.loading.increments_per_cycle == PRESETS["accurate"]["increments_per_cycle"]


def test_explicit_keys_win_over_the_preset():
    # hertz.toml sets contact_mesh_size = 0.01 and local_tol = 1e-10 itself; --set force_tol too
    s = load_scene("hertz", ["solver.preset=fast", "solver.force_tol=1e-3"])
    assert s.geometry.contact_mesh_size == 0.01
    assert s.solver.local_tol == 1e-10
    assert s.solver.force_tol == 1e-3
    assert s.loading.increments_per_cycle == PRESETS["fast"]["increments_per_cycle"]  # not in hertz.toml
    # no preset: the scene as written, defaults untouched
    d = load_scene("hertz", ["geometry.contact_mesh_size=none"])
    assert d.solver.preset is None and d.geometry.contact_mesh_size == 0.01 and d.loading.increments_per_cycle == 80
    # elastic-plastic scenes keep their tightened tolerances under any preset
    e = load_scene("cylinder-flat", ["solver.preset=fast", "material.model=elastoplastic",
                                     "material.yield_stress=840", "material.hardening_modulus=7230"])
    assert (e.solver.local_tol, e.solver.force_tol) == (1e-12, 1e-11)


def test_bad_preset_names_key_and_allowed_values():
    with pytest.raises(SceneError) as exc:
        load_scene("hertz", ["solver.preset=quick"])
    msg = str(exc.value)
    assert "solver.preset = 'quick'" in msg
    assert "'fast', 'balanced' or 'accurate'" in msg
    # a preset value that clashes with an explicit key is refused naming that key
    with pytest.raises(SceneError, match="geometry.contact_half_width"):
        load_scene("hertz", ["solver.preset=fast", "geometry.contact_mesh_size=none",
                             "geometry.contact_half_width=0.01"])
