"""A sphere pressed and rubbed on a flat in 3D, through the public API (Contact, FrettingProblem): half models
with the symmetry plane y = 0 (a roller), structured hexahedra (meshes_3d.sphere_on_flat).

References: Hertz (Johnson, *Contact Mechanics*, 1985, §4.2: a = (3PR/(4E*))^(1/3), p0 = 3P/(2 pi a^2));
Cattaneo-Mindlin (Johnson §7.2: stick radius c = a (1 - Q/(mu P))^(1/3) for identical bodies); Archard's
wear-energy identity (worn volume = k/mu x dissipated energy); the full model for the half model.

Meshes are named by a/h (Hertz radius over the contact element), the extent (lateral size, cap height and
flat depth over a) and the growth ratio of the graded cells; each test says which gives its numbers.
"""

import numpy as np
import pytest
from mpi4py import MPI

from dolfinx import fem  # noqa: E402

import dolfinx_fretting as dfr  # noqa: E402
from dolfinx_fretting import _dolfinx as dfx  # noqa: E402

from support.sphere import COMM, E, NU, P, R, contact_radii, pressed, sphere_model  # noqa: E402


def test_hertz_sphere_on_a_rigid_plane():
    """a/h = 3, extent 9, growth 1.5 (6237 dofs, 39 contacts): the loaded area's equivalent radius is a + 0.43 h,
    the farthest loaded node a + 0.16 h, the peak nodal pressure p0 + 0.08 % (measured; a/h = 4, extent 9:
    +0.41 h, +0.24 h, +0.12 %; the note's hexahedra give the peak within 0.1 % from a/h = 3). Tolerances of the
    issue: a within one element, p0 within 2 %. The half model carries half the load."""
    body, problem, a, p0, h = sphere_model(3, 9.0, 1.5, flat=False)
    state = pressed(problem, P / 2)
    assert problem.total_force(state)[0] == pytest.approx(P / 2, rel=1e-8)  # LocalSolver.force_tol
    a_eq, r_max, p_max = contact_radii(problem, state)
    assert abs(a_eq - a) <= h and abs(r_max - a) <= h
    assert p_max == pytest.approx(p0, rel=0.02)
    problem.destroy()


def test_symmetry_plane_contacts_have_no_force_across_it():
    """Nodes on y = 0 have u_y held by the roller: their t2 row of H touches a fixed dof only. Their t2 force
    is zero (by symmetry) with friction and a tangential force along x; W has no coupling on those rows; a
    motion or a force across the plane is refused (a half model moves in its plane only)."""
    body, problem, a, p0, h = sphere_model(2, 5.0, 1.6, flat=False, mu=0.5)
    cs = problem.contact.contact_set
    on_plane = np.flatnonzero(np.abs(cs.coords[:, 1]) <= 1e-12)
    held = problem.contact.held_rows
    assert on_plane.size > 0 and held.tolist() == (3 * on_plane + 2).tolist()
    W = problem.operators.W
    off = W[held].copy()
    off[np.arange(held.size), held] = 0.0
    assert np.abs(off).max() == 0.0 and np.all(W[held, held] == W[held - 2, held - 2])
    state = pressed(problem, P / 2)
    state = problem.commit(state, problem.solve(state, tangential=(dfr.Force(0.3 * P / 2), dfr.Displacement(0.0))))
    # LocalSolver.force_tol = 1e-8 of the largest load in play (the normal force P/2)
    assert problem.total_force(state)[1] == pytest.approx(0.3 * P / 2, abs=1e-8 * P / 2)
    r = state.forces.reshape(-1, 3)
    assert np.abs(r[on_plane, 2]).max() == 0.0 and np.abs(r[:, 1]).max() > 0
    for bad in (dict(tangential=(dfr.Force(1.0), dfr.Force(0.0))), dict(tangential=[0.0, 1e-4]),
                dict(tangential=dfr.Force([1.0, 0.0]))):
        with pytest.raises(ValueError, match="tangential t2"):
            problem.solve(state, **bad)
    with pytest.raises(ValueError, match="tangential t2"):
        problem.run_cycle(state, dfr.CyclePath.waveform(4, tangential=[1e-4, 1e-4]))
    problem.destroy()


# Two deformable bodies: node-to-face -------------------------------------------------------------------------
def test_closest_points_on_faces_against_sampling():
    """Closest points of a warped quadrilateral and a triangle (pure NumPy) against a dense sampling of each
    facet: the distance agrees to the sampling's resolution, the weights are the facet's shape functions at the
    point (they sum to 1, are >= 0 and reproduce it) and the normal points away from the body."""
    from scipy.spatial import cKDTree

    from dolfinx_fretting.contact import pair_with_faces

    rng = np.random.default_rng(3)
    quad = np.array([[0.0, 0.0, 0.0], [1.0, 0.1, 0.05], [1.1, 1.0, -0.1], [0.1, 0.9, 0.08]])
    tri = np.array([[2.0, 0.0, 0.0], [3.0, 0.2, 0.1], [2.4, 1.0, -0.05], [2.4, 1.0, -0.05]])
    faces = np.array([quad, tri])
    inside = np.array([[0.5, 0.5, -1.0], [2.5, 0.4, -1.0]])
    points = rng.uniform([-0.5, -0.5, -0.3], [3.5, 1.5, 0.8], size=(400, 3))
    out = pair_with_faces(points, faces, np.array([4, 3]), inside)
    s = np.linspace(0, 1, 401)
    xi, eta = [g.ravel() for g in np.meshgrid(s, s)]
    N = np.column_stack([(1 - xi) * (1 - eta), xi * (1 - eta), xi * eta, (1 - xi) * eta])
    samples = [N @ quad, np.column_stack([1 - xi - eta, xi, eta])[xi + eta <= 1] @ tri[:3]]
    # The nearest sample by a k-d tree (exact: eps = 0), the same distances as the all-pairs norms (which took
    # 18 s and 1.5 GB for 400 points x 160 801 samples), in 0.3 s.
    brute = np.min([cKDTree(smp).query(points)[0] for smp in samples], axis=0)
    # the sampling step is 1/400 of a ~1 mm facet: its nearest sample is within ~2.5e-3 of the closest point
    assert np.all(out["distance"] <= brute + 1e-12) and np.all(out["distance"] >= brute - 4e-3)
    assert np.allclose(out["weights"].sum(axis=1), 1.0, atol=1e-14) and out["weights"].min() >= 0.0
    assert np.allclose(np.einsum("ni,nij->nj", out["weights"], faces[out["face"]]), out["point"], atol=1e-13)
    assert np.all(np.einsum("ij,ij->i", out["normal"], out["point"] - inside[out["face"]]) > 0)
    assert np.allclose(np.linalg.norm(out["normal"], axis=1), 1.0)


@pytest.mark.parametrize("flat_a_over_h", [None, 2.5], ids=["matching", "non-matching"])
def test_node_to_face_pairing_gaps_and_rigid_motions(flat_a_over_h):
    """The sphere's nodes paired with the flat's quadrilaterals (a/h = 3 on the sphere; the flat's a/h 3 or
    2.5): on a flat master the paired point is right below the node, the gap the sphere's height
    f = R - sqrt(R^2 - x^2 - y^2), the frame the obstacle's; a rigid translation of both bodies moves no contact,
    one of the sphere alone moves each by frame . D; nodes on y = 0 are held along t2."""
    body, problem, a, p0, h = sphere_model(3, 4.0, 1.6, flat=True, flat_mesh_size=flat_a_over_h)
    cs = problem.contact.contact_set
    x = cs.coords
    assert np.allclose(cs.master_points, np.column_stack([x[:, :2], np.zeros(cs.nc)]), atol=1e-15)
    assert np.allclose(cs.gap0, R - np.sqrt(R**2 - x[:, 0] ** 2 - x[:, 1] ** 2), atol=1e-15)
    assert np.allclose(cs.frames, np.eye(3)[[2, 0, 1]], atol=1e-15)
    if flat_a_over_h is not None:  # not all nodes face a master node: the bilinear weights are in use
        assert np.sum((cs.master_weights > 1e-9).sum(axis=1) > 1) > cs.nc // 2
    V = problem.V
    imap = V.dofmap.index_map
    sphere = np.unique(dfx.cell_dofmap(V)[body.cell_tags.find(body.regions["sphere"])])
    sphere = np.unique(np.concatenate(COMM.allgather(imap.local_to_global(sphere.astype(np.int32)))))
    D = np.array([1.0, -2.0, 0.5])
    both = np.tile(D, imap.size_global)
    alone = np.zeros(3 * imap.size_global)
    alone[(3 * sphere[:, None] + np.arange(3)).ravel()] = np.tile(D, sphere.size)
    assert np.abs(cs.H @ both).max() <= 1e-14
    assert np.allclose(cs.H @ alone, (cs.frames @ D).ravel(), atol=1e-14)
    on_plane = np.flatnonzero(np.abs(x[:, 1]) <= 1e-12)
    assert problem.contact.held_rows.tolist() == (3 * on_plane + 2).tolist()
    problem.destroy()


def test_hertz_sphere_on_an_identical_flat():
    """Two identical bodies, E* = E/(2(1 - nu^2)), matching meshes a/h = 3, extent 9, growth 1.5 (12474 dofs,
    50 contacts): equivalent radius a + 0.43 h, farthest loaded node a + 0.16 h, peak p0 + 0.12 % (measured).
    Issue's tolerances: one element, 2 %. (Non-matching meshes, node-to-face with bilinear weights: the peak is
    off by -6.6 % with the flat at a/h = 2.5, -2.8 % at 3.7, +3.4 % at 4: node-to-segment's known failure of the
    contact patch test; the contact radius stays within 0.45 h.)"""
    body, problem, a, p0, h = sphere_model(3, 9.0, 1.5, flat=True)
    state = pressed(problem, P / 2)
    assert problem.total_force(state)[0] == pytest.approx(P / 2, rel=1e-8)  # LocalSolver.force_tol
    a_eq, r_max, p_max = contact_radii(problem, state)
    assert abs(a_eq - a) <= h and abs(r_max - a) <= h
    assert p_max == pytest.approx(p0, rel=0.02)
    problem.destroy()


@pytest.mark.parametrize("flat", [False, True], ids=["rigid_plane", "elastic_flat"])
def test_hertz_sphere_on_the_depth_graded_mesh(flat):
    """The opt-in depth-graded mesh (meshes_3d.sphere_on_flat with depth_growth 1.5, coarsening 2, field_cell
    0.125: layers h thick at the contact face growing by 1.5, at most a/8 down to a, lateral 3:1 transitions
    below), a/h = 6, extent 9 (20 k dofs rigid, 41 k two bodies). Measured: peak nodal pressure p0 + 0.016 %
    (rigid plane), + 0.047 % (identical flat); equivalent radius a + 0.21 h, farthest loaded node a + 0.08 h.
    Tolerances: 0.5 % on p0 (graded meshes measured within +0.4 % at a/h = 6-12 with field_cell <= 0.25, today's
    within +0.2 %: benchmarks/results/contacts_3d.md; the issue asks 1 % of an a/16 reference), the radii within
    one element, as today's mesh."""
    body, problem, a, p0, h = sphere_model(6, 9.0, 1.5, flat=flat, depth_growth=1.5, coarsening=2)
    state = pressed(problem, P / 2)
    assert problem.total_force(state)[0] == pytest.approx(P / 2, rel=1e-8)  # LocalSolver.force_tol
    a_eq, r_max, p_max = contact_radii(problem, state)
    assert abs(a_eq - a) <= h and abs(r_max - a) <= h
    assert p_max == pytest.approx(p0, rel=0.005)
    problem.destroy()


# Friction and wear -------------------------------------------------------------------------------------------
def test_cattaneo_mindlin_stick_radius_and_slip_annulus():
    """Identical bodies (no normal-tangential coupling: Dundurs' beta = 0), mu = 0.5, then Q = phi mu P by force
    with P held (phi = 0.5): Cattaneo-Mindlin's stick radius c = a (1 - phi)^(1/3) = 0.794 a. Matching meshes
    a/h = 4, extent 9, growth 1.5 (21450 dofs, 75 contacts). Measured: the sticking area's equivalent radius
    c + 0.26 h (+8 %: the tributary areas of the stick zone's edge nodes reach half an element beyond it); the
    last sticking node at 0.79 a, the first sliding one at 0.90 a (a/h = 6: c_eq -0.01 h; a/h = 8: +0.25 h).
    The shear at the centre, Mindlin's mu p0 (1 - c/a), within 2 % (measured -0.7 %).
    Tolerance of the issue for c: 3 % + one element. In the slip annulus |q| = mu p to the local solver's
    tolerance, and it is an annulus: every loaded node beyond the last sticking one slides."""
    mu, phi = 0.5, 0.5
    body, problem, a, p0, h = sphere_model(4, 9.0, 1.5, flat=True, mu=mu)
    state = pressed(problem, P / 2)
    for f in (0.5, 1.0):
        state = problem.commit(state, problem.solve(
            state, tangential=(dfr.Force(f * phi * mu * P / 2), dfr.Displacement(0.0))))
    assert problem.total_force(state)[:2] == pytest.approx([P / 2, phi * mu * P / 2], abs=1e-8 * P / 2)
    fields = problem.contact_fields(state)
    tributary = problem.contact.contact_set.tributary
    r = np.linalg.norm(fields["coordinates"][:, :2], axis=1)
    stick, slip = fields["status"] == 1, fields["status"] == 2
    c_ref = a * (1 - phi) ** (1 / 3)
    c_eq = np.sqrt(2 * tributary[stick].sum() / np.pi)
    assert abs(c_eq - c_ref) <= 0.03 * c_ref + h
    assert abs(r[stick].max() - c_ref) <= h and abs(r[slip].min() - c_ref) <= h
    loaded = fields["pressure"] > 0
    assert np.all(slip[loaded & (r > r[stick].max())])  # an annulus
    q, p = np.linalg.norm(fields["shear"], axis=1), fields["pressure"]
    # |r_t| = mu r_n to the local solver's tolerance (1e-10 natural map), far below the classification's 1e-6
    assert np.allclose(q[slip], mu * p[slip], rtol=1e-8)
    assert np.all(q[stick] < mu * p[stick])
    centre = int(np.argmin(r))
    # Mindlin's traction at r = 0 (Johnson eq. 7.40) against a nodal force over its tributary area: 2 %
    assert q[centre] == pytest.approx(mu * p0 * (1 - c_ref / a), rel=0.02)
    problem.destroy()


def _gross_slip_run(half, mu=0.5, k=1e-6):
    """The coarse two-body model (a/h = 2, extent 4, growth 1.6: 1980 dofs half, 3630 full) pressed by P, then
    three gross-slip increments (0.005, 0.01, 0.015 mm along x) and one compiled cycle of +-0.015 mm."""
    body, problem, a, p0, h = sphere_model(2, 4.0, 1.6, flat=True, mu=mu, half=half, wear=dfr.Archard(k))
    state = pressed(problem, P / 2 if half else P)
    records = []
    for d in (0.005, 0.01, 0.015):
        state = problem.commit(state, problem.solve(state, tangential=(dfr.Displacement(d), dfr.Displacement(0.0))))
        records.append(state.record)
    cycle = problem.run_cycle(state, dfr.CyclePath.waveform(8, normal=state.obstacle[0], tangential=[0.015, 0.0]))
    assert cycle.compiled
    return problem, records, cycle, problem.commit(state, cycle), h


def test_wear_energy_identity_in_gross_slip():
    """Archard: worn volume (wear gap times tributary areas) = k/mu x dissipated energy, increment by increment
    (the per-increment path) and over a compiled cycle, to 1e-10 (measured: 0 and 2e-16; a/h = 2): every contact
    slides, where r_t = -mu r_n dx_t/|dx_t| exactly. Then a stroke beyond half an element warns once."""
    mu, k = 0.5, 1e-6
    problem, records, cycle, state, h = _gross_slip_run(True, mu, k)
    for rec in records:
        assert rec["n_stick"] == 0 and rec["n_slip"] > 0
        assert rec["wear_area_increment"] == pytest.approx(k / mu * rec["dissipated_energy"], rel=1e-10)
    assert cycle.records["wear_area_increment"].sum() == pytest.approx(
        k / mu * cycle.records["dissipated_energy"].sum(), rel=1e-10)
    assert state.record["wear_area"] == pytest.approx(
        float(problem.contact_fields(state)["wear"] @ problem.contact.contact_set.tributary), rel=1e-14)
    assert problem.relative_slip_ratio(state) < 0.5
    with pytest.warns(RuntimeWarning, match="exceeds half an element") if COMM.rank == 0 else _no_warning():
        state = problem.commit(state, problem.solve(state, tangential=(dfr.Displacement(0.6 * h),
                                                                     dfr.Displacement(0.0))))
    assert problem.relative_slip_ratio(state) > 0.5
    problem.destroy()


class _no_warning:
    """Other ranks: rank 0 alone warns."""

    def __enter__(self):
        import warnings

        self._catch = warnings.catch_warnings(record=True)
        self.caught = self._catch.__enter__()
        warnings.simplefilter("always")

    def __exit__(self, *exc):
        self._catch.__exit__(*exc)
        assert not [w for w in self.caught if "exceeds half an element" in str(w.message)]


def _steady_cycle_energy(problem, state, tangential, increments=40, cycles=2):
    """Whole-ball dissipated energy of the last of ``cycles`` cycles of a triangular ``tangential`` waveform
    (a Force or a Displacement amplitude along x, half model: y held at 0), P held by force."""
    wave = dfr.CyclePath.waveform(increments, tangential=1.0).tangential.value  # 0 -> +1 -> 0 -> -1 -> 0
    kind = type(tangential)
    path = dfr.CyclePath(normal=dfr.Force(np.full(increments, P / 2)),
                         tangential=(kind(tangential.value * wave), dfr.Displacement(np.zeros(increments))))
    for _ in range(cycles):
        cycle = problem.run_cycle(state, path)
        state = problem.commit(state, cycle)
    return 2 * float(cycle.records["dissipated_energy"].sum()), cycle


# slow (8 s): the same closed form (Johnson eq. 7.60, phi = 0.8, identical spheres, P held, partial slip) is
# checked by default through the runner, which drives this API's run_cycle: test_sphere_scene.py's
# test_mindlin_deresiewicz_energy_of_a_force_controlled_cycle (a/h = 5, 3 %).
@pytest.mark.slow
def test_mindlin_deresiewicz_energy_of_a_steady_partial_slip_cycle():
    """Energy of a steady cycle Q = +-Q*, P held, identical spheres (Mindlin & Deresiewicz 1953; Johnson §7.3):
    Mindlin's load-displacement curve delta(Q) = (3 mu P (2 - nu) / (8 a G)) [1 - (1 - Q/(mu P))^(2/3)] (Johnson
    eq. 7.42 with both bodies' compliances) unloaded by Masing's rule (the unloading branch is the loading curve
    of 2 Q* doubled) encloses W = (9 mu^2 P^2 / (10 a)) (2 (2 - nu) / G) [1 - (1 - phi)^(5/3)
    - (5 phi / 6) (1 + (1 - phi)^(2/3))], phi = Q*/(mu P) (Johnson eq. 7.60; checked against the Masing loop
    integrated numerically to 1e-12). The second cycle is the closed loop (the first starts from Q = 0).

    phi = 0.8 on matching meshes a/h = 6, extent 9, growth 1.5 (47124 dofs): measured +1.6 % (a/h = 4: +7.2 %,
    a/h = 8: +0.9 %); 40 or 80 increments a cycle agree to 1e-4. The issue's 5 %. (At phi = 0.5 the slip annulus,
    0.21 a wide, holds one or two rings of nodes and the error jumps with them: +12.6, -2.7, +5.2 % at a/h = 4,
    6, 8.)"""
    mu, phi = 0.5, 0.8
    body, problem, a, p0, h = sphere_model(6, 9.0, 1.5, flat=True, mu=mu)
    energy, cycle = _steady_cycle_energy(problem, pressed(problem, P / 2), dfr.Force(phi * mu * P / 2))
    assert cycle.records["n_stick"].min() > 0  # partial slip throughout
    G = E / (2 * (1 + NU))
    closed = (9 * mu**2 * P**2 / (10 * a) * (2 * (2 - NU) / G)
              * (1 - (1 - phi) ** (5 / 3) - 5 * phi / 6 * (1 + (1 - phi) ** (2 / 3))))
    assert energy == pytest.approx(closed, rel=0.05)
    problem.destroy()


def test_gross_slip_loop_grows_by_4_mu_P():
    """Beyond the transition the loop is a parallelogram whose width grows with the stroke: dW/d(delta*) = 4 mu P
    (a Coulomb slide at mu P over 4 d(delta*) a cycle). Coarse mesh a/h = 2, extent 4, growth 1.6; strokes 15
    and 20 um (relative slip below half an element): measured 1 - 2e-5. The issue's 1 %."""
    mu = 0.5
    body, problem, a, p0, h = sphere_model(2, 4.0, 1.6, flat=True, mu=mu)
    state = pressed(problem, P / 2)
    energies = []
    for stroke in (0.015, 0.02):
        energy, cycle = _steady_cycle_energy(problem, state, dfr.Displacement(stroke))
        assert cycle.records["n_stick"].min() == 0  # gross slip: some increment has every contact sliding
        energies.append(energy)
    assert (energies[1] - energies[0]) / 0.005 == pytest.approx(4 * mu * P, rel=0.01)
    problem.destroy()


def _steady_energy_along(problem, state, path_xy, cycles=3):
    """Whole-ball energy of the last of ``cycles`` cycles of the obstacle's tangential path (n, 2) (x, y), P held
    by force; returns (energy, the last cycle's state)."""
    n = path_xy.shape[0]
    path = dfr.CyclePath(normal=dfr.Force(np.full(n, P)), tangential=dfr.Displacement(path_xy))
    for _ in range(cycles):
        cycle = problem.run_cycle(state, path)
        state = problem.commit(state, cycle)
    return float(cycle.records["dissipated_energy"].sum()), state


def test_strokes_in_any_direction_and_turning_strokes_dissipate_mu_P_along_the_slip_path():
    """The whole ball (no symmetry plane), coarse mesh a/h = 2, mu = 0.5, gross slip:

    - a circular stroke, the obstacle at delta (cos 2 pi t, sin 2 pi t) over n = 32 increments: the friction force
      turns with the slip at |Q| = mu P (the 3D Coulomb cone; the slip is never along a fixed axis), along the
      obstacle's motion, and the steady cycle dissipates mu P times the slip path, an n-gon that follows the
      obstacle's up to the elastic part e (the contact's tangential compliance times mu P, about 1.4 um here,
      lagging along the path), so dW/d delta = mu P 2 n sin(pi / n) (= 0.998 x 2 pi mu P) up to terms of order
      (e / delta)^2 ~ 1 %;
    - a rectilinear stroke at 30 degrees from x: dW/d delta = 4 mu P, as along x.
    Strokes 15 and 20 um, 3 cycles each; 1 % (measured: circle +0.56 %, oblique -3.8e-5; the rectilinear stroke
    along x measures 2e-5 in the half model's test)."""
    mu, n = 0.5, 32
    body, problem, a, p0, h = sphere_model(2, 4.0, 1.6, flat=True, mu=mu, half=False)
    state = pressed(problem, P)
    t = np.arange(1, n + 1) / n
    circle = np.column_stack([np.cos(2 * np.pi * t), np.sin(2 * np.pi * t)])
    wave = dfr.CyclePath.waveform(n, tangential=1.0).tangential.value
    oblique = np.outer(wave, [np.cos(np.pi / 6), np.sin(np.pi / 6)])
    for shape, slope in ((circle, mu * P * 2 * n * np.sin(np.pi / n)), (oblique, 4 * mu * P)):
        energies = []
        for stroke in (0.015, 0.02):
            energy, final = _steady_energy_along(problem, state, stroke * shape)
            energies.append(energy)
            if shape is circle:   # sliding everywhere at the cone's edge, the force turning with the stroke
                Q = problem.total_force(final)[1:]
                assert np.linalg.norm(Q) == pytest.approx(mu * P, rel=1e-3)
                # along the obstacle's last step (the flat drags the ball), up to the slip's lag behind it
                # (measured cos = 0.992)
                step = (shape[-1] - shape[-2]) / np.linalg.norm(shape[-1] - shape[-2])
                assert np.dot(Q, step) > 0.97 * np.linalg.norm(Q)
        assert (energies[1] - energies[0]) / 0.005 == pytest.approx(slope, rel=0.01)
    problem.destroy()


def test_half_model_equals_full_model():
    """The half model (rollers on y = 0, P/2) and the full model (P) of the same coarse mesh through the same
    friction and wear history: forces, energy and worn volume halve, every node's pressure, shear, slip and wear
    match its twin's, to 1e-6 (measured: 4e-13 for the totals, 4e-10 of the largest value for the nodal fields;
    both solve to the local tolerance 1e-10)."""
    half, rec_h, cyc_h, st_h, _ = _gross_slip_run(True)
    full, rec_f, cyc_f, st_f, _ = _gross_slip_run(False)
    for a, b in zip(rec_h + [st_h.record], rec_f + [st_f.record]):
        for key in ("normal_force", "tangential_force", "dissipated_energy", "wear_area", "wear_area_increment"):
            assert 2 * a[key] == pytest.approx(b[key], rel=1e-6), key
        for key in ("max_pressure", "max_wear_depth"):
            assert a[key] == pytest.approx(b[key], rel=1e-6), key
    assert 2 * st_h.dissipated_energy == pytest.approx(st_f.dissipated_energy, rel=1e-6)
    fh, ff = half.contact_fields(st_h), full.contact_fields(st_f)
    twin = {tuple(np.round(x, 12)): i for i, x in enumerate(ff["coordinates"])}
    index = np.array([twin[tuple(np.round(x, 12))] for x in fh["coordinates"]])
    for key in ("pressure", "shear", "slip", "wear", "gap"):
        scale = np.abs(ff[key]).max()
        assert np.abs(fh[key] - ff[key][index]).max() <= 1e-6 * scale, key
    # the mirror nodes (y < 0) carry the mirrored shear: t2 components change sign
    mirror = np.array([twin[tuple(np.round(x * [1, -1, 1], 12))] for x in fh["coordinates"]])
    assert np.abs(ff["shear"][mirror] * [1, -1] - ff["shear"][index]).max() <= 1e-6 * np.abs(ff["shear"]).max()
    half.destroy()
    full.destroy()


# The built-in scene's model ----------------------------------------------------------------------------------
def test_sphere_flat_scene_model_is_hertz():
    """The ``sphere-flat`` scene's model (geometries.sphere), with the Contact and FrettingProblem a run
    builds from it, pressed by the scene's P on the half model (model_fraction 0.5): Hertz for two identical
    steel bodies; h = a/3 here (12.5k dofs) as in test_hertz_sphere_on_an_identical_flat. A caller that does not
    scale the forces to the half model is refused."""
    from dolfinx_fretting.analytic import hertz_sphere
    from dolfinx_fretting.geometries import build_scene_model
    from dolfinx_fretting.scenes import load_scene

    scene = load_scene("sphere-flat", ["geometry.contact_mesh_size=0.0622", "contact.mu=0"])
    with pytest.raises(ValueError, match="geometry.half_model = true"):
        build_scene_model(scene, COMM)
    setup = build_scene_model(scene, COMM, applies_model_fraction=True)
    contact = dfr.Contact(setup.V, setup.surface, setup.obstacle, scene.contact.mu, setup.bcs, setup.window)
    problem = dfr.FrettingProblem(setup.form, contact, setup.bcs, loads=setup.loads)
    assert setup.model_fraction == 0.5 and setup.small_sliding and setup.element_size == 0.0622
    E_star = scene.material.E / (2 * (1 - scene.material.nu**2))
    a, p0 = hertz_sphere(scene.loading.normal_force, scene.geometry.radius, E_star)
    state = pressed(problem, scene.loading.normal_force * setup.model_fraction)
    a_eq, r_max, p_max = contact_radii(problem, state)
    assert abs(a_eq - a) <= setup.element_size and p_max == pytest.approx(p0, rel=0.02)
    problem.destroy()


@pytest.mark.parametrize("override, fragment", [
    (["contact.plane_normal=[0.0, 1.0]", "contact.plane_point=[0.0, 0.0]"], "contact.plane_normal"),
    (["geometry.nx=10"], "geometry.nx is not a key of geometry.kind = 'sphere'"),
    (["geometry.contact_mesh_size=1.0"], "geometry.contact_mesh_size"),
    (["loading.normal_force=1e9"], "loading.normal_force"),
    (["loading.tangential_displacement=none", "loading.tangential_pressure=10.0"], "loading.tangential_pressure"),
    (["contact.obstacle='rigid_plane'", "contact.plane_point=[0.0, 0.0, 0.1]"], "contact.plane_point"),
    (["geometry.kind='half_cylinder'", "contact.plane_normal=[0.0, 1.0]", "contact.plane_point=[0.0, 0.0]"],
     "geometry.half_model"),
])
def test_sphere_flat_scene_refuses_bad_keys(override, fragment):
    from dolfinx_fretting.scenes import SceneError, load_scene

    with pytest.raises(SceneError, match=fragment.replace("[", r"\[").replace("(", r"\(")):
        load_scene("sphere-flat", override)


def test_elastic_plastic_sphere_that_cannot_yield_is_the_elastic_run(tmp_path):
    """The sphere-flat scene with the J2 law and sigma_y = 1e12 MPa (3D hexahedra, 8 Gauss points a cell, Newton
    with the contact inside each iteration): one Newton iteration an increment, no yielded point, and the
    elastic run's results. Coarse mesh (contact_mesh_size 0.09 mm, 7344 dofs, 29 contacts), one gross-slip
    cycle of 8 increments; measured 4e-8 at most (wear, energy), 1.7e-9 on the peak pressure."""
    from dolfinx_fretting.contact_output import read_table
    from dolfinx_fretting.scenes import load_scene
    from dolfinx_fretting.simulation import run_scene

    base = ["geometry.contact_mesh_size=0.09", "loading.cycles=1", "loading.increments_per_cycle=8",
            "output.xdmf=false", "output.plots=false", "output.progress=false"]
    plastic = ["material.model=elastoplastic", "material.yield_stress=1e12", "material.hardening_modulus=7230"]
    elastic = run_scene(load_scene("sphere-flat", base), tmp_path / "elastic", COMM, quiet=True)
    yielding = run_scene(load_scene("sphere-flat", base + plastic), tmp_path / "plastic", COMM, quiet=True)
    history = read_table(tmp_path / "plastic" / "history.csv")
    assert np.all(history["newton_iterations"] == 1) and np.all(history["yielded_points"] == 0)
    assert yielding["max_equivalent_plastic_strain"] == 0.0
    # Newton stops at delta_1 <= 1e-8 and the elastic-plastic scene tightens the local tolerance to 1e-12
    # (against 1e-10): the two paths agree to those tolerances, 1e-7 relative.
    for key in ("max_pressure", "contact_radius", "tangential_force", "max_wear_depth", "dissipated_energy",
                "wear_volume"):
        assert yielding[key] == pytest.approx(elastic[key], rel=1e-7), key


@pytest.mark.parametrize("p0_over_yield", [1.5, 1.7])
def test_first_yield_under_a_hertz_sphere(tmp_path, p0_over_yield):
    """Identical elastic-perfectly-plastic spheres pressed (the sphere-flat scene, P = 100 N, no tangential load):
    von Mises yield begins below the surface when p0 = 1.60 sigma_y, nu = 0.3 (Johnson, *Contact Mechanics*,
    1985, §6.2; the peak von Mises stress is 0.625 p0). p0 from Hertz with E* = E / (2 (1 - nu^2)). At
    sigma_y = p0 / 1.5 nothing yields and the peak of the quadrature points' von Mises stress is 0.625 p0 within
    3 % (measured +1.8 % at a/h = 3: contact_mesh_size 0.0622 mm, 13860 dofs); at p0 / 1.7 the body yields and
    the return mapping caps the stress at sigma_y. The 6 % margins on either side of 1.60 exceed that error."""
    from dolfinx_fretting.scenes import load_scene
    from dolfinx_fretting.simulation import run_scene

    base = load_scene("sphere-flat")
    E, nu, R, P = base.material.E, base.material.nu, base.geometry.radius, base.loading.normal_force
    E_star = E / (2 * (1 - nu**2))
    a = (3 * P * R / (4 * E_star)) ** (1 / 3)
    p0 = 3 * P / (2 * np.pi * a * a)
    sigma_y = p0 / p0_over_yield
    scene = load_scene("sphere-flat", ["material.model=elastoplastic", f"material.yield_stress={sigma_y!r}",
                                       "material.hardening_modulus=0", "geometry.contact_mesh_size=0.0622",
                                       "loading.cycles=0", "loading.tangential_displacement=0",
                                       "loading.tangential_increments=1", "output.xdmf=false", "output.plots=false",
                                       "output.progress=false"])
    s = run_scene(scene, tmp_path / "run", COMM, quiet=True)
    if p0_over_yield < 1.60:
        assert s["max_equivalent_plastic_strain"] == 0.0
        assert s["max_von_mises"] == pytest.approx(0.625 * p0, rel=0.03)
    else:
        assert s["max_equivalent_plastic_strain"] > 0.0
        assert s["max_von_mises"] <= sigma_y * (1 + 1e-9)
