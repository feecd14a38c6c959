"""The plugin API refuses misuse instead of answering wrong (issue 27): a result is committed once, to the state it
was solved from; a checkpoint loads only into a problem with its contact parameters; non-finite inputs are refused
where they are given, named; a waveform reaches its amplitude.

The refusals are checked against the old behaviour (each of them answered before: a result committed twice added
its wear twice, a checkpoint loaded under another mu, a NaN target reached the first solve); the sequences that must
keep working (solve/commit chains, cut-backs, a new window, a checkpoint read back) are compared with the same
operations done by hand, and the wear against Archard's wear-energy identity.

Runs serially and under ``mpirun -n 2`` (every call is collective; the checkpoint path is rank 0's).
"""

import dataclasses
import json
import warnings

import numpy as np
import pytest
from mpi4py import MPI  # before dolfinx: on the DOLFINx wheel it loads the MPI library DOLFINx needs

import ufl  # noqa: E402
from dolfinx import fem, mesh  # noqa: E402
from petsc4py import PETSc  # noqa: E402
from support.blocks import elasticity, tagged  # noqa: E402

import dolfinx_fretting as dfr  # noqa: E402
from dolfinx_fretting import compat, loading  # noqa: E402

RADIUS = 2.0          # the block's bottom is the parabola y = x^2 / (2 RADIUS): the first contact is at x = 0
APPROACH, STROKE = 2e-3, 2e-3
MU, K = 0.5, 1e-5


def rounded_block(mu=MU, wear=dfr.Archard(K), plane=None, window=None, grow=False, loads=None, bc_value=0.0,
                  **kw):
    """A 2 x 1 block with a rounded bottom (marker 1) on a rigid plane y = 0, its top (marker 2) clamped (at
    ``bc_value`` along y); ``loads(V, tags)`` gives named linear forms."""
    msh = mesh.create_rectangle(MPI.COMM_WORLD, [[-1.0, 0.0], [1.0, 1.0]], [16, 8], mesh.CellType.quadrilateral)
    tags = tagged(msh, {1: lambda x: np.isclose(x[1], 0.0), 2: lambda x: np.isclose(x[1], 1.0),
                        3: lambda x: np.isclose(x[0], -1.0)})
    x = msh.geometry.x
    x[:, 1] += (1.0 - x[:, 1]) * x[:, 0] ** 2 / (2 * RADIUS)
    V = compat.vector_space(msh, 1)
    top = fem.locate_dofs_topological(V, 1, tags.find(2))
    bcs = [fem.dirichletbc(np.array([0.0, bc_value], dtype=PETSc.ScalarType), top, V)]
    contact = dfr.Contact(V, (tags, 1), plane or dfr.RigidPlane([0.0, 0.0], [0.0, 1.0]), mu=mu, bcs=bcs,
                          window=window, grow_window=grow)
    return dfr.FrettingProblem(elasticity(V), contact, bcs, wear=wear,
                               loads=loads(V, tags) if loads else None, **kw)


def pressed(problem):
    state = problem.initial_state()
    return problem.commit(state, problem.solve(state, normal=APPROACH))


def worn_area(problem, state):
    return float(state.wear_gap @ problem.contact.contact_set.tributary)


def shared_path(tmp_path, name):
    """Rank 0's temporary file (every rank reads the checkpoint rank 0 wrote)."""
    return MPI.COMM_WORLD.bcast(str(tmp_path / name), root=0)


# A result is committed once, to the state it was solved from -----------------------------------------------------
def test_an_increment_result_is_committed_once_to_its_own_state():
    """commit(commit(s, r), r) added r's wear and increment twice (the issue: 8.07e-7 -> 1.52e-6); now refused, as
    is r committed to the state before s. The one commit obeys Archard's wear-energy identity: worn area = k / mu x
    dissipated energy (every sliding contact wears k p |dx_t| while dissipating mu p |dx_t|), to rounding."""
    problem = rounded_block()
    start = pressed(problem)
    result = problem.solve(start, tangential=STROKE)
    once = problem.commit(start, result)
    assert once.increment == 2 and worn_area(problem, once) > 0
    assert worn_area(problem, once) == pytest.approx(K / MU * once.dissipated_energy, rel=1e-10)
    with pytest.raises(ValueError, match="solved from another state .* committed once"):
        problem.commit(once, result)
    with pytest.raises(ValueError, match="solved from another state"):
        problem.commit(problem.initial_state(), result)
    with pytest.raises(ValueError, match="carries no token"):
        problem.commit(start, dataclasses.replace(result, solved_from=None))
    problem.destroy()


@pytest.mark.parametrize("compiled", [True, False])
def test_a_cycle_result_is_committed_once_to_its_own_state(compiled):
    """A run_cycle result committed again returned its final state a second time (its increments counted again by
    a caller that adds them up); now refused, compiled or increment by increment. One cycle's wear obeys the
    wear-energy identity (to rounding)."""
    problem = rounded_block(solver=dfr.LocalSolver(compiled_cycles=compiled))
    start = pressed(problem)
    result = problem.run_cycle(start, dfr.CyclePath.waveform(8, tangential=STROKE))
    assert result.compiled == compiled
    after = problem.commit(start, result)
    assert after.increment == start.increment + 8
    assert worn_area(problem, after) == pytest.approx(K / MU * after.dissipated_energy, rel=1e-10)
    with pytest.raises(ValueError, match="cycle result was solved from another state"):
        problem.commit(after, result)
    with pytest.raises(ValueError, match="cycle result was solved from another state"):
        problem.commit(problem.initial_state(), result)
    problem.destroy()


def test_equal_states_share_their_token_and_every_commit_changes_it():
    """The token is a digest of the state's contents: two initial states are one state (a result of one commits to
    the other), and a commit always changes it (the increment counter), even one that changes nothing else."""
    problem = rounded_block()
    first, second = problem.initial_state(), problem.initial_state()
    assert first is not second and first.token == second.token
    # The plane moved away from the body: every gap open, forces and wear stay exactly 0.
    state = problem.commit(first, problem.solve(second, normal=-APPROACH))
    assert np.array_equal(state.forces, first.forces) and state.token != first.token
    problem.destroy()


def test_an_increment_that_changes_nothing_but_the_counter_is_committed_once():
    """With the plane away from the body (every gap open), an increment that moves nothing (the same approach)
    returns the state's own forces, positions and obstacle: only the increment counter tells the committed state
    from the one it was solved from, so the token must hold the counter (else the result commits twice, counting
    the increment twice). Each counter alone changes the token."""
    problem = rounded_block()
    away = problem.commit(problem.initial_state(), problem.solve(problem.initial_state(), normal=-APPROACH))
    result = problem.solve(away, normal=-APPROACH)   # the plane where it is (the approach is its position)
    state = problem.commit(away, result)
    assert np.array_equal(state.forces, away.forces) and np.array_equal(state.obstacle, away.obstacle)
    assert state.increment == away.increment + 1 and state.token != away.token
    with pytest.raises(ValueError, match="solved from another state"):
        problem.commit(state, result)
    for counter in ("increment", "local_iterations"):
        assert dataclasses.replace(away, **{counter: getattr(away, counter) + 1}).token != away.token, counter
    problem.destroy()


def test_cutbacks_commit_each_sub_increment_to_its_own_state():
    """advance halves a failed increment and commits each half to the state it was solved from: its state equals
    the two halves solved and committed by hand (the same local problems from the same warm starts; 1e-12 of the
    force scale covers a different summation order only)."""
    problem = rounded_block()
    start = pressed(problem)
    solve = problem.solve
    tries = []

    def failing_once(state, *args, **kwargs):   # the full increment fails once, as a Newton loop may
        tries.append(state.increment)
        if len(tries) == 1:
            raise dfr.ConvergenceError("planted failure of the full increment")
        return solve(state, *args, **kwargs)

    problem.solve = failing_once
    advanced, info = problem.advance(start, tangential=STROKE, max_cutbacks=1)
    del problem.solve
    assert info["cutbacks"] == 1 and tries == [1, 1, 2]
    half = problem.commit(start, problem.solve(start, tangential=0.5 * STROKE))
    by_hand = problem.commit(half, problem.solve(half, tangential=STROKE))
    scale = np.abs(by_hand.forces).max()
    assert np.abs(advanced.forces - by_hand.forces).max() <= 1e-12 * scale
    assert np.abs(advanced.wear_gap - by_hand.wear_gap).max() <= 1e-12 * by_hand.wear_gap.max()
    assert advanced.increment == 2 and by_hand.increment == 3   # the halves count as one increment of the path
    problem.destroy()


def test_a_state_carried_to_a_new_window_is_solved_from_and_committed():
    """set_window carries the state into a wider window: results solved from the carried state commit to it, and a
    result of the state before (another contact set) is refused on it. The carried state's next increment equals the
    one of a problem built with the wider window from the start (1e-8 of the force scale: two local solves to
    tol 1e-10)."""
    tight = dfr.LocalSolver(tol=1e-12)
    problem = rounded_block(window=0.4, solver=tight)
    start = pressed(problem)
    old = problem.solve(start, tangential=STROKE)
    carried = problem.set_window(start, 0.8)
    assert carried.forces.size > start.forces.size
    with pytest.raises(ValueError, match="solved from another state"):
        problem.commit(carried, old)
    after = problem.commit(carried, problem.solve(carried, tangential=STROKE))
    wide = rounded_block(window=0.8, solver=tight)
    wide_start = pressed(wide)
    reference = wide.commit(wide_start, wide.solve(wide_start, tangential=STROKE))
    assert np.abs(after.forces - reference.forces).max() <= 1e-8 * np.abs(reference.forces).max()
    problem.destroy()
    wide.destroy()


def test_a_loaded_checkpoint_is_solved_from_and_committed(tmp_path):
    """A state read back from its checkpoint holds the same token (its contents, bit for bit), so a result of either
    commits to either; the chain goes on as without the checkpoint (the same operations: equal to the last bit,
    checked to 1e-14 of the scale)."""
    problem = rounded_block()
    state = pressed(problem)
    path = shared_path(tmp_path, "state.npz")
    problem.save_state(state, path)
    back, _ = problem.load_state(path)
    assert back.token == state.token
    result = problem.solve(back, tangential=STROKE)
    after = problem.commit(back, result)
    direct = problem.commit(state, problem.solve(state, tangential=STROKE))
    assert np.abs(after.wear_gap - direct.wear_gap).max() <= 1e-14 * direct.wear_gap.max()
    with pytest.raises(ValueError, match="solved from another state"):
        problem.commit(after, result)
    problem.destroy()


# Checkpoints check the contact parameters --------------------------------------------------------------------------
CHANGES = {
    "mu": (dict(mu=0.3), r"mu: saved 0\.5, this problem's 0\.3"),
    "wear k": (dict(wear=dfr.Archard(2e-5)), r"wear law: saved Archard, k = 1e-05 .*this problem's Archard, k = 2e-05"),
    "no wear": (dict(wear=None), r"wear law: saved Archard, k = 1e-05 .*this problem's no wear"),
    "acceleration": (dict(wear=dfr.Archard(K, acceleration=10.0)),
                     r"wear law: saved .*x acceleration 1\.0, this problem's .*x acceleration 10\.0"),
    "plane moved": (dict(plane=dfr.RigidPlane([0.0, -1e-3], [0.0, 1.0])),
                    r"obstacle: saved RigidPlane point \[0\.0, 0\.0\] .*"
                    r"this problem's RigidPlane point \[0\.0, -0\.001\]"),
    "plane tilted": (dict(plane=dfr.RigidPlane([0.0, 0.0], [0.01, 1.0])), r"obstacle: saved .*normal \[0\.0, 1\.0\]"),
}


@pytest.fixture(scope="module")
def saved_checkpoint(tmp_path_factory):
    """A pressed state of the reference block (mu 0.5, Archard k = 1e-5, the plane y = 0), saved."""
    problem = rounded_block()
    state = pressed(problem)
    path = MPI.COMM_WORLD.bcast(str(tmp_path_factory.mktemp("checkpoint") / "state.npz"), root=0)
    problem.save_state(state, path)
    problem.destroy()
    return path, state


@pytest.mark.parametrize("change", list(CHANGES))
def test_load_state_refuses_other_contact_parameters(saved_checkpoint, change):
    """The checkpoint loaded silently into a problem with another mu (the issue); now each contact parameter that
    differs is refused, its saved and its new value named."""
    path, _ = saved_checkpoint
    kwargs, message = CHANGES[change]
    problem = rounded_block(**kwargs)
    with pytest.raises(ValueError, match="other contact parameters than this problem's: " + message):
        problem.load_state(path)
    problem.destroy()


def test_load_state_accepts_the_same_plane_given_by_another_point(saved_checkpoint):
    """A plane is its normal and its position along it: another point of the same plane changes no gap, and the
    state loads equal to the one saved."""
    path, state = saved_checkpoint
    problem = rounded_block(plane=dfr.RigidPlane([0.7, 0.0], [0.0, 2.0]))
    back, _ = problem.load_state(path)
    assert back.token == state.token
    problem.destroy()


def test_an_older_checkpoint_without_contact_parameters_still_loads(saved_checkpoint, tmp_path):
    """A checkpoint written before the contact parameters were saved loads as before (they are unchecked: the
    docstring and docs/api.md say so), even into a problem with another mu; rank 0 warns that they were not
    checked."""
    path, state = saved_checkpoint
    older = shared_path(tmp_path, "older.npz")
    if MPI.COMM_WORLD.rank == 0:
        with np.load(path) as npz:
            arrays = {k: npz[k] for k in npz.files}
        info = json.loads(str(arrays["state"]))
        del info["contact_parameters"]
        arrays["state"] = json.dumps(info)
        np.savez(older, **arrays)
    MPI.COMM_WORLD.barrier()
    problem = rounded_block(mu=0.3)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        back, _ = problem.load_state(older)
    assert np.array_equal(back.forces, state.forces)
    said = [str(w.message) for w in caught if "earlier release" in str(w.message)]
    if MPI.COMM_WORLD.rank == 0:
        assert len(said) == 1 and "contact parameters (mu, wear law, obstacle): they were not checked" in said[0]
    else:
        assert not said
    problem.destroy()


# Non-finite inputs are refused where they are given ---------------------------------------------------------------
NON_FINITE = {
    "plane point": (lambda: dfr.RigidPlane([np.nan, 0.0], [0.0, 1.0]), r"RigidPlane\.point = \[nan, 0\.0\]"),
    "plane normal": (lambda: dfr.RigidPlane([0.0, 0.0], [0.0, np.inf]), r"RigidPlane\.normal = \[0\.0, inf\]"),
    "zero normal": (lambda: dfr.RigidPlane([0.0, 0.0], [0.0, 0.0]), r"RigidPlane\.normal = \[0\.0, 0\.0\]: .*non-zero"),
    "Archard k": (lambda: dfr.Archard(np.nan), r"Archard\.k = nan"),
    "Archard k_master": (lambda: dfr.Archard(k_slave=1e-5, k_master=np.inf), r"Archard\.k_master = inf"),
    "Force": (lambda: dfr.Force(np.nan), r"Force\.value = nan"),
    "Displacement": (lambda: dfr.Displacement([0.0, np.nan]), r"Displacement\.value = \[0\.0, nan\].*entry \(1,\)"),
    "waveform tangential": (lambda: dfr.CyclePath.waveform(8, tangential=np.nan),
                            r"CyclePath\.waveform: tangential = nan"),
    "waveform normal": (lambda: dfr.CyclePath.waveform(8, normal=np.inf, tangential=1.0),
                        r"CyclePath\.waveform: normal = inf"),
    "waveform load": (lambda: dfr.CyclePath.waveform(8, loads={"push": np.nan}),
                      r"CyclePath\.waveform: loads\['push'\] = nan"),
    "path load": (lambda: dfr.CyclePath(loads={"push": [0.0, np.nan, 0.0, 0.0]}),
                  r"CyclePath\.loads\['push'\] = \[0\.0, nan, 0\.0, 0\.0\]"),
}


@pytest.mark.parametrize("case", list(NON_FINITE))
def test_non_finite_values_are_refused_where_given(case):
    """Each refused by its constructor, naming the argument and its value (before: Force(nan), Displacement(nan)
    and a CyclePath's NaN amplitudes reached the first solve)."""
    make, message = NON_FINITE[case]
    with pytest.raises(ValueError, match=message):
        make()


def _loads_with(value):
    def loads(V, tags):
        traction = fem.Constant(V.mesh, PETSc.ScalarType((value, 0.0)))
        ds = ufl.Measure("ds", domain=V.mesh, subdomain_data=tags)
        return {"side": ufl.inner(traction, ufl.TestFunction(V)) * ds(3)}
    return loads


@pytest.mark.parametrize("value", [np.nan, np.inf])
def test_a_non_finite_load_is_refused_by_the_problem(value):
    """A NaN in a named load's form reached the first solve, which said "q: contains non-finite values" and named
    no load; now the problem refuses it when built, naming the load (before the factorisation)."""
    with pytest.raises(ValueError, match=r"loads\['side'\] is not finite"):
        rounded_block(loads=_loads_with(value))


def test_a_non_finite_dirichlet_value_is_refused_by_the_problem():
    with pytest.raises(ValueError, match=r"bcs \(their Dirichlet values\) is not finite"):
        rounded_block(bc_value=np.nan)


def test_a_finite_load_is_applied_and_a_non_finite_factor_refused():
    """The same form with a finite value builds, and a NaN factor is refused at solve, named."""
    problem = rounded_block(loads=_loads_with(10.0))
    with pytest.raises(ValueError, match=r"loads\['side'\] = nan"):
        problem.solve(problem.initial_state(), normal=APPROACH, loads={"side": np.nan})
    problem.destroy()


# Waveforms reach their amplitude -----------------------------------------------------------------------------------
@pytest.mark.parametrize("increments", [1, 2, 3, 5, 6, 10, 42])
def test_a_waveform_that_misses_its_amplitude_is_refused(increments):
    """waveform(3) turned at 0.67 of the amplitude (n = 10: 0.8): the peaks at 1/4 and 3/4 of the cycle are
    increment ends only for a multiple of 4, which the message asks for."""
    with pytest.raises(ValueError, match=f"increments per cycle = {increments}: expected a multiple of 4, at least 4"):
        dfr.CyclePath.waveform(increments, tangential=1.0)


@pytest.mark.parametrize("shape", ["triangular", "sinusoidal"])
@pytest.mark.parametrize("increments", [4, 8, 12, 80])
def test_a_waveform_reaches_plus_and_minus_its_amplitude(shape, increments):
    """Peaks exactly at +-A (triangular: interpolation at its knots is exact; sinusoidal: sin(pi/2) rounds to 1;
    1e-15 covers the last bit) at increments n/4 and 3n/4, and ends at 0."""
    wave = loading.waveform(shape, increments)
    assert wave[increments // 4 - 1] == pytest.approx(1.0, abs=1e-15)
    assert wave[3 * increments // 4 - 1] == pytest.approx(-1.0, abs=1e-15)
    assert wave[-1] == 0.0 and np.abs(wave).max() == pytest.approx(1.0, abs=1e-15)
    path = dfr.CyclePath.waveform(increments, shape, tangential=2.5)
    assert path.tangential.value.max() == pytest.approx(2.5, rel=1e-15)
