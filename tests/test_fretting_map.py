"""Fretting maps (dolfinx_fretting.fretting_map): the classifiers on constructed cycle tables, and a tiny map through
the command line on cylinder-flat (2D: gross slip is where the tangential force reaches mu P)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.optimize import brentq

from dolfinx_fretting.analytic import (hertz_sphere, mindlin_deresiewicz_energy, mindlin_shear_modulus,
                                       mindlin_tangential_displacement)
from dolfinx_fretting.cli import main
from dolfinx_fretting.contact_output import read_table
from dolfinx_fretting import plots
from dolfinx_fretting.fretting_map import (GROSS_SLIP_ENERGY_RATIO, MAP_FIELDS, MapPoint, check_axis,
                                           classify_cycles, contact_amplitudes, energy_ratios,
                                           mindlin_contact_compliance,
                                           mindlin_transition_amplitude, plan_map, plot_map, read_map_csv,
                                           regime_of_cycles, reversal_compliance)
from dolfinx_fretting.scenes import SceneError, load_scene


def _shoelace(delta: np.ndarray, force: np.ndarray) -> float:
    """Area of the closed loop (delta, Q), counter-clockwise positive: the energy a cycle dissipates."""
    return 0.5 * float(np.sum(delta * np.roll(force, -1) - np.roll(delta, -1) * force))


def _table(loops: list[tuple[np.ndarray, np.ndarray]], regimes: list[str]) -> dict[str, np.ndarray]:
    """A cycles.csv table of the given loops: each one's energy (its area), force and displacement extremes."""
    return {"cycle": np.arange(1, len(loops) + 1),
            "dissipated_energy": np.array([abs(_shoelace(d, q)) for d, q in loops]),
            "tangential_force_max": np.array([q.max() for _, q in loops]),
            "tangential_force_min": np.array([q.min() for _, q in loops]),
            "displacement_max": np.array([d.max() for d, _ in loops]),
            "displacement_min": np.array([d.min() for d, _ in loops]),
            "regime": np.array(regimes)}


def _gross_loop(amplitude: float, force: float, elastic: float) -> tuple[np.ndarray, np.ndarray]:
    """Coulomb's gross-slip loop: a parallelogram of height 2 Q*, each branch stuck over 2 e then sliding."""
    delta = np.array([-amplitude, -amplitude + 2 * elastic, amplitude, amplitude - 2 * elastic])
    return delta, np.array([-force, force, force, -force])


def _masing_loop(q_star: float, mu: float, P: float, a: float, g_star: float, n: int = 400):
    """Mindlin-Deresiewicz's partial-slip loop of a sphere by Masing's rule: the unloading branch from +Q* is the
    loading curve of twice the force change, doubled (Johnson §7.3); the reloading branch its mirror."""
    change = np.linspace(0.0, 2 * q_star, n)[1:-1]
    delta_star = mindlin_tangential_displacement(q_star, mu, P, a, g_star)
    down = delta_star - 2 * np.array([mindlin_tangential_displacement(c / 2, mu, P, a, g_star) for c in change])
    q_down = q_star - change
    delta = np.concatenate([[delta_star], down, [-delta_star], -down])
    return delta, np.concatenate([[q_star], q_down, [-q_star], -q_down])


def test_energy_ratio_of_a_rectangular_gross_slip_loop():
    # A = area / (4 delta* Q*) = 1 - e/delta* exactly for the parallelogram (shoelace area: 2 Q* x 2 (delta* - e))
    delta_star, q_star, elastic = 0.02, 80.0, 2e-4
    table = _table([_gross_loop(delta_star, q_star, elastic)], ["gross_slip"])
    assert energy_ratios(table)[0] == pytest.approx(1 - elastic / delta_star, rel=1e-12)
    result = classify_cycles(table)
    assert result["regime"] == result["regime_by_stick"] == "gross" and result["regimes_agree"]
    assert result["energy_ratio_first"] == result["energy_ratio_last"] == pytest.approx(0.99, rel=1e-12)


def test_energy_ratio_of_a_thin_partial_slip_loop_and_fouvrys_transition():
    """The sphere's Mindlin-Deresiewicz loop (Masing's rule on Johnson eq. 7.42), its area by the shoelace formula:
    at Q* = 0.3 mu P, A is small (the series W = Q*^3 / (36 a G* mu P) gives A = Q*/(36 mu P) / (delta*/(Q*/8aG*))
    ~ 0.0094); at the onset of sliding (Q* -> mu P) A = (3/20) / (3/4) = 0.2: Fouvry's A_t, the constant itself."""
    E, nu, R, P, mu = 210000.0, 0.3, 10.0, 100.0, 0.8
    g_star = mindlin_shear_modulus(E, nu, E, nu)
    a = hertz_sphere(P, R, E / (2 * (1 - nu**2)))[0]
    thin = _masing_loop(0.3 * mu * P, mu, P, a, g_star)
    # the polygon's area against the closed form (Johnson eq. 7.60): 400 points, 1e-4
    assert abs(_shoelace(*thin)) == pytest.approx(mindlin_deresiewicz_energy(0.3 * mu * P, mu, P, a, g_star),
                                                  rel=1e-4)
    table = _table([thin], ["partial_slip"])
    ratio = energy_ratios(table)[0]
    assert 0.005 < ratio < 0.02  # thin: well under A_t (series value ~0.0094; the loop is not a rectangle)
    assert classify_cycles(table)["regime"] == "partial"
    # Fouvry's transition, from the closed forms (no polygon): the energy at Q* = mu P (1 - 1e-12) over 4 delta_t mu P
    q_edge = mu * P * (1 - 1e-12)
    a_t = (mindlin_deresiewicz_energy(q_edge, mu, P, a, g_star)
           / (4 * q_edge * mindlin_tangential_displacement(q_edge, mu, P, a, g_star)))
    assert a_t == pytest.approx(GROSS_SLIP_ENERGY_RATIO, rel=1e-6)  # (1 - phi)^(2/3) terms: 1e-8 at 1 - 1e-12


def test_mixed_regime_and_the_first_cycle():
    gross, partial = _gross_loop(0.02, 80.0, 2e-3), (np.array([-0.02, 0.0199, 0.02, -0.0199]),
                                                       np.array([-50.0, 50.0, 50.0, -50.0]))
    # Vincent et al.'s mixed regime: gross slip in the first cycles, then partial (friction rose)
    table = _table([gross, gross, partial, partial], ["gross_slip"] * 2 + ["partial_slip"] * 2)
    result = classify_cycles(table)
    assert result["regime"] == result["regime_by_stick"] == "mixed"
    assert result["cycle_regimes"][1:] == ["gross", "partial", "partial"]
    assert result["energy_ratio_first"] == pytest.approx(0.9, rel=1e-12)  # cycle 2: 1 - e/delta*
    assert result["energy_ratio_last"] == pytest.approx(0.0025, rel=1e-9)  # 2 Q* 2 (0.0001) / (4 Q* 0.02)
    # the first cycle starts on the virgin curve: the energy classifier reads from the second on, so a low first
    # A (a first loop that slid little) does not make a steady gross-slip run mixed
    first = _gross_loop(0.02, 80.0, 0.0195)
    result = classify_cycles(_table([first, gross, gross], ["gross_slip"] * 3))
    assert energy_ratios(_table([first], ["gross_slip"]))[0] == pytest.approx(0.025, rel=1e-9)
    assert result["regime"] == "gross" and result["regimes_agree"]
    # open cycles do not count; the threshold's range is checked
    assert regime_of_cycles(["open", "partial", "partial"]) == "partial"
    assert regime_of_cycles(["open"]) == "open"
    with pytest.raises(ValueError, match="threshold = 1.5.*> 0 and < 1"):
        classify_cycles(table, 1.5)
    # a threshold above the gross loops' A turns them partial: the option is honoured
    assert classify_cycles(_table([gross, gross], ["gross_slip"] * 2), 0.95)["regime"] == "partial"


def test_mindlin_transition_amplitude_of_the_sphere_scene():
    # sphere-flat: P = 100 N, mu = 0.8, identical steel bodies: a = 0.187 mm (the scene's comment),
    # G* = G / (2 (2 - nu)), delta_t = 3 mu P / (16 G* a) = 3.38 um
    scene = load_scene("sphere-flat")
    G = 210000.0 / (2 * 1.3)
    a = (3 * 100.0 * 10.0 / (4 * 210000.0 / (2 * (1 - 0.09)))) ** (1 / 3)
    assert a == pytest.approx(0.187, abs=5e-4)
    expected = 3 * 0.8 * 100.0 / (16 * G / (2 * 1.7) * a)
    assert mindlin_transition_amplitude(scene, 100.0) == pytest.approx(expected, rel=1e-12)
    assert mindlin_transition_amplitude(load_scene("cylinder-flat"), 100.0) is None  # 2D: none


def _rig_cycle(amplitude: float, bulk: float, mu: float, P: float, a: float, g_star: float, n: int = 64):
    """The steady cycle of a sphere on a flat under a triangular imposed displacement (0 -> +A -> -A -> 0, n
    increments) through a bulk compliance ``bulk`` in series with the contact: delta = bulk Q + Mindlin's loop
    (the virgin curve to the tip, Johnson eq. 7.42; Masing's branches, each the virgin curve of half the force
    change, doubled), the force solved at each increment's displacement (brentq, 1e-15 relative). A loop that
    reaches mu P slides at it (gross slip). Returns (displacement, force) at the increments' ends, and Q*."""
    limit = mu * P * (1 - 1e-12)

    def contact(change: float) -> float:   # Mindlin's displacement of a force change from a stuck state
        return mindlin_tangential_displacement(min(change, limit), mu, P, a, g_star)

    tip = bulk * limit + contact(limit)
    q_star = limit if amplitude >= tip else brentq(lambda q: bulk * q + contact(q) - amplitude, 0, limit,
                                                   xtol=1e-300, rtol=1e-15)
    j = np.arange(1, n + 1)
    wave = np.interp(j / n, [0, 0.25, 0.75, 1.0], [0, 1, -1, 0])
    delta = amplitude * wave
    force = np.empty(n)
    for i, (d, t) in enumerate(zip(delta, j / n)):
        down = 0.25 <= t < 0.75   # the branch from (+A, +Q*); else from (-A, -Q*)
        sign, start = (-1.0, amplitude) if down else (1.0, -amplitude)
        reach = abs(d - start)   # the displacement travelled from the reversal

        def branch(change):
            return bulk * change + 2 * contact(change / 2)
        change = 2 * q_star if reach >= branch(2 * q_star) else brentq(lambda c: branch(c) - reach, 0, 2 * q_star,
                                                                         xtol=1e-300, rtol=1e-15)
        force[i] = -sign * q_star + sign * change
    return delta, force, q_star


def test_reversal_slope_and_contact_amplitude_of_mindlins_loop():
    """Loops made of Mindlin's closed form (sphere-flat's steel bodies at P = 100 N) in series with a bulk
    compliance C_b = 5 % of the contact's 1/(8 G* a): the reversal slope is C_b + 1/(8 G* a) (Johnson §7.2), to
    1e-3 (the linear extrapolation of the first two chords leaves 2 u1 u2 / 27 of it, u the force changes over
    2 mu P: u1 ~ 0.03, u2 ~ 0.06 at 64 increments, 1.3e-4; the first chord alone would be u1/6 = 5e-3 off); the
    contact amplitude delta* - C_b Q* is Mindlin's displacement at Q*, delta_M(Q*), to 1e-3 of delta_t (the slope's
    error times Q*/delta_t ~ 1); a loop that slides within two increments of its reversal gives no slope, and its
    contact amplitude uses the load's measured C_b."""
    scene = load_scene("sphere-flat")
    m, mu, P = scene.material, scene.contact.mu, 100.0
    g_star = mindlin_shear_modulus(m.E, m.nu, m.E, m.nu)
    a = hertz_sphere(P, scene.geometry.radius, scene.contact_modulus)[0]
    contact = mindlin_contact_compliance(scene, P)
    assert contact == pytest.approx((2 - m.nu) / (4 * (m.E / (2 * (1 + m.nu))) * a), rel=1e-12)  # identical bodies
    assert mindlin_contact_compliance(load_scene("cylinder-flat"), P) is None
    bulk = 0.05 * contact
    delta_t = mindlin_transition_amplitude(scene, P)
    rows, plan = [], []
    for ratio in (0.3, 0.9, 1.1, 30.0):   # partial, partial, gross, gross sliding at once
        amplitude = ratio * delta_t
        delta, force, q_star = _rig_cycle(amplitude, bulk, mu, P, a, g_star, n=64 if ratio < 10 else 16)
        slope = reversal_compliance(delta, force)
        if ratio < 10:
            assert slope == pytest.approx(bulk + contact, rel=1e-3)
        else:
            assert math.isnan(slope)   # the chords reach -mu P: not elastic
        rows.append({"normal": P, "amplitude": amplitude, "converged": True, "reversal_compliance": slope,
                     "force_amplitude_last": q_star})
        plan.append(MapPoint(P, amplitude, "", [], scene))
    contact_amplitudes(rows, plan)
    for row in rows[:3]:
        assert row["bulk_compliance"] == pytest.approx(bulk, abs=1e-3 * contact)   # the slope's 1e-3
    for row in rows[:2]:
        q_star = row["force_amplitude_last"]
        expected = mindlin_tangential_displacement(q_star, mu, P, a, g_star)
        assert row["contact_amplitude"] == pytest.approx(expected, abs=1e-3 * delta_t)
    gross = rows[3]
    assert math.isnan(gross["bulk_compliance"])
    # the measured C_b's error (1e-3 of 1/(8 G* a)) times mu P: 7e-4 delta_t
    assert gross["contact_amplitude"] == pytest.approx(gross["amplitude"] - bulk * mu * P, abs=1e-3 * delta_t)
    # the transition in contact terms: 0.9 delta_t imposed is 0.9 delta_t - C_b Q*, under delta_t, as 1.1 is over
    assert rows[1]["contact_amplitude"] < delta_t < rows[2]["contact_amplitude"]


def test_map_axis_option(tmp_path, monkeypatch):
    """The picture's abscissa: ``contact`` draws the contact amplitude (a sphere) and says so on its axis, the
    default the imposed one (a loop variable once shadowed the option: every picture was labelled delta_c); a scene
    that is not a sphere, or another name, is refused naming the option before any run."""
    rows = [{"normal": 100.0, "amplitude": 0.003, "contact_amplitude": 0.0029, "regime": "partial",
             "converged": True, "regimes_agree": True},
            {"normal": 100.0, "amplitude": 0.004, "contact_amplitude": 0.0039, "regime": "gross",
             "converged": True, "regimes_agree": True}]
    assert plot_map(rows, tmp_path / "contact.png", axis="contact", mindlin={100.0: 0.0034}).stat().st_size > 10_000
    with pytest.raises(ValueError, match="axis = 'x': allowed imposed, contact"):
        plot_map(rows, tmp_path / "x.png", axis="x")
    assert main(["map", "cylinder-flat", "--normal", "100", "--amplitude", "0.01", "--axis", "contact",
                 "--out", str(tmp_path / "m")]) == 2
    assert not (tmp_path / "m" / "runs").exists()
    with pytest.raises(SceneError, match="--axis = 'sideways': allowed imposed, contact"):
        check_axis(plan_map("sphere-flat", [100.0], [0.003], cycles=1), "sideways")
    labels = []
    monkeypatch.setattr(plots, "_save", lambda fig, path: labels.append(fig.axes[0].get_xlabel()) or path)
    plot_map(rows, tmp_path / "imposed.png")
    plot_map(rows, tmp_path / "contact.png", axis="contact")
    assert labels == ["displacement amplitude delta* (mm)", "contact's amplitude delta_c = delta* - C_b Q* (mm)"]


#: cylinder-flat at CI size (contact elements of 40 um, 16 increments a cycle, 3 cycles): ~2 s a point; the refined
#: zone (and so the window's limit) 0.2 mm: P = 400 N/mm (Hertz a = 0.217 mm) does not fit and fails at its preload.
TINY = ["--set", "geometry.contact_mesh_size=0.04", "--set", "geometry.coarse_mesh_size=1.0",
        "--set", "loading.increments_per_cycle=16", "--set", "geometry.contact_half_width=0.2",
        "--set", "contact.candidate_half_width=0.15"]


@pytest.fixture(scope="module")
def tiny_map(tmp_path_factory):
    out = tmp_path_factory.mktemp("map")
    code = main(["map", "cylinder-flat", "--normal", "100,400", "--amplitude", "0.004,0.02", "--cycles", "3",
                 "--out", str(out), "--quiet", *TINY])
    return out, code


def test_tiny_map_through_the_cli(tiny_map):
    out, code = tiny_map
    assert code == 1  # the failed points (P = 400) stay in the table; the exit code says the map is not whole
    rows = read_map_csv(out / "map.csv")
    assert list(rows[0]) == MAP_FIELDS
    assert [(r["normal"], r["amplitude"]) for r in rows] == [(100, 0.004), (100, 0.02), (400, 0.004), (400, 0.02)]
    mu = load_scene("cylinder-flat").contact.mu
    partial, gross = rows[0], rows[1]
    for row in (partial, gross):
        assert row["converged"] and row["cycles"] == 3 and row["regimes_agree"]
        cycles = read_table(out / row["folder"] / "cycles.csv")
        # A from the run's own table (output.cycle_row's energy_ratio, another code path): 6 digits in map.csv
        assert row["energy_ratio_last"] == pytest.approx(cycles["energy_ratio"][-1], rel=1e-5)
        # the 2D reference (Coulomb): gross slip is Q* = mu P; force control on P within solver.force_tol
        # (1e-8 of P by default) and the local solver's 1e-10: 1e-6
        q_star = 0.5 * (cycles["tangential_force_max"][-1] - cycles["tangential_force_min"][-1])
        assert row["force_ratio_last"] == pytest.approx(q_star / (mu * 100.0), rel=1e-5)
    assert partial["regime"] == "partial" and partial["force_ratio_last"] < 0.9  # measured 0.63
    assert partial["energy_ratio_last"] < 0.05  # measured 0.010
    assert gross["regime"] == "gross" and gross["force_ratio_last"] == pytest.approx(1.0, abs=1e-6)
    assert gross["energy_ratio_last"] > 0.5  # measured 0.68
    # 2D: the loop's reversal slope is read (partial slip: elastic chords), no contact amplitude (a line contact has
    # no compliance apart from the bodies' size); Q* as the cycle's half range
    assert partial["reversal_compliance"] > 0 and math.isnan(partial["contact_amplitude"])
    assert math.isnan(partial["bulk_compliance"])
    assert partial["force_amplitude_last"] == pytest.approx(partial["force_ratio_last"] * mu * 100.0, rel=1e-5)
    for failed in rows[2:]:
        assert not failed["converged"] and failed["regime"] == "failed"
        assert "candidate window" in failed["error"] and math.isnan(failed["energy_ratio_last"])
    text = (out / "map.md").read_text()
    assert "**failed**" in text and "P = 100: 0.004 < delta_t < 0.02" in text
    assert (out / "map.png").stat().st_size > 10_000


def test_map_survives_a_point_that_crashes(tmp_path, monkeypatch, capsys):
    """A point whose run ends in an exception the runner does not turn into a SimulationError (a bug, a PETSc
    error) is a failed row with its message, and the later point is kept. Before the map shared the study's
    point runner (``study.run_point``), such an exception lost the whole map: no table at all."""
    import dolfinx_fretting.simulation as simulation

    real_run = simulation.run_scene

    def crashing(scene, folder, *args, **kwargs):
        if folder.name.endswith("0.004"):
            raise RuntimeError("ValueError on rank 0: q: contains non-finite values")
        return real_run(scene, folder, *args, **kwargs)

    monkeypatch.setattr(simulation, "run_scene", crashing)
    code = main(["map", "cylinder-flat", "--normal", "100", "--amplitude", "0.004,0.02", "--cycles", "1",
                 "--out", str(tmp_path), "--quiet", *TINY])
    assert code == 1
    rows = read_map_csv(tmp_path / "map.csv")
    assert [(r["amplitude"], r["converged"], r["regime"]) for r in rows] == [(0.004, False, "failed"),
                                                                            (0.02, True, "gross")]
    assert rows[0]["error"] == "RuntimeError: ValueError on rank 0: q: contains non-finite values"
    assert "1 of 2 runs failed (P = 100, delta* = 0.004)" in capsys.readouterr().err


@pytest.mark.parametrize("args, fragment", [
    (["--normal", "0,100", "--amplitude", "0.01"], "--normal '0,100': 0 is out of range"),
    (["--normal", "100", "--amplitude", "0.01,x"], "--amplitude '0.01,x': 'x' is not a number"),
    (["--normal", "100", "--amplitude", "0.01", "--cycles", "0"], "--cycles = 0"),
    (["--normal", "100", "--amplitude", "0.01", "--energy-threshold", "1.2"], "--energy-threshold = 1.2"),
    (["--normal", "1e9", "--amplitude", "0.01"], "map point P = 1e+09"),
])
def test_map_cli_bad_input(capsys, tmp_path, args, fragment):
    assert main(["map", "cylinder-flat", "--out", str(tmp_path / "m"), *args]) == 2
    assert fragment in capsys.readouterr().err
    assert not (tmp_path / "m" / "runs").exists()  # refused before any run


@pytest.mark.slow
def test_sphere_transition_against_mindlin(tmp_path):
    """sphere-flat (identical steel bodies, cubes of a/4: the scene's default before issue 26), P = 100 N, no wear,
    two cycles of 16 increments, in imposed and in contact terms:
    the transition amplitude against Mindlin's delta_t = 3 mu P / (16 G* a) = 3.383 um. The scene imposes the flat's
    displacement on finite bodies: delta_t,FE = delta_t + C_b mu P, C_b the bulk compliance, measured on the
    partial-slip point as (delta* - delta_M(Q*)) / Q* (delta_M: Mindlin's loading curve): measured C_b mu P = 0.10 um
    (3 % of delta_t; benchmarks/results/fretting_map_sphere.md). The points at 0.9 and 1.1 times the predicted
    transition must fall on its two sides by both classifiers: the tolerance 10 % is the transition's position
    between two rings of contact nodes at a/4 spacing (the stick radius falls to 0 at Q = mu P; the last ring's
    tributary area is ~1/16 of the contact, so the loop's end is reached within a few per cent of mu P). ~40 s."""
    a_hertz = hertz_sphere(100.0, 10.0, load_scene("sphere-flat").contact_modulus)[0]
    quarter = f"geometry.contact_mesh_size={a_hertz / 4:.6g}"
    scene = load_scene("sphere-flat", [quarter])
    delta_t = mindlin_transition_amplitude(scene, 100.0)
    low, high = 0.9 * delta_t, 1.1 * delta_t
    out = tmp_path / "map"
    assert main(["map", "sphere-flat", "--normal", "100", "--amplitude", f"{low:.6g},{high:.6g}", "--cycles", "2",
                 "--out", str(out), "--quiet", "--set", "wear.law='none'", "--set", "wear.k=none",
                 "--set", "loading.increments_per_cycle=16", "--set", quarter]) == 0
    partial, gross = read_map_csv(out / "map.csv")
    m, mu, P = scene.material, scene.contact.mu, 100.0
    g_star = mindlin_shear_modulus(m.E, m.nu, m.E, m.nu)
    a = hertz_sphere(P, scene.geometry.radius, scene.contact_modulus)[0]
    q_star = partial["force_ratio_last"] * mu * P
    bulk = (partial["amplitude"] - mindlin_tangential_displacement(q_star, mu, P, a, g_star)) / q_star
    predicted = delta_t + bulk * mu * P
    assert 0 <= bulk * mu * P < 0.1 * delta_t  # the bulk's share is small on the scene's bodies (measured 3 %)
    assert partial["amplitude"] < predicted < gross["amplitude"]
    assert partial["regime"] == partial["regime_by_stick"] == "partial"
    assert gross["regime"] == gross["regime_by_stick"] == "gross"
    # The contact's own amplitude (map.csv). The loop's slope at its reversals is the stuck contact's compliance
    # plus the bulk's: Mindlin's 1/(8 G* a) (Johnson §7.2) within 5 % (measured over 2..6 um in
    # benchmarks/results/fretting_map_sphere.md: -1.9 % .. +3.1 %, the chords of 16 increments a cycle read after the
    # outer ring of nodes has slipped; the loop's secant delta*/Q* would be +50 %)
    contact = mindlin_contact_compliance(scene, P)
    for row in (partial, gross):
        assert row["reversal_compliance"] == pytest.approx(contact, rel=0.05)
        # map.csv's 6 digits of the slope: 5e-11 mm/N
        assert row["bulk_compliance"] == pytest.approx(row["reversal_compliance"] - contact, abs=1e-10)
    # delta_c = delta* - C_b Q* against Mindlin's displacement at the partial point's Q* (Johnson eq. 7.42): within
    # 5 % of delta_t: the slope's 3 % of 1/(8 G* a) times mu P is 2 % of delta_t, the FE loop's own C_b from its
    # tip (above) 3 % (measured 2 %). Removing the whole slope would leave 3.05 - 2.15 um: -70 %.
    assert partial["contact_amplitude"] == pytest.approx(
        mindlin_tangential_displacement(partial["force_amplitude_last"], mu, P, a, g_star), abs=0.05 * delta_t)
    # the transition in contact terms brackets Mindlin's delta_t (the points 10 % either side of it)
    assert partial["contact_amplitude"] < delta_t < gross["contact_amplitude"]
