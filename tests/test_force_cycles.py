"""Force-controlled cycles in the compiled loop (issue 26): a held normal force (and a cyclic tangential force)
found inside :func:`~dolfinx_fretting.cycling.run_force_increments` by the stepwise path's load control.

The reference is the stepwise path (``LocalSolver(compiled_cycles=False)``, increment by increment through
``increments._local_with_control``), and the prescribed force itself: every kept increment's total contact force
must meet its target to ``force_tol``.

Tolerance. The two paths run the same iteration from the same warm starts (the same trials and sweeps, counted
equal below; force control tries no cached contact pattern, whatever ``pattern_reuse``); they differ only in the
order of the sums forming q and the total force, so by rounding: measured 1.5e-13 of the forces' scale and 3.5e-11
of the wear's (a small difference of positions) on the rigid-plane block; 1e-10 holds both with room. (With the
pattern cache the answers moved by ~2e-8, the local tolerance's effect: measured, and why it is not used.)
"""

import dataclasses

import numpy as np
import pytest
from mpi4py import MPI  # before dolfinx: on the DOLFINx wheel it loads the MPI library DOLFINx needs

import ufl  # noqa: E402
from dolfinx import fem, mesh  # noqa: E402
from petsc4py import PETSc  # noqa: E402

import dolfinx_fretting as dfr  # noqa: E402
from dolfinx_fretting import _dolfinx as dfx  # noqa: E402
from dolfinx_fretting.loading import waveform  # noqa: E402
from support.finite_sliding import cylinder_on_flat, pressed, sliding_problem  # noqa: E402

E, NU, MU = 200000.0, 0.3, 0.3
FORCE_TOL = 1e-8      # LocalSolver's default force_tol


def _block_problem(solver: dfr.LocalSolver) -> dfr.FrettingProblem:
    """A 2 x 1 block (12 x 6 quadrilaterals), top clamped, its bottom on a rigid plane (mu 0.3), Archard wear."""
    msh = mesh.create_rectangle(MPI.COMM_WORLD, [[-1.0, 0.0], [1.0, 1.0]], [12, 6], mesh.CellType.quadrilateral)
    found = [mesh.locate_entities_boundary(msh, 1, where) for where in (
        lambda x: np.isclose(x[1], 0.0), lambda x: np.isclose(x[1], 1.0))]
    facets = np.concatenate(found)
    values = np.concatenate([np.full(f.size, i + 1, dtype=np.int32) for i, f in enumerate(found)])
    order = np.argsort(facets)
    tags = mesh.meshtags(msh, 1, facets[order], values[order])
    V = dfx.vector_space(msh, 1)
    lmbda, shear = E * NU / ((1 + NU) * (1 - 2 * NU)), E / (2 * (1 + NU))
    u, v = ufl.TrialFunction(V), ufl.TestFunction(V)
    eps = lambda w: ufl.sym(ufl.grad(w))  # noqa: E731
    form = ufl.inner(lmbda * ufl.tr(eps(u)) * ufl.Identity(2) + 2 * shear * eps(u), eps(v)) * ufl.dx
    top = fem.locate_dofs_topological(V, 1, tags.find(2))
    bcs = [fem.dirichletbc(np.zeros(2, dtype=PETSc.ScalarType), top, V)]
    contact = dfr.Contact(V, (tags, 1), dfr.RigidPlane([0.0, 0.0], [0.0, 1.0]), mu=MU, bcs=bcs)
    return dfr.FrettingProblem(form, contact, bcs, wear=dfr.Archard(1e-6), solver=solver)


def _cycles(problem, state, path, compiled: bool, cycles: int = 3):
    """``cycles`` cycles of ``path`` from ``state`` by one path; (last result, final state)."""
    problem.solver = dataclasses.replace(problem.solver, compiled_cycles=compiled)
    for _ in range(cycles):
        result = problem.run_cycle(state, path, keep=True)
        assert result.compiled == compiled
        state = problem.commit(state, result)
    return result, state


def _assert_same(problem, fast, slow, targets, rel):
    """Forces, slip, positions, wear, obstacle equal to ``rel`` of their scale; the targets met to force_tol."""
    (a, state_a), (b, state_b) = fast, slow
    for i, name in enumerate(("forces", "slip", "positions", "wear_gap")):
        # The slip is a difference of positions (in partial slip only their rounding): held to their scale.
        scale = np.abs(b.kept[2 if name == "slip" else i]).max()
        assert scale > 0, name
        assert np.abs(a.kept[i] - b.kept[i]).max() <= rel * scale, name
    assert np.abs(a.obstacle - b.obstacle).max() <= rel * np.abs(b.obstacle).max()
    assert np.abs(state_a.wear_gap - state_b.wear_gap).max() <= rel * state_b.wear_gap.max()
    assert np.array_equal(state_a.targets, state_b.targets)
    assert np.array_equal(state_a.force_controlled, state_b.force_controlled)
    contact = problem.operators.contact
    for j in range(a.kept[0].shape[0]):
        force = contact.obstacle_forces(a.kept[0][j])
        # The load control's own test: |F - target| <= force_tol times the largest target or first trial's force.
        controlled = state_a.force_controlled
        scale = max(np.abs(targets[j][controlled]).max(), np.abs(force).max())
        assert np.all(np.abs(force - targets[j])[controlled] <= 1.0001 * FORCE_TOL * scale), j


@pytest.mark.parametrize("reuse", [False, True])
def test_held_normal_force_on_a_rigid_plane(reuse):
    """A held normal force through gross-slip displacement cycles: the compiled loop equals the stepwise path."""
    problem = _block_problem(dfr.LocalSolver(tol=1e-12, pattern_reuse=reuse))
    state = problem.initial_state()
    state = problem.commit(state, problem.solve(state, normal=dfr.Force(2.0)))
    path = dfr.CyclePath.waveform(8, normal=dfr.Force(2.0), tangential=4e-4)
    fast = _cycles(problem, state, path, True)
    slow = _cycles(problem, state, path, False)
    targets = np.column_stack([np.full(8, 2.0), fast[0].obstacle[:, 1]])
    _assert_same(problem, fast, slow, targets, 1e-10)
    assert np.all(fast[0].records["load_solves"] >= 3)   # the force was searched (the first trial and a root find)
    for key in ("load_solves", "local_iterations"):   # the same iteration: the same trials and sweeps
        assert np.array_equal(fast[0].records[key], slow[0].records[key]), key
    # No per-increment LU factors are made for a loop that tries no pattern (sizes.estimate counts none for
    # force-controlled scenes): the cache is the one-row stand-in.
    assert problem.operators.kernel_data(None)[2].lu.shape[0] == 1
    problem.destroy()


def test_cyclic_tangential_force_on_a_rigid_plane():
    """Normal and tangential force both prescribed (partial slip, |Q| = 0.5 mu P): two controlled components,
    swept in turn inside the loop as by the stepwise path."""
    problem = _block_problem(dfr.LocalSolver(tol=1e-12, pattern_reuse=False))
    state = problem.initial_state()
    state = problem.commit(state, problem.solve(state, normal=dfr.Force(2.0)))
    path = dfr.CyclePath.waveform(8, normal=dfr.Force(2.0), tangential=dfr.Force(0.5 * MU * 2.0))
    fast = _cycles(problem, state, path, True)
    slow = _cycles(problem, state, path, False)
    targets = np.column_stack([np.full(8, 2.0), 0.5 * MU * 2.0 * waveform("triangular", 8)])
    _assert_same(problem, fast, slow, targets, 1e-10)
    for key in ("load_solves", "local_iterations"):
        assert np.array_equal(fast[0].records[key], slow[0].records[key]), key
    problem.destroy()


def test_unreachable_tangential_force_is_reported_and_leaves_no_state():
    """|Q| above mu P: both paths raise the same ConvergenceError (the physical reason, with the numbers of the last
    trial) at the same step, and the state is untouched."""
    problem = _block_problem(dfr.LocalSolver(pattern_reuse=False))
    state = problem.initial_state()
    state = problem.commit(state, problem.solve(state, normal=dfr.Force(2.0)))
    before = (state.forces.copy(), state.wear_gap.copy(), state.positions.copy(), state.obstacle.copy())
    path = dfr.CyclePath.waveform(8, normal=dfr.Force(2.0), tangential=dfr.Force(1.2 * MU * 2.0))
    failures = []
    for compiled in (True, False):
        problem.solver = dataclasses.replace(problem.solver, compiled_cycles=compiled)
        with pytest.raises(dfr.ConvergenceError, match="cannot be reached: it must stay below mu x P") as failed:
            problem.run_cycle(state, path)
        failures.append((failed.value.step, str(failed.value)))
        for kept, now in zip(before, (state.forces, state.wear_gap, state.positions, state.obstacle)):
            assert np.array_equal(kept, now)
    # mu P is crossed between the first (0.6 mu P) and second (1.2 mu P) increments of the waveform.
    assert failures[0] == failures[1] and failures[0][0] == 2
    problem.destroy()


def test_held_normal_force_on_an_elastic_flat():
    """McColl's set-up, CI-sized: the cylinder (R 6 mm) pressed by a held normal force on the deformable flat
    (fixed pairing), gross slip, both bodies wearing; the compiled loop equals the stepwise path."""
    model = cylinder_on_flat(mesh_size=0.04)
    problem = sliding_problem(model, "small", wear=dfr.Archard(k_slave=1.9e-6, k_master=2.9e-6))
    problem.solver = dfr.LocalSolver(tol=1e-12, pattern_reuse=False)
    state = pressed(problem)
    path = dfr.CyclePath.waveform(8, normal=dfr.Force(199.24), tangential=0.01)
    fast = _cycles(problem, state, path, True, cycles=2)
    slow = _cycles(problem, state, path, False, cycles=2)
    targets = np.column_stack([np.full(8, 199.24), fast[0].obstacle[:, 1]])
    _assert_same(problem, fast, slow, targets, 1e-10)
    problem.destroy()
