"""No silent truncation (issue 22): the nodes of the contact surface outside the candidate window are checked.

A ``Contact(..., window=w)`` solves on the nodes within ``w`` of the first point of contact only. Whatever ``w``,
no node of the tagged surface may penetrate the obstacle unnoticed: after every increment (every increment of a
compiled cycle too) the problem checks the nodes outside the window and raises
:class:`~dolfinx_fretting.state.WindowError` naming the window needed, or, with ``grow_window=True``, widens the
window and solves again. References: symmetry (two equal feet share the load equally), equilibrium (the total
force is the one prescribed), Hertz's line contact, and the displacement recovered independently of the check
(every surface node's gap).
"""

import numpy as np
import pytest
from mpi4py import MPI  # before dolfinx: on the DOLFINx wheel it loads the MPI library DOLFINx needs

import ufl  # noqa: E402
from dolfinx import fem, mesh  # noqa: E402
from petsc4py import PETSc  # noqa: E402

import dolfinx_fretting as dfr  # noqa: E402
from dolfinx_fretting import _dolfinx as dfx  # noqa: E402
from dolfinx_fretting import local_solvers  # noqa: E402
from dolfinx_fretting.analytic import hertz_line_contact  # noqa: E402
from dolfinx_fretting.geometries import build_scene_model  # noqa: E402
from dolfinx_fretting.scenes import load_scene  # noqa: E402
from dolfinx_fretting.simulation import SimulationError, run_scene  # noqa: E402

pytestmark = pytest.mark.skipif(MPI.COMM_WORLD.size > 1, reason="serial references; tests/test_parallel.py "
                                                                  "checks the decision under MPI")

E, NU = 200000.0, 0.3
LMBDA, MU_LAME = E * NU / ((1 + NU) * (1 - 2 * NU)), E / (2 * (1 + NU))
FOOT_X, FOOT_R = 0.5, 1.0     # the feet's centres (x = -0.5 and 0.5) and radius
P = 2000.0                    # the normal force on the two feet


def elasticity(V):
    u, v = ufl.TrialFunction(V), ufl.TestFunction(V)
    eps = lambda w: ufl.sym(ufl.grad(w))  # noqa: E731
    sigma = LMBDA * ufl.tr(eps(u)) * ufl.Identity(2) + 2 * MU_LAME * eps(u)
    return ufl.inner(sigma, eps(v)) * ufl.dx


def two_feet(comm=MPI.COMM_WORLD, lift=0.0, nx=40, ny=20):
    """A 2 x 1 block whose bottom (marker 1) is two round feet of radius 1 at x = -0.5 and 0.5, their lowest
    points at y = 0 (the left one at y = ``lift``); the top (marker 2) is clamped. Quadrilaterals, symmetric about
    x = 0 when ``lift`` is 0. The feet are parabolic profiles y = (x - x_i)^2 / 2R (Hertz's approximation of a
    circle), mapped onto a structured mesh."""
    msh = mesh.create_rectangle(comm, [[-1.0, 0.0], [1.0, 1.0]], [nx, ny], mesh.CellType.quadrilateral)
    found = [mesh.locate_entities_boundary(msh, 1, f) for f in (lambda x: np.isclose(x[1], 0.0),
                                                                lambda x: np.isclose(x[1], 1.0))]
    facets = np.concatenate(found)
    values = np.concatenate([np.full(f.size, i + 1, dtype=np.int32) for i, f in enumerate(found)])
    order = np.argsort(facets)
    tags = mesh.meshtags(msh, 1, facets[order], values[order])
    x = msh.geometry.x
    profile = np.minimum((x[:, 0] - FOOT_X) ** 2, (x[:, 0] + FOOT_X) ** 2 + 2 * FOOT_R * lift) / (2 * FOOT_R)
    x[:, 1] += (1.0 - x[:, 1]) * profile
    V = dfx.vector_space(msh, 1)
    dofs = fem.locate_dofs_topological(V, 1, tags.find(2))
    bcs = [fem.dirichletbc(np.zeros(2, dtype=PETSc.ScalarType), dofs, V)]
    return V, tags, bcs


def feet_problem(window, grow=False, mu=0.0, lift=0.0, comm=MPI.COMM_WORLD, **kw):
    """The two feet on a rigid plane y = 0 pushed up; the plane's point under the right foot makes the right foot
    the first point of contact (ties of equal feet go to the foot nearest the plane's point)."""
    V, tags, bcs = two_feet(comm, lift)
    contact = dfr.Contact(V, (tags, 1), dfr.RigidPlane([FOOT_X, 0.0], [0.0, 1.0]), mu=mu, bcs=bcs, window=window,
                          grow_window=grow)
    return dfr.FrettingProblem(elasticity(V), contact, bcs, **kw), V, tags


def surface_gaps(problem, V, tags, state):
    """Every bottom node's gap to the plane from the displacement solved anew (K u = H^T r), independent of
    the outside rows the check uses: y + u_y - d, the plane moved up by the approach d."""
    u = problem.displacement(state)
    nodes = fem.locate_dofs_topological(V, 1, tags.find(1))
    x = V.tabulate_dof_coordinates()[nodes]
    return x[:, 1] + u.x.array[2 * nodes + 1] - state.obstacle[0], x


def test_two_feet_window_around_one_foot_raises_then_grows_and_shares_the_load():
    """Issue 22's first case: a window around one foot. Without the check that foot carried the whole load and
    the other penetrated the plane silently; now the solve raises WindowError naming the window, the penetrating
    nodes (all under the other foot) and the window needed; with grow_window=True the increment is solved again in
    a wider window: the two equal feet (a symmetric mesh) carry P/2 each, the total is P, and no node of the surface
    penetrates."""
    problem, V, tags = feet_problem(window=0.2)
    state = problem.initial_state()
    with pytest.raises(dfr.WindowError) as caught:
        problem.solve(state, normal=dfr.Force(P))
    err = caught.value
    assert isinstance(err, dfr.ConvergenceError)  # what callers that stop on a failed increment catch
    assert "window = 0.2" in str(err) and "window needed" in str(err)
    assert err.window == 0.2 and err.positions.shape[1] == 2 and err.penetration > 0
    # Every penetrating node is under the left foot, and the window needed reaches the farthest of them from the
    # window's centre (the right foot's lowest point, x = 0.5).
    assert np.all(np.abs(err.positions[:, 0] + FOOT_X) < 0.3)
    assert err.window_needed > np.abs(err.positions[:, 0] - FOOT_X).max()
    assert f"{err.window_needed:.6g}" in str(err)

    problem, V, tags = feet_problem(window=0.2, grow=True)
    with pytest.warns(RuntimeWarning, match="candidate window grown from 0.2"):
        state, _ = problem.advance(problem.initial_state(), normal=dfr.Force(P))
    assert problem.contact.window == pytest.approx(err.window_needed)
    # The outside rows were rebuilt with the window: what is left outside lies beyond it.
    outside = problem.operators.outside
    assert outside is None or np.all(outside.distance > problem.contact.window)
    fields = problem.contact_fields(state)
    left = fields["coordinates"][:, 0] < 0
    rn = state.forces[0::2]
    # Force control reaches P to the solver's force tolerance (1e-8 relative).
    assert rn.sum() == pytest.approx(P, rel=1e-7)
    # Symmetry: the mesh is symmetric to rounding, the local solve converged to 1e-10 (natural map): the feet's
    # forces agree to far better than 1e-6 of P.
    assert rn[left].sum() == pytest.approx(P / 2, rel=1e-6) and rn[~left].sum() == pytest.approx(P / 2, rel=1e-6)
    gaps, _ = surface_gaps(problem, V, tags, state)
    # A converged open node may sit below zero by the solver's tolerance times the displacement scale (~1e-3 here):
    # 1e-9 of the approach is far above it and far below a truncation's penetration (here 1e-2).
    assert gaps.min() >= -1e-9 * state.obstacle[0]


def test_hertz_cylinder_window_narrower_than_its_contact():
    """Issue 22's second case: a cylinder whose window is narrower than its Hertz contact (a = 0.108 mm, window
    0.05 mm) raised no warning and gave a wrong peak. Now: WindowError with a window needed wider than a; solved
    again in that window, the peak pressure is Hertz's p0 to the mesh's accuracy (1 %, as tests/test_hertz.py)."""
    P_line = 199.24
    scene = load_scene("hertz", ["geometry.contact_mesh_size=0.02", "contact.mu=0.0", "loading.tangential_force=0.0"])
    model = build_scene_model(scene, MPI.COMM_WORLD)
    a, p0 = hertz_line_contact(P_line, scene.geometry.radius, scene.material.E / (1 - scene.material.nu ** 2))
    contact = dfr.Contact(model.V, model.surface, model.obstacle, 0.0, model.bcs, window=0.05)
    problem = dfr.FrettingProblem(model.form, contact, model.bcs)
    state = problem.initial_state()
    with pytest.raises(dfr.WindowError, match="window = 0.05") as caught:
        problem.solve(state, normal=dfr.Force(P_line))
    needed = caught.value.window_needed
    assert needed >= a
    state = problem.set_window(state, needed)
    state = problem.commit(state, problem.solve(state, normal=dfr.Force(P_line)))  # no WindowError now
    fields = problem.contact_fields(state)
    assert problem.total_force(state)[0] == pytest.approx(P_line, rel=1e-7)
    assert fields["pressure"].max() == pytest.approx(p0, rel=0.01)
    # The contact now ends inside the window: its outermost candidates carry nothing.
    assert state.forces[0] == 0.0 and state.forces[-2] == 0.0


def test_no_window_and_an_unviolated_window_leave_the_answer_untouched():
    """``window=None`` (the default) is the whole surface: nothing outside, nothing checked. Where the check runs and
    finds nothing, it changes nothing either: the increment is the local solve of (W, q) itself, bit for bit."""
    problem, _, _ = feet_problem(window=None, mu=0.3, lift=2e-3)
    assert problem.contact.outside is None and problem.operators.outside is None
    # A window around the right foot with a load the right foot carries alone (the left foot 2e-3 higher than
    # the approach of 1e-3): the check runs (the left foot's nodes are outside) and passes.
    windowed, _, _ = feet_problem(window=0.2, mu=0.3, lift=2e-3)
    assert windowed.operators.outside is not None and windowed.operators.outside.nodes.nc > 0
    for prob in (problem, windowed):
        state = prob.initial_state()
        result = prob.solve(state, normal=1e-3, tangential=2e-4)
        ops = prob.operators
        q, _ = ops.q(result.obstacle, result.load_factors, state.positions, state.wear_gap)
        plain = local_solvers.solve(ops.W, q, ops.contact.mu, 2, method="uzawa", tol=prob.solver.tol,
                                    max_iter=prob.solver.max_iter, r0=state.forces)
        assert np.array_equal(result.forces, plain.r) and np.array_equal(result.slip, plain.x)
        # The steps the operators hold are block_rho of the W they hold (same numbers, computed once per W).
        assert np.array_equal(ops.block_steps, local_solvers.block_rho(ops.W, 2))
    # ... and follow W when the window changes (another contact set: other blocks, another count).
    before = windowed.operators.block_steps
    windowed.set_window(windowed.initial_state(), 0.6)
    ops = windowed.operators
    assert ops.block_steps.size == ops.contact.contact_set.nc != before.size
    assert np.array_equal(ops.block_steps, local_solvers.block_rho(ops.W, 2))
    assert ops.kernel_data(4)[1] is ops.block_steps
    # The 2D contact-pattern cache has one row per increment and the compiled loop indexes it unchecked: a cache
    # made for a one-increment call (an evolving friction of the energy runs one increment a call) must not serve a
    # cycle of 8 (before: any cache of one row was reused, whatever the cycle's length)
    assert ops.kernel_data(1)[2].pattern.shape[0] == 1
    assert ops.kernel_data(8)[2].pattern.shape == (8, ops.contact.contact_set.nc)


def test_every_increment_of_a_cycle_is_checked():
    """The left foot sits 2e-3 above the right one. Preloaded to an approach of 1e-3, only the right foot (in the
    window) touches. The cycle raises the approach to 4e-3 and back to 1e-3: the left foot, outside the window,
    goes through the plane in the middle of the cycle only, so a check of the cycle's last increment alone would
    pass. The compiled loop and the increment-by-increment loop both raise at the first penetrating increment;
    with grow_window=True the cycle is solved again in a wider window and the left foot carries load mid-cycle."""
    lift, d0, d1 = 2e-3, 1e-3, 4e-3
    ramp = np.array([0.25, 0.5, 0.75, 1.0, 0.75, 0.5, 0.25, 0.0])
    path = dfr.CyclePath(normal=dfr.Displacement(d0 + (d1 - d0) * ramp),
                         tangential=dfr.Displacement(np.zeros(ramp.size)))
    steps = []
    for compiled in (True, False):
        problem, _, _ = feet_problem(window=0.2, mu=0.3, lift=lift,
                                     solver=dfr.LocalSolver(compiled_cycles=compiled))
        state, _ = problem.advance(problem.initial_state(), normal=d0)
        with pytest.raises(dfr.WindowError) as caught:
            problem.run_cycle(state, path)
        steps.append(caught.value.step)
        assert np.all(caught.value.positions[:, 0] < 0)       # the left foot's nodes
        assert problem.solve(state, normal=d0) is not None     # the cycle's last increment alone passes
    # The first increment whose approach passes the lift (plus what the right foot's load lifts the left one by).
    assert steps[0] == steps[1] and 1 < steps[0] < ramp.size

    problem, _, _ = feet_problem(window=0.2, mu=0.3, lift=lift, grow=True)
    state, _ = problem.advance(problem.initial_state(), normal=d0)
    with pytest.warns(RuntimeWarning, match="candidate window grown"):
        result = problem.run_cycle(state, path, keep=True)
    assert result.compiled
    state = problem.commit(state, result)
    left = problem.contact_fields(state)["coordinates"][:, 0] < 0
    forces = result.kept[0]                                     # (increments, 2 nc)
    assert forces[3, 0::2][left].sum() > 0                      # the peak approach: both feet
    assert forces[-1, 0::2][left].sum() == 0                    # back to d0: the right foot alone


@pytest.mark.parametrize("sliding", ["small", "finite"])
def test_two_bodies_outside_rows_are_the_displacement_s_gaps(sliding):
    """Two deformable bodies (the cylinder on an elastic flat): the outside nodes are paired with the flat as the
    candidates are (finite sliding: their reference pairing; the contacts' pairing changes as the bodies slide), and
    their gaps from the outside rows equal those of the displacement solved anew (K u = H^T r): an identity of
    linear elasticity, to rounding (1e-12 of the displacement). A window narrower than the contact raises."""
    scene = load_scene("cylinder-flat", ["geometry.contact_mesh_size=0.02", f"contact.sliding='{sliding}'"])
    model = build_scene_model(scene, MPI.COMM_WORLD)
    bcs = model.bcs + [bc for conditions in model.prescribed.values() for bc in conditions]

    def problem_of(window):
        contact = dfr.Contact(model.V, model.surface, model.obstacle, scene.contact.mu, bcs, window=window)
        return dfr.FrettingProblem(model.form, contact, model.bcs, loads=model.loads, prescribed=model.prescribed)

    narrow = problem_of(0.05)   # the Hertz half-width is 0.153 mm
    with pytest.raises(dfr.WindowError, match="window = 0.05"):
        narrow.solve(narrow.initial_state(), normal=dfr.Force(scene.loading.normal_force))

    problem = problem_of(0.45)
    state = problem.initial_state()
    for force in (0.5, 1.0):
        state, _ = problem.advance(state, normal=dfr.Force(force * scene.loading.normal_force))
    for stroke in (0.01, 0.03):   # gross slip: finite sliding pairs the contacts anew on the way
        state, _ = problem.advance(state, tangential=stroke)
    if sliding == "finite":
        assert problem.sliding.repairs > 0
    # (first: reading the state makes its pairing the problem's, with the outside rows of that pairing)
    u = problem.displacement(state).x.array   # serial: the local array is the global one
    out = problem.operators.outside
    D = problem.obstacle_translation(state.obstacle)
    rows = out.gaps(state.forces, state.obstacle, state.load_factors)[0]
    H = out.nodes.H[0::2]
    moved = H @ u[:H.shape[1]]
    normals = out.nodes.frames[:, 0, :]
    assert np.abs(rows - (out.nodes.gap0 + moved - normals @ D)).max() <= 1e-12 * np.abs(moved).max()
    assert rows.min() > 0   # the window holds the contact: every node outside it is open


def test_scene_runner_stops_a_block_truncated_by_its_window(tmp_path):
    """A scene's window with no refined zone to grow into (a rectangle: the window cannot grow): the block pressed
    flat on the plate with a window of 10 mm on its 50 mm face ran to the end before, carrying the preload on a
    fifth of the face; now the run stops at the first increment naming the window needed (the far corner lies
    50 mm from the window's centre, the near corner) and the scene key."""
    scene = load_scene("stromberg-block", ["geometry.nx=20", "geometry.ny=20", "contact.candidate_half_width=10.0",
                                           "loading.cycles=1", "output.xdmf=false", "output.plots=false"])
    with pytest.raises(SimulationError, match=r"increment 1 \(normal\): the contact reaches the edge of the candidate "
                                              r"window and beyond: .* the window needed is 55 mm; widen "
                                              r"contact.candidate_half_width \(now 10 mm\)"):
        run_scene(scene, tmp_path, quiet=True)
