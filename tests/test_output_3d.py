"""The output writers on a 3D contact: profiles with both tangent components, the contact plane in contact.xdmf,
the contact maps, the loaded area in the history.

The body: a hexahedral box pressed on a rigid plane (uniform pressure: the contact area is the box's face,
exactly) and dragged obliquely until it slides, through the public API; its states written by
:class:`~dolfinx_fretting.output.FrettingWriter`, then read back and compared with the problem's own fields.
"""

import warnings
from pathlib import Path

import numpy as np
import pytest
from mpi4py import MPI  # before dolfinx: on the DOLFINx wheel it loads the MPI library DOLFINx needs

import ufl  # noqa: E402
from dolfinx import fem, mesh  # noqa: E402

import dolfinx_fretting as dfr  # noqa: E402
from dolfinx_fretting import _dolfinx as dfx  # noqa: E402
from dolfinx_fretting.contact_output import read_contact_xdmf, read_profiles, read_table, write_contact_xdmf  # noqa: E402

E, NU, L, H, MU, K = 1000.0, 0.3, 1.0, 1.0, 0.3, 1e-3
COMM = MPI.COMM_WORLD


def box_problem():
    msh = mesh.create_box(COMM, [[-L / 2, -L / 2, 0.0], [L / 2, L / 2, H]], [4, 4, 4], mesh.CellType.hexahedron)
    V = dfx.vector_space(msh, 1)
    bottom = mesh.locate_entities_boundary(msh, 2, lambda x: np.isclose(x[2], 0.0))
    tags = mesh.meshtags(msh, 2, np.sort(bottom), np.full(bottom.size, 1, dtype=np.int32))
    top = mesh.locate_entities_boundary(msh, 2, lambda x: np.isclose(x[2], H))
    bcs = [fem.dirichletbc(np.zeros(3, dtype=np.float64), fem.locate_dofs_topological(V, 2, top), V)]
    lmbda, mu = E * NU / ((1 + NU) * (1 - 2 * NU)), E / (2 * (1 + NU))
    u, v = ufl.TrialFunction(V), ufl.TestFunction(V)
    eps = lambda w: ufl.sym(ufl.grad(w))  # noqa: E731
    a = ufl.inner(lmbda * ufl.tr(eps(u)) * ufl.Identity(3) + 2 * mu * eps(u), eps(v)) * ufl.dx
    contact = dfr.Contact(V, (tags, 1), dfr.RigidPlane([0, 0, 0], [0, 0, 1]), mu=MU, bcs=bcs)
    return dfr.FrettingProblem(a, contact, bcs, wear=dfr.Archard(K))


@pytest.fixture(scope="module")
def written(tmp_path_factory):
    folder = tmp_path_factory.mktemp("box3d") if COMM.rank == 0 else None
    folder = COMM.bcast(str(folder) if folder else None, root=0)
    problem = box_problem()
    # the box's numbers declared SI (E = 1000 Pa, L = 1 m): the labels say so, nothing else changes
    writer = dfr.FrettingWriter(problem, folder, dfr.RunDescription.of(problem, "box", preload_increments=1,
                                                                       units=dfr.Units.si()))
    state = problem.commit(problem.initial_state(), problem.solve(problem.initial_state(), normal=dfr.Force(10.0)))
    writer.write_increment(state, stage="normal")
    for d in (5e-3, 2e-2, 5e-2):  # oblique drag (t1 and t2), the last ones in gross slip
        state = problem.commit(state, problem.solve(state, tangential=dfr.Displacement([d, 0.5 * d])))
        writer.write_increment(state, stage="tangential")
    writer.close()
    fields = problem.contact_fields(state)
    frame = problem.contact.frame
    yield folder, fields, frame, state
    problem.destroy()


def test_profiles_hold_both_tangent_components(written):
    folder, fields, frame, state = written
    prof = read_profiles(folder)
    assert prof.dim == 3 and prof.position.size == fields["pressure"].size == 25
    # nodes matched by their point of the contact plane (the CSV holds 10 significant digits)
    in_plane = fields["coordinates"] @ frame[1:].T
    match = [prof.nearest_node(p1, p2) for p1, p2 in in_plane]
    assert sorted(match) == list(range(25))
    last = prof.increments.size - 1
    assert state.record["n_slip"] == 25  # gross slip: every node slides, and wears
    for column, expected in (("pressure", fields["pressure"]), ("shear", fields["shear"][:, 0]),
                             ("shear_2", fields["shear"][:, 1]), ("slip", fields["slip"][:, 0]),
                             ("slip_2", fields["slip"][:, 1]), ("wear", fields["wear"]),
                             ("relative_tangential_2", fields["relative_tangential"][:, 1])):
        # written with %.10g: 1e-9 relative to the column's scale
        scale = np.abs(expected).max()
        assert np.allclose(prof.values[column][last, match], expected, rtol=0, atol=1e-9 * scale), column
    # Coulomb in 3D: the shear vector of a sliding node has magnitude mu p
    shear = np.hypot(prof.values["shear"][last], prof.values["shear_2"][last])
    assert np.allclose(shear, MU * prof.values["pressure"][last], rtol=1e-6)


def test_history_holds_the_loaded_area(written):
    folder, fields, _, _ = written
    history = read_table(f"{folder}/history.csv")
    # the lumped tributary areas of a face sum to its area exactly; every node is loaded (uniform pressure)
    assert history["contact_area"] == pytest.approx(np.full(4, L * L), rel=1e-9)
    assert history["stick_area"][-1] == 0.0
    # wear-energy identity through the tables: worn volume = (k / mu) x energy (10 significant digits)
    assert history["wear_area"][-1] == pytest.approx(K / MU * history["dissipated_energy"].sum(), rel=1e-8)


def test_contact_xdmf_is_the_contact_plane(written):
    folder, *_ = written
    if COMM.rank != 0:
        return
    data = read_contact_xdmf(write_contact_xdmf(folder))
    kind, triangles = data["cells"]
    assert kind == "Triangle"
    p = data["points"]
    # the Delaunay triangles of the nodes tile the square face: their areas sum to L^2
    e1, e2 = p[triangles[:, 1]] - p[triangles[:, 0]], p[triangles[:, 2]] - p[triangles[:, 0]]
    assert 0.5 * np.abs(np.cross(e1, e2)[:, 2]).sum() == pytest.approx(L * L, rel=1e-12)
    assert {"shear_2", "slip_2", "pressure"} <= set(data["point_data"][-1])


def test_plot_run_draws_the_contact_maps(written):
    folder, *_ = written
    if COMM.rank != 0:
        return
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        pictures = {p.name for p in dfr.plot_run(folder)}
    assert not [str(w.message) for w in caught if issubclass(w.category, RuntimeWarning)]
    assert {"contact_maps.png", "profiles.png", "profiles_across.png"} <= pictures
    # The section across the sliding direction: the nodes of the line x = 0, ordered along t2.
    _, fields, frame, _ = written
    across = read_profiles(Path(folder) / "contact_profiles.csv").section_across(0.0)
    along_t1, along_t2 = fields["coordinates"] @ frame[1], fields["coordinates"] @ frame[2]
    level = along_t1[np.argmin(np.abs(along_t1))]
    expected = np.sort(along_t2[np.abs(along_t1 - level) < 1e-12])
    assert across.position.size >= 3 and np.allclose(across.position, expected, atol=1e-9)


def test_an_si_model_is_labelled_in_si(written, monkeypatch):
    """Issue 22: a user's model declared SI writes m, N, Pa in run.json and its plots say m and Pa, never mm or
    MPa (before: run.json and every label said mm, N, MPa whatever the model)."""
    import json

    from dolfinx_fretting import plots

    folder, *_ = written
    if COMM.rank != 0:
        return
    units = json.loads((Path(folder) / "run.json").read_text())["units"]
    assert (units["length"], units["force"], units["stress"]) == ("m", "N", "Pa")
    assert (units["contact_force"], units["wear_measure"], units["wear_coefficient"]) == ("N", "m³", "1/Pa")
    drawn = {}

    def keep(fig, path):
        drawn[Path(path).name] = fig
        return path

    monkeypatch.setattr(plots, "_save", keep)
    dfr.plot_run(folder)
    maps = drawn["contact_maps.png"]
    labels = [t for ax in maps.axes for t in (ax.get_xlabel(), ax.get_ylabel(), ax.get_title())]
    assert "t1 (m)" in labels and "pressure (Pa)" in labels
    assert any(t.startswith("end of preload") and t.endswith("t2 (m)") for t in labels)
    assert not [t for t in labels if "MPa" in t]   # small lengths (slips, wear) are rescaled down from m: mm here


def test_mean_relative_tangential_runs_opposite_to_Q(written):
    """The history's mean_relative_tangential is the body's position relative to the obstacle (y_t1 = u_t1 - D_t1):
    dragged along +t1 the box lags behind the obstacle, so the column is negative while Q > 0; the fretting loop
    plots its negative (plots._loop_displacement), which turns with Q."""
    folder, *_ = written
    history = read_table(f"{folder}/history.csv")
    dragged = history["stage"] == "tangential" if history["stage"].dtype.kind in "OU" else slice(1, None)
    Q, y = history["tangential_force"][dragged], history["mean_relative_tangential"][dragged]
    assert np.all(Q > 0) and np.all(y < 0)
