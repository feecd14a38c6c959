"""The ``sphere-flat`` scene through the scene runner: the half model reports the whole contact.

The half model about the plane y = 0 (a roller there) is given half the scene's forces and its sums (forces,
energy, worn volume, loaded area) are reported divided by the model fraction; the whole sphere on the mirrored
mesh must then give the same numbers. Coarse mesh (h = a/2), two gross-slip cycles, rigid plane (so the two
models differ only by the symmetry); the tolerance 1e-6 is the agreement of the two models through the API
(tests/test_sphere.py::test_half_model_equals_full_model: the two meshes' factorisations round differently).
"""

import json

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

    import numpy as np

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
    import numpy as np

    from dolfinx_fretting.study import _outcome, point_errors

    folder, _ = runs[True]
    outcome = _outcome(folder)
    prof = read_profiles(folder)
    assert outcome.position.shape == (prof.position.size, 2)
    np.testing.assert_array_equal(outcome.position[:, 1], prof.position_2)
    errors = point_errors(folder, folder)
    assert errors["err_wear_l2"] == 0.0 and errors["err_max_wear"] == 0.0
