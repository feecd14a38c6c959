"""Sweeps on the working set (``local_solvers.solve(..., working_set=True)``, the default) give the full sweeps'
answer: on the shared FCLIB problems and on a sphere-flat-like half-space problem, including one where contacts
outside the starting set must join (the check on all contacts after the sweeps is what catches them).

References independent of the restricted route: the full sweeps (``working_set=False``, the solver before issue
26), and the natural-map error recomputed on the whole problem by :func:`natural_map_error`.
"""

import gc

import numpy as np
import pytest
from support.fclib_problems import needs_fclib, problem
from support.local_problems import cycle_q, half_space, sphere_flat_cycle, sphere_flat_q

from dolfinx_fretting import cycling
from dolfinx_fretting import local_solvers as ls
from dolfinx_fretting.local_solvers import natural_map_error, solve

TOL = 1e-10  # the scenes' solver.local_tol

# Dense problems the sweeps solve within seconds (benchmarks/results/local_solvers.md), 2D and 3D, FE and multibody.
FCLIB_DENSE = ["Box_Stacks-i0122-82-5", "Confeti-ex03-Fc3D-SBM", "NESpheres_30_1", "Spheres-i099-356-679",
               "FrictionContactProblem00071", "getfem_hertz2d_mu0.9", "gfc2d_granularflowonwall_00230_00206"]


@pytest.fixture(scope="module")
def sphere_flat():
    W, xy = half_space()
    assert np.linalg.eigvalsh(W).min() > 0  # SPD (a precondition of the unique solution compared below)
    return W, xy


def test_half_space_is_sphere_flat_like(sphere_flat):
    """The synthetic W decays like the FE W (benchmarks/results/contacts_3d.md: slope -0.83 over r > 2h; a
    half-space's exact -1): its normal blocks fall as 1/r, so 8 h away a block is 1/8 of one at h."""
    W, xy = sphere_flat
    i = 0
    j = int(np.argmin(np.abs(np.hypot(*(xy - xy[i]).T) - 1.0)))
    k = int(np.argmin(np.abs(np.hypot(*(xy - xy[i]).T) - 8.0)))
    assert W[3 * i, 3 * k] / W[3 * i, 3 * j] == pytest.approx(1.0 / 8.0, rel=1e-12)


@needs_fclib
@pytest.mark.parametrize("method", ["uzawa", "nsgs"])
@pytest.mark.parametrize("name", FCLIB_DENSE)
def test_fclib_same_answer(name, method):
    P = problem(name)
    full = solve(P.W, P.q, P.mu, P.dim, method=method, tol=TOL, max_iter=20000, working_set=False)
    restricted = solve(P.W, P.q, P.mu, P.dim, method=method, tol=TOL, max_iter=20000)
    assert full.converged and restricted.converged, (full.message, restricted.message)
    assert restricted.passes >= 1 and restricted.working_set >= 1
    # The stopping criterion holds on the whole problem, recomputed from scratch.
    assert natural_map_error(P.W, P.q, restricted.r, P.mu, P.dim) < TOL
    if restricted.joined == 0:
        # No contact outside the starting set closed at the end, and (measured, with the margin NEAR_MARGIN) none
        # dipped below a zero gap during the sweeps: the same iterates, hence the same bits. (With the margin 0,
        # NESpheres_30_1's touching contacts get 1e-19 forces from the full sweeps' rounding: not the same bits.)
        assert np.array_equal(restricted.r, full.r) and np.array_equal(restricted.x, full.x)
        assert restricted.sweeps == full.sweeps


@pytest.mark.parametrize("method", ["uzawa", "nsgs"])
@pytest.mark.parametrize("warm", [False, True])
def test_sphere_flat_same_bits(sphere_flat, method, warm):
    """Loading from zero and a gross-slip increment from the previous one: only the contact zone (and its rim)
    is swept, and the answer is the full sweeps' to the last bit (the gross-slip predictor off: it answers at
    another point within the tolerance, test_gross_slip_predictor.py)."""
    W, xy = sphere_flat
    q_before = sphere_flat_q(xy, radius=40.0, approach=0.5, slip=0.3)
    q = sphere_flat_q(xy, radius=40.0, approach=0.5, slip=0.6)
    r0 = solve(W, q_before, 0.5, 3, tol=TOL, working_set=False).r if warm else None
    full = solve(W, q, 0.5, 3, method=method, tol=TOL, r0=r0, working_set=False)
    restricted = solve(W, q, 0.5, 3, method=method, tol=TOL, r0=r0, gross_slip_predictor=False)
    assert full.converged and restricted.converged
    assert restricted.working_set < xy.shape[0] // 2  # a real restriction: the contact zone is a disc inside
    assert restricted.joined == 0 and restricted.passes == 1
    assert np.array_equal(restricted.r, full.r) and np.array_equal(restricted.x, full.x)


@pytest.mark.parametrize("method", ["uzawa", "nsgs"])
@pytest.mark.parametrize("margin", [0.0, ls.NEAR_MARGIN])
def test_contacts_outside_the_start_join(sphere_flat, method, margin, monkeypatch):
    """A warm start that overloads the centre holds the rim of the contact open (its gaps well above the margin):
    the sweeps on the starting set converge with the rim open and penetrating, the check on all contacts finds
    it, and it joins. The answer is the full sweeps' to the tolerance (one solution: W is SPD)."""
    monkeypatch.setattr(ls, "NEAR_MARGIN", margin)
    W, xy = sphere_flat
    q = sphere_flat_q(xy, radius=40.0, approach=0.5, slip=0.3)
    exact = solve(W, q, 0.5, 3, tol=1e-14, max_iter=100000, working_set=False)
    centre = np.repeat(np.hypot(*xy.T) < 2.0, 3)
    r0 = np.where(centre, 5.0 * exact.r, 0.0)
    x0 = W @ r0 + q
    rim = (exact.r[0::3] > 0) & ~centre[0::3]
    # The rim: closed at the end, open beyond the default margin at the start (the deepest penetration is -min q_n).
    assert rim.sum() >= 8 and np.all(x0[0::3][rim] > ls.NEAR_MARGIN * -q[0::3].min())
    full = solve(W, q, 0.5, 3, method=method, tol=TOL, r0=r0, working_set=False)
    restricted = solve(W, q, 0.5, 3, method=method, tol=TOL, r0=r0)
    assert full.converged and restricted.converged
    assert restricted.joined >= rim.sum() and restricted.passes >= 2
    assert natural_map_error(W, q, restricted.r, 0.5, 3) < TOL
    # Both within the tolerance of the one solution: the natural-map error bounds the distance to it by a
    # constant of W's conditioning (here measured: max |r - r_exact| / max |r_exact| <= 1.9e-9 for either route at
    # error < 1e-10), so 1e-7 holds both with a 50x margin and rejects a rim left open (an O(1) change).
    for result in (full, restricted):
        assert np.abs(result.r - exact.r).max() <= 1e-7 * np.abs(exact.r).max()


def test_float32_sweeps_meet_the_tolerance(sphere_flat):
    """float32 updates of x with float64 recomputations: the same stopping criterion on the whole problem,
    the iterates differing by rounding only."""
    W, xy = sphere_flat
    q = sphere_flat_q(xy, radius=40.0, approach=0.5, slip=0.6)
    exact = solve(W, q, 0.5, 3, tol=1e-14, max_iter=100000, working_set=False)
    single = solve(W, q, 0.5, 3, tol=TOL, float32_sweeps=True)
    assert single.converged
    assert natural_map_error(W, q, single.r, 0.5, 3) < TOL
    # The same bound as above: within the tolerance of the one solution.
    assert np.abs(single.r - exact.r).max() <= 1e-7 * np.abs(exact.r).max()


def _own(sphere_flat):
    """The fixture's W as an array of this test's own (the block held is keyed on the array) and its steps."""
    W, xy = sphere_flat
    W = W.copy()
    return W, xy, ls.block_rho(W, 3)


def test_held_block_same_bits_over_a_cycle(sphere_flat):
    """A fretting cycle of increments on one W with its steps given (as the package solves): from the second
    increment on, the sweeps run on the block W_AA held from the increment before, and every answer is the full
    sweeps' to the last bit (the same W_AA values, so the same sweeps; the gross-slip predictor off, as above).

    The set is the same at every increment because these half-spaces are alike (no normal-tangential coupling in
    W: the normal forces, hence the loaded contacts and the gaps, do not move with the slip); the solve from zero
    before the cycle starts from a larger set (every penetrating contact), so the first increment gathers its own.
    """
    W, xy, steps = _own(sphere_flat)
    r_held = r_full = solve(W, sphere_flat_q(xy, 40.0, 0.5, 0.6), 0.5, 3, tol=TOL, block_steps=steps,
                            gross_slip_predictor=False).r
    held = []
    for k in range(1, 9):
        q = sphere_flat_q(xy, radius=40.0, approach=0.5, slip=0.6 * np.cos(2.0 * np.pi * k / 8))
        restricted = solve(W, q, 0.5, 3, tol=TOL, r0=r_held, block_steps=steps, gross_slip_predictor=False)
        full = solve(W, q, 0.5, 3, tol=TOL, r0=r_full, working_set=False, hold_block=False)
        assert restricted.converged and full.converged
        assert np.array_equal(restricted.r, full.r) and np.array_equal(restricted.x, full.x)
        held.append(restricted.block_held)
        r_held, r_full = restricted.r, full.r
    assert held == [False] + [True] * 7


def test_held_block_not_used_for_a_changed_W(sphere_flat):
    """W rebuilt in place (the same array, new values; its steps recomputed into the same array): the block held
    for the old values is not used, and the answer is a fresh solve's on the new W (with the old block, r would be
    off by the factor of 2 between the two W)."""
    W, xy, steps = _own(sphere_flat)
    q = sphere_flat_q(xy, radius=40.0, approach=0.5, slip=0.6)
    first = solve(W, q, 0.5, 3, tol=TOL, block_steps=steps)
    second = solve(W, q, 0.5, 3, tol=TOL, block_steps=steps)
    assert second.block_held and np.array_equal(second.r, first.r)  # the same set from zero: held
    W *= 2.0
    steps[:] = ls.block_rho(W, 3)
    changed = solve(W, q, 0.5, 3, tol=TOL, block_steps=steps)
    fresh = solve(W.copy(), q, 0.5, 3, tol=TOL, hold_block=False)
    assert not changed.block_held
    assert np.array_equal(changed.r, fresh.r) and np.array_equal(changed.x, fresh.x)


def test_a_W_not_held_is_checked(sphere_flat):
    """W's check for non-finite values is skipped only for the very array whose block is held (checked when it was
    first solved on): another W with the same steps, a NaN in it, is refused before any sweep."""
    W, xy, steps = _own(sphere_flat)
    q = sphere_flat_q(xy, radius=40.0, approach=0.5, slip=0.6)
    assert solve(W, q, 0.5, 3, tol=TOL, block_steps=steps).converged
    assert solve(W, q, 0.5, 3, tol=TOL, block_steps=steps).block_held
    other = W.copy()
    other[3, 0] = np.nan
    with pytest.raises(ValueError, match="W: contains non-finite values"):
        solve(other, q, 0.5, 3, tol=TOL, block_steps=steps)


def test_start_at_the_answer_gives_the_whole_x(sphere_flat):
    """From the answer the restricted route forms x only on the rows the sweeps read (the outside contacts'
    tangential rows wait for the check): returned at once, x is complete, the full route's from the same start to
    the last bit."""
    W, xy = sphere_flat
    q = sphere_flat_q(xy, radius=40.0, approach=0.5, slip=0.6)
    answer = solve(W, q, 0.5, 3, tol=TOL, working_set=False).r
    full = solve(W, q, 0.5, 3, tol=TOL, r0=answer, working_set=False)
    again = solve(W, q, 0.5, 3, tol=TOL, r0=answer)
    assert full.iterations == 0 and again.converged and again.iterations == 0
    assert np.count_nonzero(again.x[1::3]) == xy.shape[0]  # every tangential row formed (a uniform slip: none is 0)
    assert np.array_equal(again.r, full.r) and np.array_equal(again.x, full.x)


def test_held_block_across_a_join_and_in_float32(sphere_flat):
    """The block held is used only for its own set: a solve that starts from a smaller set gathers that one, and
    once the rim joins and the set is the held one, sweeps on the held block (the same bits as the solve that held
    it). float32 sweeps hold their float32 copy beside it and meet the tolerance on the whole problem."""
    W, xy, steps = _own(sphere_flat)
    q = sphere_flat_q(xy, radius=40.0, approach=0.5, slip=0.3)
    exact = solve(W, q, 0.5, 3, tol=1e-14, max_iter=100000, working_set=False)
    centre = np.repeat(np.hypot(*xy.T) < 2.0, 3)
    r0 = np.where(centre, 5.0 * exact.r, 0.0)  # the rim held open at the start (test_contacts_outside_the_start_join)
    first = solve(W, q, 0.5, 3, tol=TOL, r0=r0, block_steps=steps)
    second = solve(W, q, 0.5, 3, tol=TOL, r0=r0, block_steps=steps)
    assert first.joined > 0 and not first.block_held
    assert second.joined == first.joined and second.block_held
    assert np.array_equal(second.r, first.r) and np.array_equal(second.x, first.x)
    singles = [solve(W, q, 0.5, 3, tol=TOL, block_steps=steps, float32_sweeps=True) for _ in range(2)]
    assert singles[1].block_held
    for single in singles:
        assert single.converged and natural_map_error(W, q, single.r, 0.5, 3) < TOL
        # Within the tolerance of the one solution (see test_contacts_outside_the_start_join for the 1e-7).
        assert np.abs(single.r - exact.r).max() <= 1e-7 * np.abs(exact.r).max()


def test_held_block_only_for_its_own_set(sphere_flat):
    """The block held is used only for the very set it was gathered for: a sphere pressed 2 spacings left of centre
    after one pressed 2 right has a working set of the same size (the mirror image) but other contacts, and gathers
    its own. On a W scaled contact by contact (no longer the same under translation and mirroring, unlike the
    half-space's, where another set's block has the same values) the answer is a fresh solve's to the last bit;
    a held block reused for any set of its size (the set check skipped) fails here."""
    W, xy = sphere_flat
    scale = np.repeat(np.random.default_rng(7).uniform(0.7, 1.3, xy.shape[0]), 3)
    W = W * scale[:, None] * scale[None, :]   # S W S: symmetric positive definite as W
    steps = ls.block_rho(W, 3)
    shift = np.array([2.0, 0.0])
    right = solve(W, sphere_flat_q(xy - shift, 40.0, 0.5, 0.6), 0.5, 3, tol=TOL, block_steps=steps)
    q_left = sphere_flat_q(xy + shift, 40.0, 0.5, 0.6)
    left = solve(W, q_left, 0.5, 3, tol=TOL, block_steps=steps)
    fresh = solve(W.copy(), q_left, 0.5, 3, tol=TOL, hold_block=False)
    assert right.converged and left.converged and left.working_set == right.working_set > 0
    assert not left.block_held
    assert np.array_equal(left.r, fresh.r) and np.array_equal(left.x, fresh.x)


def test_x_from_the_held_block_only_for_its_forces(sphere_flat):
    """A solve on a held block forms x on the held set's rows from the block (W's columns outside the set meet zero
    forces) when every force of its warm start lies in the set: the same bits as W's rows. A warm start with forces
    outside the set (a sphere moved 2 spacings, its answer as the start) forms x from W's rows: the answer is a fresh
    solve's to the last bit (from the block alone, x would miss those forces' columns)."""
    W, xy = sphere_flat
    scale = np.repeat(np.random.default_rng(7).uniform(0.7, 1.3, xy.shape[0]), 3)
    W = W * scale[:, None] * scale[None, :]   # no two sets' blocks alike (test_held_block_only_for_its_own_set)
    steps = ls.block_rho(W, 3)
    shift = np.array([2.0, 0.0])
    q_right, q_left = sphere_flat_q(xy - shift, 40.0, 0.5, 0.6), sphere_flat_q(xy + shift, 40.0, 0.5, 0.6)
    r_left = solve(W.copy(), q_left, 0.5, 3, tol=TOL, hold_block=False).r
    right = solve(W, q_right, 0.5, 3, tol=TOL, block_steps=steps)
    x = np.full(W.shape[0], np.nan)
    held = ls._held[0]
    assert ls._x_from_held_block(W, True, held.member, held.block, q_right, right.r, x, 3)
    assert held.member.sum() == right.working_set   # formed: the held set's rows
    rows = np.flatnonzero(np.repeat(held.member, 3))
    exact = np.empty(W.shape[0])
    ls._recompute_x_by_rows(W, q_right, right.r, exact, rows)
    assert np.array_equal(x[rows], exact[rows]) and np.isnan(np.delete(x, rows)).all()
    assert not ls._x_from_held_block(W, True, held.member, held.block, q_left, r_left, x, 3)
    left = solve(W, q_left, 0.5, 3, tol=TOL, r0=r_left, block_steps=steps)
    fresh = solve(W.copy(), q_left, 0.5, 3, tol=TOL, r0=r_left, hold_block=False)
    assert left.converged and np.array_equal(left.r, fresh.r) and np.array_equal(left.x, fresh.x)


def test_held_block_goes_with_its_W(sphere_flat):
    """The block held (tens of MB at 1000+ contacts) is dropped when its W is freed."""
    W, xy, steps = _own(sphere_flat)
    assert solve(W, sphere_flat_q(xy, 40.0, 0.5, 0.6), 0.5, 3, tol=TOL, block_steps=steps).converged
    assert ls._held[0] is not None and ls._held[0].serves(W, steps)
    del W
    gc.collect()
    assert ls._held[0] is None


# The compiled cycle loop (cycling.run_increments, run_force_increments) holds the block too, from one local solve to
# the next of one call (W is fixed within a call).
LOOP_OUTPUTS = ("rows", "r", "x", "y", "wear_gap", "states", "d", "solves")


@pytest.mark.parametrize("normal_force", [None, 1.6])
def test_compiled_loop_holds_the_block(sphere_flat, normal_force):
    """A fretting cycle in the compiled loop, displacement or normal-force controlled (the sphere-flat scene's way:
    several local solves an increment): with the block held, every increment's answer meets the tolerance on its
    own whole problem (the natural-map error recomputed from W, independent of the loop), the loop's outputs are
    those of the loop that gathers W_AA at every solve to the last bit (the same W_AA values, so the same sweeps),
    and the held block was used (a loop that never holds counts 0 and fails here).

    The force 1.6 presses the sphere about as far as the approach 0.5 (r_n sums to 1.66 there). The wear moves the
    gaps a little from one increment to the next, so the force-controlled loop looks for the approach at every
    increment (3-6 solves each, measured).
    """
    W, xy = sphere_flat
    assert np.array_equal(W, W.T)  # exactly symmetric, as the package's W (the helper passes it as W^T)
    slips = 0.6 * np.cos(2.0 * np.pi * np.arange(1, 9) / 8)
    held = sphere_flat_cycle(W, xy, 40.0, 0.5, slips, wear=1e-3, normal_force=normal_force)
    gathered = sphere_flat_cycle(W, xy, 40.0, 0.5, slips, wear=1e-3, normal_force=normal_force, hold_block=False)
    n = slips.size
    for out in (held, gathered):
        assert out["done"] == n and out["status"] == 1, out
    for j in range(n):
        assert natural_map_error(W, cycle_q(held, j), held["r"][j], 0.5, 3) < TOL
    assert held["wear_gap"][-1].max() > 0 and np.any(held["states"][-1] == 2)  # worn, and sliding at the end
    if normal_force is not None:
        assert held["solves"].min() >= 2  # trials of the load control: solves within an increment hold the block too
        assert np.abs(held["r"][:, 0::3].sum(axis=1) - normal_force).max() <= 1e-8 * normal_force  # force_tol
    for name in LOOP_OUTPUTS:
        assert np.array_equal(held[name], gathered[name]), name
    # Each solve that swept used the block it held or gathered one (a trial may start at its answer: no sweep, and
    # neither count); the set changes at the first increments (from r = 0 every penetrating contact, then the loaded
    # ones) and, under force control, when a trial's approach moves the rim across the margin: measured 6 of 8 and 25
    # of 29 sweeping solves (37 solves) on the held block. The loop that gathers never holds. A solve may count in
    # both (it swept the held block, then a contact joined and it gathered the larger set's).
    swept = int(gathered["counts"][4])
    assert max(held["counts"][3], held["counts"][4]) <= swept <= held["counts"][3] + held["counts"][4]
    assert swept <= int(held["solves"].sum())
    assert held["counts"][3] >= swept // 2 and gathered["counts"][3] == 0


def test_compiled_loop_starts_from_the_known_x(sphere_flat):
    """The compiled loop's local solve from the answer of the solve before (force control's trials, the increments
    warm started from the last one) starts from ``x + q - q_before`` instead of forming ``W r + q`` again: the same
    answer to the tolerance's effect, every answer's ``x`` formed exactly (the bits of ``W r + q`` by W's rows), and
    an answer at the start judged again on the exact ``x`` (the start's own ``x`` differs in the last bits)."""
    W, xy = sphere_flat
    nc, m = xy.shape[0], W.shape[0]
    mu = np.full(nc, 0.5)
    rho = ls.block_rho(W, 3)
    cache = cycling.ActivePatternCache(1, nc, 3)
    normal_only, Wn, qn, rn, xn = cycling._normal_rows(W, mu, 3)

    def local(q, r, x, q_before, known):
        x_known = np.array([known])
        its, err, status, _ = cycling._solve_local(
            W, Wn, normal_only, rho, mu, 3, q, r, x, TOL, 20000, ls._REFRESH, False, 0, cache.pattern, cache.lu,
            cache.piv, cache.lu_ok, cache.counts, np.empty(m), qn, rn, xn, ls._nothing_held(), False, False, False,
            q_before, x_known)
        assert status == 1 and x_known[0] and np.array_equal(q_before, q)
        exact = np.empty(m)
        ls._recompute_x_by_rows(W, q, r, exact, np.arange(m))
        assert np.array_equal(x, exact)   # the answer's x formed exactly
        return its

    q1, q2 = sphere_flat_q(xy, 40.0, 0.5, 0.6), sphere_flat_q(xy, 40.0, 0.52, 0.7)
    r, x, q_before = np.zeros(m), np.empty(m), np.empty(m)
    local(q1, r, x, q_before, False)
    r_known, x_known_start, r_formed = r.copy(), x.copy(), r.copy()
    assert local(q2, r_known, x_known_start, q_before.copy(), True) > 0
    assert local(q2, r_formed, np.empty(m), q_before.copy(), False) > 0
    assert np.abs(r_known - r_formed).max() <= 1e-7 * np.abs(r_formed).max()   # as test_contacts_outside_...
    q3 = q2 * (1.0 + 1e-14)   # r_known still answers it: returned at the start
    start = x_known_start + (q3 - q2)
    exact = np.empty(m)
    ls._recompute_x_by_rows(W, q3, r_known, exact, np.arange(m))
    assert not np.array_equal(start, exact)   # the known start is off in the last bits
    assert local(q3, r_known, x_known_start, q2.copy(), True) == 0


def test_compiled_loop_float32_sweeps_meet_the_tolerance(sphere_flat):
    """float32 sweeps in the compiled loop (on the held float32 copy of the block): every increment's answer meets
    the tolerance on its own whole problem, and the cycle is the float64 one's to the tolerance's effect."""
    W, xy = sphere_flat
    slips = 0.6 * np.cos(2.0 * np.pi * np.arange(1, 9) / 8)
    double = sphere_flat_cycle(W, xy, 40.0, 0.5, slips, wear=1e-3)
    single = sphere_flat_cycle(W, xy, 40.0, 0.5, slips, wear=1e-3, float32_sweeps=True)
    assert single["done"] == slips.size and single["status"] == 1
    for j in range(slips.size):
        assert natural_map_error(W, cycle_q(single, j), single["r"][j], 0.5, 3) < TOL
    assert single["counts"][3] > 0  # the float32 copy held with the block
    assert not np.array_equal(single["r"], double["r"])  # float32 updates: other iterates
    # Within the tolerance of the one solution of each increment (see test_contacts_outside_the_start_join for the
    # 1e-7: measured 1.9e-9 at error < 1e-10); each increment starts from its own previous answer and positions.
    assert np.abs(single["r"] - double["r"]).max() <= 1e-7 * np.abs(double["r"]).max()
