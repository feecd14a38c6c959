"""The gross-slip predictor of the 3D working-set solve (``local_solvers._gross_slip_predictor``, on by default in
``local_solvers.solve`` and the compiled cycle loops).

References independent of the predictor: the natural-map error recomputed on the whole problem
(:func:`natural_map_error`), the sweeps alone (``gross_slip_predictor=False``), and, for like half-spaces (no
normal-tangential coupling in W), the frictionless normal forces: in gross slip every loaded contact slides, and
with ``W_nt = 0`` the normal rows do not see the tangential forces, so the normal forces are those of the
frictionless problem (Johnson, Contact Mechanics, section 7.1: like materials uncouple the normal and tangential
problems), and each tangential force is ``mu r_n`` against the slip.
"""

import numpy as np
import pytest
from support.local_problems import cycle_q, half_space, sphere_flat_cycle, sphere_flat_q

from dolfinx_fretting import local_solvers as ls
from dolfinx_fretting.local_solvers import natural_map_error, solve

TOL = 1e-10  # the scenes' solver.local_tol
MU = 0.5
# Two answers that both meet the natural-map tolerance 1e-10 are different points within it: they differ by up to
# 1.8e-8 of the largest force over the sphere's half-space cycles at 1024-2025 contacts, mu 0.8
# (benchmarks/results/gross_slip.md), 2.4e-9 on this module's 256-contact problem at mu 0.5 (measured); 1e-7 leaves
# a margin of 5 over the largest and still fails a predictor off by a sign or a missing term (those miss by 1e-2 and
# more, or never converge).
SAME_ANSWER = 1e-7


@pytest.fixture(scope="module")
def sphere_flat():
    W, xy = half_space()
    assert np.array_equal(W, W.T)  # exactly symmetric, as the package's W (the predictor factors W_nn)
    return W, xy


def _gross_slip_increment(W, xy):
    """An increment of gross slip from the one before (the whole contact slides, at slip 0.6 > mu's reach)."""
    r_before = solve(W, sphere_flat_q(xy, 40.0, 0.5, 0.6), MU, 3, tol=TOL, gross_slip_predictor=False).r
    return sphere_flat_q(xy, 40.0, 0.5, 1.2), r_before


def test_gross_slip_answered_by_the_predictor(sphere_flat):
    """A gross-slip increment: the predictor answers alone (no sweep) within the tolerance on the whole problem;
    its normal forces are the frictionless problem's and its tangential forces mu r_n against the slip (like
    half-spaces, module docstring); the sweeps alone give the same answer to the tolerance's effect."""
    W, xy = sphere_flat
    q, r0 = _gross_slip_increment(W, xy)
    result = solve(W, q, MU, 3, tol=TOL, r0=r0)
    assert result.converged and result.predictor_steps >= 1 and result.sweeps == 0, result.message
    assert result.iterations == result.predictor_steps
    assert natural_map_error(W, q, result.r, MU, 3) < TOL
    normal, tangential = result.r[0::3], result.r.reshape(-1, 3)[:, 1:]
    loaded = normal > 0
    assert loaded.sum() > 50  # a contact zone, not a handful of nodes
    frictionless = solve(W, q, 0.0, 3, tol=TOL).r[0::3]
    scale = normal.max()
    assert np.abs(normal - frictionless).max() <= SAME_ANSWER * scale
    slip = result.x.reshape(-1, 3)[loaded, 1:]
    against = -MU * normal[loaded, None] * slip / np.linalg.norm(slip, axis=1)[:, None]
    assert np.abs(tangential[loaded] - against).max() <= SAME_ANSWER * scale
    sweeps = solve(W, q, MU, 3, tol=TOL, r0=r0, gross_slip_predictor=False)
    assert sweeps.converged and sweeps.predictor_steps == 0
    assert np.abs(result.r - sweeps.r).max() <= SAME_ANSWER * scale
    # The steps update x from a float32 copy of W_LL; the answer's x is formed exactly (float64, from W): the bits
    # of W r + q summed row by row.
    exact = np.empty(q.size)
    ls._recompute_x_by_rows(W, q, result.r, exact, np.arange(q.size))
    assert np.array_equal(result.x, exact)
    # Its stops are judged on an exact x, so the float32 updates' rounding does not bound what it reaches: at 1e-13,
    # near float64's reach, it still answers alone (judged on the updates' x it stops at 6 steps and sweeps).
    tight = solve(W, q, MU, 3, tol=1e-13, r0=r0)
    assert tight.converged and tight.sweeps == 0 and natural_map_error(W, q, tight.r, MU, 3) < 1e-13


def test_a_large_change_of_the_forces(sphere_flat):
    """The load moved outward (a worn centre: its gaps raised by up to 0.05-0.2 of the approach) from the increment
    before: the float32 updates' offset grows with the change of r since x was last formed exactly and can hide the
    last of the error (a claim of convergence the exact x denies); the steps then go on from the exact x, and the
    predictor still answers alone at 0.05 and 0.1 (judged on the updated x it stopped and swept). At 0.2 a contact
    of the rim closes during the steps (its x is not updated by them: seen at the first exact x) and the sweeps
    finish. Every answer within the tolerance on the whole problem, its reported error the recomputed one."""
    W, xy = sphere_flat
    r0 = solve(W, sphere_flat_q(xy, 40.0, 0.5, 0.6), MU, 3, tol=TOL, gross_slip_predictor=False).r
    squared = (xy ** 2).sum(axis=1)
    contact = squared[r0[0::3] > 0].max()
    for wear, alone in ((0.05, True), (0.1, True), (0.2, False)):
        q = sphere_flat_q(xy, 40.0, 0.5, 1.2)
        q[0::3] += wear * np.exp(-squared / (0.3 * contact))
        result = solve(W, q, MU, 3, tol=TOL, r0=r0)
        assert result.converged and result.predictor_steps > 0 and (result.sweeps == 0) == alone, result.message
        error = natural_map_error(W, q, result.r, MU, 3)
        assert error < TOL and result.error == pytest.approx(error, rel=1e-6)


def test_held_factor_and_block_follow_the_loaded_set(sphere_flat):
    """A solve on the held working set whose loaded contacts are not the held factor's (warm starts with the rim's
    forces removed beyond 0.8 and then 0.9 of the contact radius: the same set, the rim's gaps closed, more contacts
    loaded) makes and holds the factor and the float32 loaded block of its own loaded contacts beside the held
    block: L L^T = W_LL's normal rows and columns, the float32 block W_LL's values."""
    W, xy = sphere_flat
    W = W.copy()
    steps = ls.block_rho(W, 3)
    q = sphere_flat_q(xy, 40.0, 0.5, 1.2)
    answer = solve(W, q, MU, 3, tol=TOL, block_steps=steps).r
    radius = np.hypot(*xy.T)
    contact = radius[answer[0::3] > 0].max()
    inner = [np.where(np.repeat(radius > share * contact, 3), 0.0, answer) for share in (0.8, 0.9)]
    first = solve(W, q, MU, 3, tol=TOL, r0=inner[0], block_steps=steps)
    second = solve(W, q, MU, 3, tol=TOL, r0=inner[1], block_steps=steps)
    held = ls._held[0]
    loaded = np.flatnonzero(inner[1][0::3] > 0)
    assert first.working_set == second.working_set and second.block_held and second.predictor_steps > 0
    assert np.count_nonzero(inner[0][0::3] > 0) < loaded.size and np.array_equal(held.loaded, loaded)
    normal = W[np.ix_(3 * loaded, 3 * loaded)]
    assert np.allclose(held.factor @ held.factor.T, normal, rtol=0, atol=1e-12 * np.abs(normal).max())
    rows = np.repeat(3 * loaded, 3) + np.tile(np.arange(3), loaded.size)
    assert np.array_equal(held.loaded_block32, W[np.ix_(rows, rows)].T.astype(np.float32))


def test_an_output_handed_on_has_its_exact_x(sphere_flat):
    """Stopped by max_steps after an output that halved the error but decided nothing (its x from the float32
    updates), the kernel hands that output on with x formed exactly from ``Wa`` (float64), the bits the sweeps
    start from; the float32 updates alone are off by rounding on the loaded rows (7e-12 of the largest x here)."""
    W, xy = sphere_flat
    q, r0 = _gross_slip_increment(W, xy)
    Wa = np.ascontiguousarray(W.T)   # the working set = every contact
    nc = xy.shape[0]
    rho = ls.block_rho(W, 3)
    r, x, stats = r0.copy(), W @ r0 + q, np.zeros(3, dtype=np.int64)
    outcome, err, steps, change, key, factor, loaded_block32 = ls._gross_slip_predictor(
        Wa, q, np.full(nc, MU), rho, ls._force_scale(q, np.full(nc, MU), rho, 3), np.arange(nc), r, x, TOL, 1,
        *ls._nothing_held()[3:], stats)
    assert (outcome, steps) == (0, 1) and change > 0   # one output kept, short of the tolerance
    exact = np.empty(q.size)
    empty_i = np.zeros(1, dtype=np.int64)
    ls._recompute_x(Wa, empty_i, empty_i, np.zeros(1), False, q, r, exact)
    assert np.array_equal(x, exact)
    moved = W @ r0 + q
    positions = np.flatnonzero(np.repeat(r0[0::3] > 0, 3))
    ls._add_moves32(loaded_block32, positions, (r - r0)[positions], moved)
    off = np.abs(moved - exact)[positions].max()   # the loaded rows (the only ones the updates move)
    assert 0 < off < 1e-9 * np.abs(exact).max()


def test_partial_slip_left_to_the_sweeps(sphere_flat):
    """Partial slip (Cattaneo-Mindlin: a small tangential displacement, the contact sticks but for an annulus),
    started from the gross-slip answer: the predictor, which lets every loaded contact slide, stops after a step
    or two, and the sweeps answer from its best iterate: within the tolerance on the whole problem, the sweeps'
    own answer to the tolerance's effect."""
    W, xy = sphere_flat
    r0 = solve(W, sphere_flat_q(xy, 40.0, 0.5, 1.2), MU, 3, tol=TOL).r
    q = sphere_flat_q(xy, 40.0, 0.5, 0.05)
    result = solve(W, q, MU, 3, tol=TOL, r0=r0)
    states = ls.contact_states(result.r, result.x, MU, 3)
    assert np.sum(states == ls.STICK) > 10  # partial slip indeed
    assert result.converged and result.predictor_steps == 1 and result.sweeps > 0, result.message
    assert natural_map_error(W, q, result.r, MU, 3) < TOL
    # Its one output did not halve the error, so the sweeps started from the start: the sweeps' own answer.
    sweeps = solve(W, q, MU, 3, tol=TOL, r0=r0, gross_slip_predictor=False)
    assert np.array_equal(result.r, sweeps.r) and result.sweeps == sweeps.sweeps


def test_not_tried_on_a_W_it_cannot_factor(sphere_flat):
    """A W whose normal block is not symmetric (the Cholesky factor would read one triangle of it): the predictor
    takes no step, the sweeps answer as with it off, to the last bit. A normal block that is not positive definite
    (here: -W's): the kernel takes no step, makes no factor and leaves r, x as they were."""
    W, xy = sphere_flat
    q, r0 = _gross_slip_increment(W, xy)
    skewed = W.copy()
    skewed[0::3, 0::3] += 1e-3 * np.triu(W[0::3, 0::3], 1)  # no longer symmetric
    assert np.linalg.eigvalsh(skewed + skewed.T).min() > 0  # still positive definite: only the symmetry is missing
    on = solve(skewed, q, MU, 3, tol=TOL, r0=r0)
    off = solve(skewed, q, MU, 3, tol=TOL, r0=r0, gross_slip_predictor=False)
    assert on.converged and on.predictor_steps == 0 and np.array_equal(on.r, off.r)
    nc = xy.shape[0]
    negative = np.ascontiguousarray(-W)
    r, x, stats = r0.copy(), negative @ r0 + q, np.zeros(3, dtype=np.int64)
    start_r, start_x = r.copy(), x.copy()
    outcome, err, steps, change, key, factor, loaded_block32 = ls._gross_slip_predictor(
        negative, q, np.full(nc, MU), ls.block_rho(W, 3), 1.0, np.arange(nc), r, x, TOL, ls.PREDICTOR_STEPS,
        *ls._nothing_held()[3:], stats)
    assert (outcome, steps, key.size, factor.size, loaded_block32.size) == (0, 0, 0, 0, 0) and not stats.any()
    assert np.array_equal(r, start_r) and np.array_equal(x, start_x)


def test_two_dimensional_problems_are_the_sweeps(sphere_flat):
    """The predictor is 3D only (2D loops have their exact pattern solves): a 2D problem (the sphere's normal and
    first tangential rows) gets the sweeps' answer to the bit with it on."""
    W, xy = sphere_flat
    q, r0 = _gross_slip_increment(W, xy)
    keep = np.sort(np.concatenate([np.arange(0, W.shape[0], 3), np.arange(1, W.shape[0], 3)]))
    W2 = np.ascontiguousarray(W[np.ix_(keep, keep)])
    on = solve(W2, q[keep], MU, 2, tol=TOL, r0=r0[keep])
    off = solve(W2, q[keep], MU, 2, tol=TOL, r0=r0[keep], gross_slip_predictor=False)
    assert on.converged and on.predictor_steps == 0 and np.array_equal(on.r, off.r)


def test_max_iter_counts_the_steps(sphere_flat):
    """The predictor's steps count against max_iter: fewer iterations allowed than its steps need, the solve stops
    there, not converged, after at most max_iter iterations (and says so); with enough, it converges."""
    W, xy = sphere_flat
    q, r0 = _gross_slip_increment(W, xy)
    needed = solve(W, q, MU, 3, tol=TOL, r0=r0).predictor_steps
    assert needed >= 3
    short = solve(W, q, MU, 3, tol=TOL, r0=r0, max_iter=needed - 1)
    assert not short.converged and short.iterations <= needed - 1 and "not converged" in short.message
    assert natural_map_error(W, q, short.r, MU, 3) == pytest.approx(short.error, rel=1e-6)


def test_coupled_normal_and_tangential_rows(sphere_flat):
    """Unlike half-spaces couple the normal and tangential rows (W_nt != 0; here a symmetric coupling of a tenth of
    the normal compliance times the direction cosine, W kept positive definite): the predictor's normal solve holds
    the tangential forces, so the coupling is met by its steps; it still answers a gross-slip increment alone,
    within the tolerance on the whole problem and at the sweeps' answer to the tolerance's effect."""
    W, xy = sphere_flat
    dx = xy[:, None, 0] - xy[None, :, 0]
    distance = np.hypot(dx, xy[:, None, 1] - xy[None, :, 1])
    np.fill_diagonal(distance, 1.0)
    coupling = 0.1 * W[0::3, 0::3] * dx / distance   # antisymmetric in (a, b): W_nt^T = -W_nt ... made symmetric:
    coupled = W.copy()
    coupled[0::3, 1::3] += coupling
    coupled[1::3, 0::3] += coupling.T
    assert np.array_equal(coupled, coupled.T) and np.linalg.eigvalsh(coupled).min() > 0
    q, _ = _gross_slip_increment(coupled, xy)
    r0 = solve(coupled, sphere_flat_q(xy, 40.0, 0.5, 0.6), MU, 3, tol=TOL, gross_slip_predictor=False).r
    result = solve(coupled, q, MU, 3, tol=TOL, r0=r0)
    assert result.converged and result.predictor_steps >= 2 and result.sweeps == 0, result.message
    assert natural_map_error(coupled, q, result.r, MU, 3) < TOL
    sweeps = solve(coupled, q, MU, 3, tol=TOL, r0=r0, gross_slip_predictor=False)
    assert np.abs(result.r - sweeps.r).max() <= SAME_ANSWER * result.r[0::3].max()


@pytest.mark.parametrize("normal_force", [None, 1.6])
def test_compiled_loop_gross_slip_by_the_predictor(sphere_flat, normal_force):
    """The compiled cycle loop (the package's fretting cycles), displacement or normal-force controlled (several
    solves an increment; the force 1.6 presses about as far as the approach 0.5): its gross-slip increments take
    a few predictor steps where the sweeps alone take tens, and every increment's answer meets the tolerance on its
    own whole problem; the loop holding its block and factor gives the bits of the loop that gathers and factors
    at every solve."""
    W, xy = sphere_flat
    slips = 1.2 * np.cos(2.0 * np.pi * np.arange(1, 13) / 12)
    held = sphere_flat_cycle(W, xy, 40.0, 0.5, slips, wear=1e-3, normal_force=normal_force)
    gathered = sphere_flat_cycle(W, xy, 40.0, 0.5, slips, wear=1e-3, normal_force=normal_force, hold_block=False)
    assert held["done"] == slips.size and held["status"] == 1
    for name in ("r", "x", "y", "wear_gap", "rows"):
        assert np.array_equal(held[name], gathered[name]), name
    iterations = held["rows"][:, -2]
    sliding = [j for j in range(1, slips.size) if np.all(held["states"][j][held["r"][j][0::3] > 0] == ls.SLIP)]
    assert len(sliding) >= 4
    for j in sliding:
        q = cycle_q(held, j)
        assert natural_map_error(W, q, held["r"][j], MU, 3) < TOL
    if normal_force is None:
        assert np.median(iterations[sliding]) <= 10, iterations   # measured 4-6 (the sweeps alone: 13-30)
    else:
        assert np.abs(held["r"][:, 0::3].sum(axis=1) - normal_force).max() <= 1e-8 * normal_force  # force_tol


def test_factor_held_only_for_its_loaded_set(sphere_flat):
    """The factor and float32 loaded block held from an earlier call are used only for the very loaded contacts
    they were made for: held for another set of the same size (here: wrong ones, the identity and zeros), the call
    factors and gathers anew and answers as a call with nothing held, to the bit; held for its own set, they are
    used (no factorisation) with the same answer."""
    W, xy = sphere_flat
    q, r0 = _gross_slip_increment(W, xy)
    Wa = np.ascontiguousarray(W.T)   # the working set = every contact
    nc = xy.shape[0]
    rho = ls.block_rho(W, 3)
    scale = ls._force_scale(q, np.full(nc, MU), rho, 3)
    contacts = np.arange(nc)
    loaded = contacts[r0[0::3] > 0]
    others = (loaded + 1) % nc
    assert not np.array_equal(others, loaded)

    def call(held_loaded, held_factor, held_loaded_block32):
        r, x, stats = r0.copy(), W @ r0 + q, np.zeros(3, dtype=np.int64)
        outcome, err, steps, change, key, factor, loaded_block32 = ls._gross_slip_predictor(
            Wa, q, np.full(nc, MU), rho, scale, contacts, r, x, TOL, ls.PREDICTOR_STEPS, held_loaded, held_factor,
            held_loaded_block32, stats)
        return outcome, r, stats, key, factor, loaded_block32

    fresh = call(*ls._nothing_held()[3:])
    assert fresh[0] == 1 and fresh[2][2] == 1 and np.array_equal(fresh[3], loaded)
    assert fresh[5].shape == (3 * loaded.size,) * 2
    stale = call(others, np.eye(loaded.size), np.zeros_like(fresh[5]))
    assert stale[2][2] == 1 and np.array_equal(stale[1], fresh[1])
    own = call(fresh[3], fresh[4], fresh[5])
    assert own[2][2] == 0 and own[4] is fresh[4] and own[5] is fresh[5] and np.array_equal(own[1], fresh[1])
