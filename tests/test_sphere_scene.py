"""The ``sphere-flat`` scene through the scene runner: the half model reports the whole contact.

The half model about the plane y = 0 (a roller there) is given half the scene's forces and its sums (forces,
energy, worn volume, loaded area) are reported divided by the model fraction; the whole sphere on the mirrored
mesh must then give the same numbers. Coarse mesh (h = a/2), two gross-slip cycles, rigid plane (so the two
models differ only by the symmetry); the tolerance 1e-6 is the agreement of the two models through the API
(tests/test_sphere.py::test_half_model_equals_full_model: the two meshes' factorisations round differently).
"""

import json

import numpy as np
import pytest
from mpi4py import MPI  # noqa: F401  (before dolfinx on the wheel)

from dolfinx_fretting.contact_output import read_profiles  # noqa: E402
from dolfinx_fretting.scenes import load_scene  # noqa: E402
from dolfinx_fretting.simulation import run_scene  # noqa: E402

COARSE = ["geometry.contact_mesh_size=0.09", "contact.obstacle='rigid_plane'", "contact.plane_point=[0.0, 0.0, 0.0]",
          "loading.cycles=2", "loading.increments_per_cycle=8", "loading.normal_increments=2",
          "output.xdmf=false", "output.plots=false", "output.progress=false", "output.snapshot_cycles=[2]",
          "wear.k=1e-6"]
SUMS = ("normal_force", "tangential_force", "dissipated_energy", "wear_area")


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    out = {}
    for half in (True, False):
        folder = tmp_path_factory.mktemp(f"half{half}")
        summary = run_scene(load_scene("sphere-flat", COARSE + [f"geometry.half_model={str(half).lower()}"]),
                            folder, quiet=True)
        out[half] = (folder, summary)
    return out


def test_half_model_reports_the_whole_contact(runs):
    (_, half), (_, full) = runs[True], runs[False]
    assert half["converged"] and full["converged"]
    # the scene's P is the whole ball's (force control to 1e-8)
    assert half["normal_force"] == pytest.approx(100.0, rel=1e-8)
    for key in SUMS + ("max_pressure", "max_wear_depth"):
        assert half[key] == pytest.approx(full[key], rel=1e-6, abs=1e-12), key
    assert half["dissipated_energy"] > 0 and half["wear_area"] > 0  # gross slip wears
    # the 3D sizes: the same contact from both models (mirrored extent across, areas of the whole contact)
    for key in ("contact_radius", "stick_radius", "contact_extent_along", "contact_extent_across", "wear_volume"):
        assert half[key] == pytest.approx(full[key], rel=1e-9, abs=1e-12), key
    # the worn volume is the lumped integral of the wear gap: the history's wear_area in 3D
    assert half["wear_volume"] == pytest.approx(half["wear_area"], rel=1e-9)
    # and the loaded area's equivalent radius is Hertz's a within one element (h = 0.09 mm): on a rigid plane
    # a = (3 P R / (4 E*))^(1/3) with E* = E / (1 - nu^2) (0.148 mm at P = 100 N, R = 10 mm)
    E_star = 210000.0 / (1 - 0.3**2)
    a = (3 * 100.0 * 10.0 / (4 * E_star)) ** (1 / 3)
    assert abs(half["contact_radius"] - a) <= 0.09


def test_half_model_tables_and_description(runs):
    folder, summary = runs[True]
    run = json.loads((folder / "run.json").read_text())
    assert run["dim"] == 3 and run["run"]["model_fraction"] == 0.5
    prof = read_profiles(folder)
    assert prof.dim == 3 and prof.position_2 is not None
    # the 3D profile columns hold the contact plane: every node at y >= 0 (the half model), some on y = 0
    assert prof.position_2.min() >= -1e-12 and (abs(prof.position_2) < 1e-12).any()


def test_window_edge_message_of_a_sphere_names_keys_it_accepts():
    # Measured: 10^4 gross-slip cycles of sphere-flat with cycle jumps stopped at cycle 4769, the worn contact
    # (radius 0.275 mm) at the edge of the window (0.28 mm, the mesh's uniform zone), with advice to widen
    # geometry.contact_half_width "(now 0.667 mm)": a key the sphere refuses and the 2D zone's size. The
    # message must name only contact.candidate_half_width (which the sphere accepts) and the real zone.
    from types import SimpleNamespace

    from dolfinx_fretting.scenes import SceneError
    from dolfinx_fretting.simulation import SimulationError, _Run

    scene = load_scene("sphere-flat")
    model = SimpleNamespace(window_can_grow=False, half_width=0.2799, setup=SimpleNamespace(window_limit=0.2799),
                            contact=SimpleNamespace(abscissa=np.array([-0.2799, 0.2799])))
    with pytest.raises(SimulationError) as raised:
        _Run._window_edge_reached(SimpleNamespace(model=model, scene=scene), "increment 5 (cycle 1, step 1)")
    message = str(raised.value)
    assert "geometry.contact_half_width" not in message
    assert "contact.candidate_half_width (now 0.2799 mm; the mesh's uniform zone ends at 0.2799 mm" in message
    load_scene("sphere-flat", ["contact.candidate_half_width=0.5"])  # the advice is accepted
    with pytest.raises(SceneError, match="geometry.contact_half_width is not a key"):
        load_scene("sphere-flat", ["geometry.contact_half_width=0.5"])


def test_study_reads_a_3d_wear_map(runs):
    # The study compares a 3D run's worn map over the contact plane: its outcome holds the nodes' (x, y).
    from dolfinx_fretting.study import _outcome, point_errors

    folder, _ = runs[True]
    outcome = _outcome(folder)
    prof = read_profiles(folder)
    assert outcome.position.shape == (prof.position.size, 2)
    np.testing.assert_array_equal(outcome.position[:, 1], prof.position_2)
    errors = point_errors(folder, folder)
    assert errors["err_wear_l2"] == 0.0 and errors["err_max_wear"] == 0.0


# The ball under a tangential force (issue 22: the runner prescribed a force along its half model's held
# direction t2 and stopped in a traceback) ------------------------------------------------------------------------
def _force_controlled_run(folder, a_over_h, phi, cycles, increments, half=True):
    """sphere-flat (two identical steel bodies, P = 100 N, mu = 0.8) under a tangential force phi mu P: monotonic
    (cycles = 0, ``increments`` of it) or +-phi mu P for ``cycles`` cycles (``increments`` a cycle), cubes of
    a/``a_over_h`` under the contact, no wear. Returns (summary, cycles.csv or None, a, h, the scene)."""
    from dolfinx_fretting.analytic import plane_strain_modulus
    from dolfinx_fretting.contact_output import read_table
    from dolfinx_fretting.analytic import hertz_sphere

    scene = load_scene("sphere-flat")
    m, P, mu = scene.material, scene.loading.normal_force, scene.contact.mu
    a, _ = hertz_sphere(P, scene.geometry.radius, plane_strain_modulus(m.E, m.nu, m.E, m.nu))  # identical bodies
    h = a / a_over_h
    control = ([f"loading.cycles={cycles}", f"loading.increments_per_cycle={increments}"] if cycles else
               ["loading.cycles=0", f"loading.tangential_increments={increments}"])
    scene = load_scene("sphere-flat", ["loading.tangential_displacement=none", f"loading.tangential_force={phi * mu * P}",
                                       f"geometry.contact_mesh_size={h}", "loading.normal_increments=2",
                                       f"geometry.half_model={str(half).lower()}", "wear.law='none'", "wear.k=0.0",
                                       "output.xdmf=false", "output.plots=false", "output.progress=false",
                                       "output.contact_profiles=false", *control])
    summary = run_scene(scene, folder, quiet=True)
    table = read_table(folder / "cycles.csv") if cycles else None
    return summary, table, a, h, scene


def test_cattaneo_mindlin_stick_radius_under_a_tangential_force(tmp_path):
    """Identical bodies (Dundurs' beta = 0), Q = 0.5 mu P reached by force in 4 increments, the scene's own mesh
    (a/h = 4): the stick radius c = a (1 - Q/(mu P))^(1/3) (Johnson §7.2). The summary's ``stick_radius`` is the
    equivalent radius of the sticking nodes' tributary areas: measured c + 0.26 h (+8.1 %; at phi = 0.8 c + 0.25 h,
    +10.5 %), the edge nodes' areas reaching half an element past c. The issue's tolerance: 3 % + one element."""
    from dolfinx_fretting.analytic import cattaneo_mindlin_stick_radius

    phi = 0.5
    summary, _, a, h, scene = _force_controlled_run(tmp_path, 4, phi, 0, 4)
    P, mu = scene.loading.normal_force, scene.contact.mu
    assert summary["converged"] and summary["n_stick"] > 0 and summary["n_slip"] > 0  # partial slip
    # solver.force_tol = 1e-8 of the largest force in play (P)
    assert summary["tangential_force"] == pytest.approx(phi * mu * P, abs=1e-8 * P)
    c = cattaneo_mindlin_stick_radius(a, phi * mu * P, mu, P)
    assert abs(summary["stick_radius"] - c) <= 0.03 * c + h
    assert abs(summary["contact_radius"] - a) <= h  # Hertz, unchanged by Q (beta = 0)


def _energy_check(folder, a_over_h, tolerance):
    from dolfinx_fretting.analytic import mindlin_deresiewicz_energy, mindlin_shear_modulus

    phi = 0.8
    summary, cycles, a, h, scene = _force_controlled_run(folder, a_over_h, phi, 2, 8)
    m, P, mu = scene.material, scene.loading.normal_force, scene.contact.mu
    assert summary["converged"]
    # the loop reaches +-Q* (solver.force_tol = 1e-8 of the largest force in play, P)
    assert cycles["tangential_force_max"] == pytest.approx(phi * mu * P, abs=1e-8 * P)
    assert cycles["tangential_force_min"] == pytest.approx(-phi * mu * P, abs=1e-8 * P)
    assert np.all(cycles["min_stick"] > 0)  # partial slip throughout
    closed = mindlin_deresiewicz_energy(phi * mu * P, mu, P, a, mindlin_shear_modulus(m.E, m.nu, m.E, m.nu))
    # cycle 1 starts from Q = 0 on the virgin curve: only cycle 2 is the closed loop
    assert cycles["dissipated_energy"][1] == pytest.approx(closed, rel=tolerance)
    assert cycles["dissipated_energy"][0] < cycles["dissipated_energy"][1]


def test_mindlin_deresiewicz_energy_of_a_force_controlled_cycle(tmp_path):
    """The frictional energy of the second cycle of Q = +-0.8 mu P (the first starts on the virgin curve), P held,
    identical bodies, against Mindlin-Deresiewicz (analytic.mindlin_deresiewicz_energy: Johnson eq. 7.60, 1/G* =
    (2 - nu1)/G1 + (2 - nu2)/G2), through the runner, 8 increments a cycle (measured: the energy moves by 0.15 %
    from 8 to 80; cycle 3 equals cycle 2 to 2e-5).

    The error is that of where the stick-slip edge c = 0.585 a falls among the rings of nodes; it shrinks with the
    nodes across the slip annulus a - c = 0.415 a, not monotonically. Measured (40 increments a cycle), a/h = 2:
    +4.5 %, 2.5: +17.0 %, 3: +1.8 %, 3.5: -0.8 %, 4: +7.2 %, 4.5: +3.8 %, 5: +0.16 %, 6: +1.6 %, 7: +0.09 %,
    8: +0.92 %; the same at a/h = 4 and 6 through the API (test_sphere.py). From a/h = 5 (two elements across the
    annulus) every measured error is within 1.6 %: tolerance 3 %. Here a/h = 5 (33930 dofs, ~3 s): measured +0.24 %
    with 8 increments a cycle."""
    _energy_check(tmp_path, 5, 0.03)


@pytest.mark.slow
def test_mindlin_deresiewicz_energy_on_a_finer_mesh(tmp_path):
    """As above at a/h = 8 (79560 dofs, ~12 s): measured +1.00 % (8 increments a cycle; +0.92 % with 40); 2 % (the
    a/h >= 5 scatter, 1.6 %, with room)."""
    _energy_check(tmp_path, 8, 0.02)


def test_whole_ball_under_a_tangential_force_equals_the_half_model(tmp_path):
    """The whole ball is given the scene's forces as they are (no held direction: a zero force across x), the half
    model half of them with u_y held at 0 on y = 0. Coarse (a/h = 2), two cycles of +-0.8 mu P: the same energy per
    cycle, stick and contact radii and forces (measured 2e-10; 1e-6 as the displacement-controlled runs above)."""
    half, half_cycles, *_ = _force_controlled_run(tmp_path / "half", 2, 0.8, 2, 8)
    whole, whole_cycles, *_ = _force_controlled_run(tmp_path / "whole", 2, 0.8, 2, 8, half=False)
    assert whole["dofs"] > half["dofs"]
    for key in ("dissipated_energy", "stick_radius", "contact_radius", "normal_force", "max_pressure"):
        assert half[key] == pytest.approx(whole[key], rel=1e-6), key
    np.testing.assert_allclose(half_cycles["dissipated_energy"], whole_cycles["dissipated_energy"], rtol=1e-6)
    np.testing.assert_allclose(half_cycles["tangential_force_max"], whole_cycles["tangential_force_max"],
                               atol=2e-8 * half["normal_force"])  # each to solver.force_tol x P
