"""The plugin API's state between increments on small models the test owns: named loads, prescribed Dirichlet
data, checkpoints of force control, a new window's carried state and the record of a cut-back increment.

References are independent of what they check: superposition (two loads at factor 1 are their sum as one load),
a rigid translation (a body held only by a lowered face moves with it), the state before a checkpoint and before a
window change (the same nodes, the same configuration), and the worn area measured on the states themselves.
"""

import numpy as np
import pytest
from mpi4py import MPI  # before dolfinx: on the DOLFINx wheel it loads the MPI library DOLFINx needs

import ufl  # noqa: E402
from dolfinx import fem, mesh  # noqa: E402
from petsc4py import PETSc  # noqa: E402

import dolfinx_fretting as dfr  # noqa: E402
from dolfinx_fretting import _dolfinx as dfx  # noqa: E402

E, NU = 200000.0, 0.3
LMBDA, MU_LAME = E * NU / ((1 + NU) * (1 - 2 * NU)), E / (2 * (1 + NU))


def elasticity(V):
    u, v = ufl.TrialFunction(V), ufl.TestFunction(V)
    eps = lambda w: ufl.sym(ufl.grad(w))  # noqa: E731
    sigma = LMBDA * ufl.tr(eps(u)) * ufl.Identity(2) + 2 * MU_LAME * eps(u)
    return ufl.inner(sigma, eps(v)) * ufl.dx


def block(nx=12, ny=6):
    """A 2 x 1 rectangle with its bottom at y = 0; facet tags 1 bottom, 2 top, 3 left, 4 right."""
    msh = mesh.create_rectangle(MPI.COMM_WORLD, [[-1.0, 0.0], [1.0, 1.0]], [nx, ny], mesh.CellType.quadrilateral)
    found = [mesh.locate_entities_boundary(msh, 1, f) for f in (
        lambda x: np.isclose(x[1], 0.0), lambda x: np.isclose(x[1], 1.0),
        lambda x: np.isclose(x[0], -1.0), lambda x: np.isclose(x[0], 1.0))]
    facets = np.concatenate(found)
    values = np.concatenate([np.full(f.size, i + 1, dtype=np.int32) for i, f in enumerate(found)])
    order = np.argsort(facets)
    return msh, mesh.meshtags(msh, 1, facets[order], values[order]), dfx.vector_space(msh, 1)


def clamped_top(V, tags):
    dofs = fem.locate_dofs_topological(V, 1, tags.find(2))
    return fem.dirichletbc(np.zeros(2, dtype=PETSc.ScalarType), dofs, V)


def traction(V, tags, marker, value):
    ds = ufl.Measure("ds", domain=V.mesh, subdomain_data=tags)
    return ufl.inner(fem.Constant(V.mesh, PETSc.ScalarType(value)), ufl.TestFunction(V)) * ds(marker)


def problem_on(plane=None, mu=0.3, loads=None, wear=None, window=None):
    msh, tags, V = block()
    bcs = [clamped_top(V, tags)]
    plane = plane or dfr.RigidPlane([0.0, 0.0], [0.0, 1.0])
    contact = dfr.Contact(V, (tags, 1), plane, mu=mu, bcs=bcs, window=window)
    forms = None if loads is None else {name: traction(V, tags, *spec) if isinstance(spec, tuple)
                                        else sum(traction(V, tags, *s) for s in spec) for name, spec in loads.items()}
    return dfr.FrettingProblem(elasticity(V), contact, bcs, wear=wear, loads=forms)


@pytest.mark.skipif(MPI.COMM_WORLD.size > 1, reason="serial models")
def test_two_named_loads_are_their_sum_as_one_load():
    """Superposition: a pressed block under two named side tractions at factors (0.7, 1.3) has the contact forces
    of the same block under one load, the tractions' weighted sum, at factor 1 (two factorisations of the same K
    and two local solves to 1e-10: 1e-8 of the largest force). The second load matters: without it the forces
    differ by more than 1 %."""
    left, right = (3, (30.0, -40.0)), (4, (-10.0, -60.0))
    two = problem_on(loads={"left": left, "right": right})
    one = problem_on(loads={"both": [(3, (21.0, -28.0)), (4, (-13.0, -78.0))]})
    try:
        assert two.load_names == ["left", "right"]
        s = two.solve(two.initial_state(), normal=2e-4, loads={"left": 0.7, "right": 1.3})
        r = one.solve(one.initial_state(), normal=2e-4, loads={"both": 1.0})
        scale = np.abs(r.forces).max()
        assert np.abs(s.forces - r.forces).max() <= 1e-8 * scale
        alone = two.solve(two.initial_state(), normal=2e-4, loads={"left": 0.7, "right": 0.0})
        assert np.abs(alone.forces - r.forces).max() > 1e-2 * scale
    finally:
        two.destroy()
        one.destroy()


@pytest.mark.skipif(MPI.COMM_WORLD.size > 1, reason="serial model")
def test_prescribed_dirichlet_data_move_the_body_with_them():
    """A block held only by its top, lowered by delta as prescribed Dirichlet data, with the plane far below (no
    contact): the block translates rigidly, u = (0, -delta) at every node, the lowered top included (rounding of
    one solve: 1e-10 of delta)."""
    msh, tags, V = block()
    delta = 3e-4
    lowered = fem.Function(V)
    lowered.x.array.reshape(-1, 2)[:, 1] = -delta
    moving_top = fem.dirichletbc(lowered, fem.locate_dofs_topological(V, 1, tags.find(2)))
    contact = dfr.Contact(V, (tags, 1), dfr.RigidPlane([0.0, -1.0], [0.0, 1.0]), mu=0.3, bcs=[moving_top])
    problem = dfr.FrettingProblem(elasticity(V), contact, [], prescribed={"lower": [moving_top]})
    try:
        state = problem.commit(problem.initial_state(), problem.solve(problem.initial_state(), loads={"lower": 1.0}))
        assert not np.any(state.forces)
        u = problem.displacement(state).x.array.reshape(-1, 2)
        assert np.abs(u - np.array([0.0, -delta])).max() <= 1e-10 * delta
    finally:
        problem.destroy()


@pytest.mark.skipif(MPI.COMM_WORLD.size > 1, reason="serial model")
def test_a_force_controlled_checkpoint_keeps_its_targets(tmp_path):
    """A state under normal and tangential force control, saved and loaded, keeps its force targets and the
    components they control; the next increment from the loaded state (the tangential force changed, the normal
    force kept at its target) equals the one from the state itself (the same arrays: 1e-12 of the forces) and
    still carries P."""
    problem = problem_on(mu=0.4)
    try:
        P, Q = 300.0, 0.3 * 0.4 * 300.0
        state = problem.initial_state()
        for f in (0.5, 1.0):
            state = problem.commit(state, problem.solve(state, normal=dfr.Force(f * P), tangential=dfr.Force(0.0)))
        state = problem.commit(state, problem.solve(state, tangential=dfr.Force(Q)))
        problem.save_state(state, tmp_path / "state.npz")
        loaded, _ = problem.load_state(tmp_path / "state.npz")
        assert np.array_equal(loaded.targets, state.targets) and loaded.targets[0] == pytest.approx(P, rel=1e-14)
        assert np.array_equal(loaded.force_controlled, state.force_controlled)
        after = problem.commit(loaded, problem.solve(loaded, tangential=dfr.Force(-Q)))
        expected = problem.commit(state, problem.solve(state, tangential=dfr.Force(-Q)))
        assert np.abs(after.forces - expected.forces).max() <= 1e-12 * np.abs(expected.forces).max()
        assert problem.total_force(after)[0] == pytest.approx(P, rel=1e-8)   # force_tol 1e-8
    finally:
        problem.destroy()


@pytest.mark.skipif(MPI.COMM_WORLD.size > 1, reason="serial model")
def test_set_window_carries_the_state_by_node():
    """A block pressed on a tilted plane touches near its left corner, inside a window of 0.6; after slip and
    wear the window is widened to 1.5: every node of the old window keeps its force, slip and wear gap (the same
    global node), the new candidates start open, unworn and unloaded, and the relative positions of the old nodes
    are those of the committed configuration (the contact forces are the same: 1e-9 of the largest).
    The new candidates' normal positions are their gaps, > 0."""
    plane = dfr.RigidPlane([-1.0, 0.0], [0.01, 1.0])          # rises to the right: touches the left corner first
    problem = problem_on(plane=plane, mu=0.3, wear=dfr.Archard(1e-6), window=0.6)
    try:
        state = problem.initial_state()
        for normal in (2e-3, 3e-3):
            state = problem.commit(state, problem.solve(state, normal=normal))
        for d in (2e-4, 4e-4):
            before, state = state, problem.commit(state, problem.solve(state, tangential=d))
        old = problem.contact.contact_set
        assert old.nc < 12 and np.count_nonzero(state.forces[0::2]) >= 2 and np.any(state.wear_gap > 0)
        wider = problem.set_window(state, 1.5)
        new = problem.contact.contact_set
        assert new.nc > old.nc
        where = {int(g): i for i, g in enumerate(new.global_nodes)}
        kept = np.array([where[int(g)] for g in old.global_nodes])
        assert state.forces[0] > 0                               # the old window's first contact is loaded
        fresh = np.setdiff1d(np.arange(new.nc), kept)
        as_pairs = lambda v: v.reshape(-1, 2)  # noqa: E731
        for name in ("forces", "slip"):
            assert np.array_equal(as_pairs(getattr(wider, name))[kept], as_pairs(getattr(state, name))), name
            assert not np.any(as_pairs(getattr(wider, name))[fresh]), name
        assert np.array_equal(wider.wear_gap[kept], state.wear_gap) and not np.any(wider.wear_gap[fresh])
        # the committed positions are the last solve's; the wear committed after it opens the normal rows by its
        # increment (what y = W r + q_abs gives with the committed wear gap); the tangential rows, where the next
        # increment's slip is measured from, are the same
        scale = np.abs(state.positions).max()
        expected = as_pairs(state.positions) + np.column_stack([state.wear_gap - before.wear_gap, np.zeros(old.nc)])
        assert np.abs(as_pairs(wider.positions)[kept] - expected).max() <= 1e-9 * scale
        assert (as_pairs(wider.positions)[fresh, 0] > 0).all()
    finally:
        problem.destroy()


@pytest.mark.skipif(MPI.COMM_WORLD.size > 1, reason="serial model")
def test_cut_back_increments_keep_their_wear_in_the_record():
    """An increment whose first try fails (a ConvergenceError, as a hard Newton step would raise) is cut back
    and solved in two halves; its record's wear and energy are the two halves' together: the wear equals the
    worn area the state gained (1e-12), as does an increment solved at once, and the halves both slide (gross
    slip), so the last half alone would be about half of it."""
    problem = problem_on(mu=0.3, wear=dfr.Archard(1e-6))
    try:
        state = problem.initial_state()
        state = problem.commit(state, problem.solve(state, normal=2e-4))
        solve, calls = problem.solve, []

        def failing_once(*args, **kwargs):
            calls.append(kwargs)
            if len(calls) == 1:
                raise dfr.ConvergenceError("planted failure of the first try")
            return solve(*args, **kwargs)

        problem.solve = failing_once
        new, info = problem.advance(state, tangential=2e-3, max_cutbacks=2)
        assert info["cutbacks"] == 1 and len(calls) == 3
        gained = problem.worn_measure(new) - problem.worn_measure(state)
        assert gained > 0
        assert new.record["wear_area_increment"] == pytest.approx(gained, rel=1e-12)
        assert new.record["wear_area"] == pytest.approx(problem.worn_measure(new), rel=1e-12)
        # Archard's identity (eq. 5): in gross slip the worn area is (k / mu) x the dissipated energy
        assert new.record["wear_area_increment"] == pytest.approx(1e-6 / 0.3 * new.record["dissipated_energy"],
                                                                  rel=1e-9)
    finally:
        problem.solve = solve
        problem.destroy()


@pytest.mark.skipif(MPI.COMM_WORLD.size > 1, reason="serial model")
def test_a_named_load_is_its_own_response_beside_prescribed_data():
    """A block held only by its top, which prescribed data lower by delta, with the plane far below (no contact),
    under a named side traction: superposition of the two responses. With the data at factor 0 the displacement
    is plain DOLFINx's solution of K u = f_side with the top held at zero; with both at factor 1 it is that plus
    the rigid translation (0, -delta) (one solve each: 1e-10 of the largest). A load's vector must not carry the
    data's lifting (that would add the translation times the load's factor)."""
    msh, tags, V = block()
    delta = 3e-4
    top_dofs = fem.locate_dofs_topological(V, 1, tags.find(2))
    lowered = fem.Function(V)
    lowered.x.array.reshape(-1, 2)[:, 1] = -delta
    moving_top = fem.dirichletbc(lowered, top_dofs)
    contact = dfr.Contact(V, (tags, 1), dfr.RigidPlane([0.0, -1.0], [0.0, 1.0]), mu=0.3, bcs=[moving_top])
    side = traction(V, tags, 4, (-20.0, -30.0))
    problem = dfr.FrettingProblem(elasticity(V), contact, [], prescribed={"lower": [moving_top]},
                                  loads={"side": side})
    try:
        u_side = dfx.solve_linear(elasticity(V), side, [clamped_top(V, tags)], {"ksp_type": "preonly", "pc_type": "lu"})
        reference = u_side.x.array.reshape(-1, 2)
        scale = np.abs(reference).max() + delta
        for lower in (0.0, 1.0):
            start = problem.initial_state()
            state = problem.commit(start, problem.solve(start, loads={"lower": lower, "side": 1.0}))
            assert not np.any(state.forces)
            u = problem.displacement(state).x.array.reshape(-1, 2)
            assert np.abs(u - (reference + np.array([0.0, -lower * delta]))).max() <= 1e-10 * scale, lower
    finally:
        problem.destroy()
