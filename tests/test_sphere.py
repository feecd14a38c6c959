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

import ufl  # noqa: E402
from dolfinx import fem  # noqa: E402

import dolfinx_fretting as dfr  # noqa: E402
from dolfinx_fretting import _dolfinx as dfx  # noqa: E402
from dolfinx_fretting import meshes_3d as m3  # noqa: E402

COMM = MPI.COMM_WORLD
E, NU, R, P = 210000.0, 0.3, 10.0, 100.0   # MPa, -, mm, N (the whole sphere's load)


def elasticity(V):
    lmbda, G = E * NU / ((1 + NU) * (1 - 2 * NU)), E / (2 * (1 + NU))
    u, v = ufl.TrialFunction(V), ufl.TestFunction(V)
    eps = lambda w: ufl.sym(ufl.grad(w))  # noqa: E731
    return ufl.inner(lmbda * ufl.tr(eps(u)) * ufl.Identity(3) + 2 * G * eps(u), eps(v)) * ufl.dx


def sphere_model(a_over_h, extent, growth, *, flat, half=True, mu=0.0, wear=None, window=1.4, flat_mesh_size=None,
                 comm=COMM):
    """The sphere's cap (top clamped) on a rigid plane z = 0 or on an identical flat (bottom clamped), sized
    from Hertz's a for P; a half model has rollers (u_y = 0) on y = 0. Returns (body, problem, a, p0, h)."""
    E_star = E / (1 - NU**2) / (2.0 if flat else 1.0)
    a, p0 = m3.hertz_sphere(P, R, E_star)
    h = a / a_over_h
    body = m3.sphere_on_flat(comm, R, a, h, extent=extent, growth=growth, half=half, flat=flat,
                             flat_mesh_size=None if flat_mesh_size is None else a / flat_mesh_size)
    V = dfx.vector_space(body.mesh, 1)
    clamp = [fem.dirichletbc(np.zeros(3), fem.locate_dofs_topological(V, 2, body.facets(name)), V)
             for name in (["top", "flat_bottom"] if flat else ["top"])]
    bcs = clamp
    if half:
        V1, _ = V.sub(1).collapse()
        sym = np.concatenate([body.facets(n) for n in body.tags if "symmetry" in n])
        bcs = clamp + [fem.dirichletbc(fem.Function(V1), fem.locate_dofs_topological((V.sub(1), V1), 2, sym),
                                       V.sub(1))]
    surface = (body.facet_tags, body.tags["surface"])
    obstacle = (dfr.ElasticBody((body.facet_tags, body.tags["flat_top"]), [0.0, 0.0, 1.0]) if flat
                else dfr.RigidPlane([0.0, 0.0, 0.0], [0.0, 0.0, 1.0]))
    contact = dfr.Contact(V, surface, obstacle, mu=mu, bcs=bcs, window=window * a + h)
    problem = dfr.FrettingProblem(elasticity(V), contact, bcs, wear=wear)
    return body, problem, a, p0, h


def pressed(problem, load):
    state = problem.initial_state()
    for f in (0.5, 1.0):
        state = problem.commit(state, problem.solve(state, normal=dfr.Force(f * load)))
    return state


def contact_radii(problem, state, half=True):
    """(equivalent radius of the loaded area sqrt(A/pi), largest radius of a loaded node, peak pressure)."""
    fields = problem.contact_fields(state)
    loaded = fields["pressure"] > 0
    area = problem.contact.contact_set.tributary[loaded].sum() * (2.0 if half else 1.0)
    r = np.linalg.norm(fields["coordinates"][:, :2], axis=1)
    return np.sqrt(area / np.pi), r[loaded].max(), fields["pressure"].max()


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
    W = problem.W
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
    brute = np.min([np.linalg.norm(points[:, None] - smp[None], axis=2).min(axis=1) for smp in samples], axis=0)
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
