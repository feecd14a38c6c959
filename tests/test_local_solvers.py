"""Local Uzawa solver (paper Algorithm 1, corrected eq. 31) against closed forms and enumeration.

References are independent of the solver: single contacts solved by hand, small 2D problems solved by
enumerating every open/stick/slip combination (a linear solve each), and De Saxce's complementarity
conditions checked directly on the returned (r, x).
"""

import numpy as np
import pytest
import scipy.sparse as sp
from support.local_problems import check_complementarity, enumerate_2d, random_problem

from dolfinx_fretting import local_solvers as ls
from dolfinx_fretting.local_solvers import OPEN, SLIP, STICK, LocalSolverError, natural_map_error, solve

TOL = 1e-12
# With error < 1e-12 on well-conditioned O(1) problems (cond(W) <= ~20 below), r and x are accurate to about
# cond * 1e-12; 1e-9 keeps a margin of 50x and still rejects any wrong contact state (errors of O(0.1)).
SOL = dict(rtol=1e-9, atol=1e-9)


# ---- single contact, closed forms ------------------------------------------------------------------------
@pytest.mark.parametrize(
    "W, q, mu, r_exp, x_exp",
    [
        # open: q_n > 0 -> r = 0, x = q
        (np.diag([2.0, 4.0]), [1.0, 3.0], 0.5, [0.0, 0.0], [1.0, 3.0]),
        # stick: r = -W^-1 q = (0.5, -0.05), |r_t| = 0.05 <= 0.5 * 0.5; x = 0
        (np.diag([2.0, 4.0]), [-1.0, 0.2], 0.5, [0.5, -0.05], [0.0, 0.0]),
        # slip: stick would need |r_t| = 0.75 > 0.25 -> r_n = 0.5 (x_n = 0), r_t = -mu r_n = -0.25,
        # x_t = 4 * (-0.25) + 3 = 2 > 0, opposed to r_t
        (np.diag([2.0, 4.0]), [-1.0, 3.0], 0.5, [0.5, -0.25], [0.0, 2.0]),
        # slip with n-t coupling W = [[2, .5], [.5, 4]]: r_t = -r_n/2, 2 r_n - r_n/4 = 1 -> r_n = 4/7,
        # r_t = -2/7, x_t = 0.5 * 4/7 - 8/7 + 3 = 15/7
        (np.array([[2.0, 0.5], [0.5, 4.0]]), [-1.0, 3.0], 0.5, [4 / 7, -2 / 7], [0.0, 15 / 7]),
        # frictionless: r_t = 0, r_n = 1/2, x_t = q_t
        (np.diag([2.0, 4.0]), [-1.0, 3.0], 0.0, [0.5, 0.0], [0.0, 3.0]),
    ],
)
def test_single_contact_2d(W, q, mu, r_exp, x_exp):
    res = solve(W, np.array(q), mu, 2, tol=TOL)
    assert res.converged, res.message
    np.testing.assert_allclose(res.r, r_exp, **SOL)
    np.testing.assert_allclose(res.x, x_exp, **SOL)
    assert res.error < TOL


def test_single_contact_3d():
    W = np.diag([2.0, 4.0, 4.0])
    # slip: |q_t| = 3 -> r_n = 0.5, r_t = -0.25 (0.6, 0.8), x_t = 4 r_t + q_t = (1.2, 1.6)
    res = solve(W, np.array([-1.0, 1.8, 2.4]), 0.5, 3, tol=TOL)
    assert res.converged, res.message
    np.testing.assert_allclose(res.r, [0.5, -0.15, -0.2], **SOL)
    np.testing.assert_allclose(res.x, [0.0, 1.2, 1.6], **SOL)
    # stick: r = -W^-1 q = (0.5, -0.025, 0.05), |r_t| = 0.0559 <= 0.25
    res = solve(W, np.array([-1.0, 0.1, -0.2]), 0.5, 3, tol=TOL)
    np.testing.assert_allclose(res.r, [0.5, -0.025, 0.05], **SOL)
    np.testing.assert_allclose(res.x, 0.0, **SOL)
    np.testing.assert_array_equal(ls.contact_states(res.r, res.x, 0.5, 3), [STICK])


# ---- enumeration ------------------------------------------------------------------------------------------
@pytest.mark.parametrize("seed", range(8))
def test_small_problems_match_enumeration(seed):
    W, q, mu = random_problem(seed, nc=3)
    sols = enumerate_2d(W, q, mu)
    assert sols, "enumeration found no solution"
    # SPD W and mu = 0.3: the solution is unique (every feasible assignment gives the same r).
    for _, r_e, _ in sols[1:]:
        np.testing.assert_allclose(r_e, sols[0][1], **SOL)
    states_e, r_e, x_e = sols[0]
    res = solve(W, q, mu, 2, tol=TOL)
    assert res.converged, res.message
    np.testing.assert_allclose(res.r, r_e, **SOL)
    np.testing.assert_allclose(res.x, x_e, **SOL)
    codes = {"open": OPEN, "stick": STICK, "slip+": SLIP, "slip-": SLIP}
    expected = [codes[s] for s in states_e]
    got = ls.contact_states(res.r, res.x, mu, 2)
    # A contact exactly at a state boundary may be enumerated either way; only compare clear-cut ones.
    R = r_e.reshape(-1, 2)
    clear = (R[:, 0] > 1e-6) & (np.abs(np.abs(R[:, 1]) - mu * R[:, 0]) > 1e-6) | (np.abs(R).max(1) == 0)
    np.testing.assert_array_equal(got[clear], np.array(expected)[clear])


def test_enumeration_covers_all_states():
    """The seeds above exercise open, stick and slip contacts (otherwise the comparison is weak)."""
    seen = set()
    for seed in range(8):
        W, q, mu = random_problem(seed, nc=3)
        seen.update(s.rstrip("+-") for s in enumerate_2d(W, q, mu)[0][0])
    assert seen == {"open", "stick", "slip"}


@pytest.mark.parametrize("dim", [2, 3])
@pytest.mark.parametrize("mu", [0.0, 0.3, 1.0])
def test_complementarity_at_solution(dim, mu):
    W, q, _ = random_problem(42, nc=20, dim=dim)
    res = solve(W, q, mu, dim, tol=TOL)
    assert res.converged, res.message
    x = check_complementarity(W, q, res.r, mu, dim)
    # x returned is W r + q to rounding (recomputed at exit).
    np.testing.assert_allclose(res.x, x, rtol=0, atol=1e-13 * np.abs(x).max())


def test_sparse_matches_dense():
    W, q, mu = random_problem(3, nc=15, dim=3)
    W[np.abs(W) < 0.05] = 0.0  # keep symmetric, some structure
    dense = solve(W, q, mu, 3, tol=TOL)
    sparse = solve(sp.csr_matrix(W), q, mu, 3, tol=TOL)
    assert dense.converged and sparse.converged
    # Same algorithm, same order of operations up to summation order: equal to rounding.
    np.testing.assert_allclose(sparse.r, dense.r, rtol=1e-10, atol=1e-12)
    assert abs(sparse.iterations - dense.iterations) <= 1


# ---- error measure -----------------------------------------------------------------------------------------
def test_error_measure_scale_invariant():
    W, q, mu = random_problem(7, nc=10, dim=3)
    r = np.abs(np.random.default_rng(1).normal(size=q.size))  # any candidate, not a solution
    e = natural_map_error(W, q, r, mu, 3)
    assert e > 1e-3
    for s, c in [(1e6, 1e-3), (1e-9, 7.0), (3.0, 1e5)]:
        # x -> c x and r -> (c/s) r: every term of the measure scales the same way.
        e_sc = natural_map_error(s * W, c * q, (c / s) * r, mu, 3)
        assert e_sc == pytest.approx(e, rel=1e-12)  # rounding of O(m) flops


def test_solver_scale_invariant():
    W, q, mu = random_problem(11, nc=12, dim=2)
    ref = solve(W, q, mu, 2, tol=1e-11)
    s, c = 115e3, 4.5e-3  # MPa-sized compliance inverse, micrometre-sized gaps
    res = solve(W / s, c * q, mu, 2, tol=1e-11)
    assert ref.converged and res.converged
    # Same iterates up to rounding, hence the same sweep count (+-1 if the error crosses tol at rounding).
    assert abs(res.iterations - ref.iterations) <= 1
    np.testing.assert_allclose(res.r, c * s * ref.r, rtol=1e-8, atol=1e-8 * np.abs(c * s * ref.r).max())


def test_error_zero_at_exact_solution_and_zero_problem():
    W = np.diag([2.0, 4.0])
    assert natural_map_error(W, np.array([-1.0, 3.0]), np.array([0.5, -0.25]), 0.5, 2) < 1e-16
    res = solve(np.eye(4), np.zeros(4), 0.3, 2)
    assert res.converged and res.iterations == 0 and res.error == 0.0
    np.testing.assert_array_equal(res.r, 0.0)


# ---- failure reporting, options, validation ----------------------------------------------------------
def test_non_convergence_is_reported():
    W, q, mu = random_problem(5, nc=30, dim=2)
    res = solve(W, q, mu, 2, tol=1e-12, max_iter=1)
    assert not res.converged
    assert res.iterations == 1 and res.error >= 1e-12
    assert "max_iter = 1" in res.message and "1.0e-12" in res.message
    # x belongs to the returned r even without convergence.
    np.testing.assert_allclose(res.x, W @ res.r + q, rtol=0, atol=1e-13 * np.abs(q).max())
    with pytest.raises(LocalSolverError, match="not converged after max_iter = 1") as exc:
        solve(W, q, mu, 2, tol=1e-12, max_iter=1, raise_on_failure=True)
    assert isinstance(exc.value, RuntimeError)


def test_non_finite_is_reported():
    W, q, mu = random_problem(5, nc=30, dim=2)
    # A step 1e300 times too long overflows: reported, not returned as a solution.
    res = solve(W, q, mu, 2, rho=1e300, max_iter=50)
    assert not res.converged and "non-finite" in res.message


def test_warm_start_from_solution_needs_no_sweep():
    W, q, mu = random_problem(9, nc=25, dim=3)
    res = solve(W, q, mu, 3, tol=1e-11)
    again = solve(W, q, mu, 3, tol=1e-11, r0=res.r)
    assert again.converged and again.iterations == 0
    # r0 is projected on the cones: a slipping contact may move by an ulp.
    np.testing.assert_allclose(again.r, res.r, rtol=1e-14, atol=1e-16)


def test_rho_factor_changes_speed_not_solution():
    W, q, mu = random_problem(13, nc=20, dim=2)
    a = solve(W, q, mu, 2, tol=TOL)
    b = solve(W, q, mu, 2, tol=TOL, rho=0.5)
    assert a.converged and b.converged and a.iterations != b.iterations
    np.testing.assert_allclose(b.r, a.r, **SOL)


def test_paper_eq31_as_printed_is_not_a_fixed_point():
    """Why eq. (31) is corrected: with x^{ab} (own term dropped) the exact solution is not a fixed point."""
    W, q, mu = np.diag([2.0, 4.0]), np.array([-1.0, 3.0]), 0.5
    r = np.array([0.5, -0.25])  # exact solution (slip case above)
    rho = 1.0 / 4.0
    x_ab = q  # sum over beta != alpha is empty for one contact
    printed = ls.project_coulomb(r - rho * ls.de_saxce_x(x_ab, mu), mu)
    corrected = ls.project_coulomb(r - rho * ls.de_saxce_x(W @ r + q, mu), mu)
    np.testing.assert_allclose(corrected, r, **SOL)
    assert np.linalg.norm(printed - r) > 0.1


def test_zero_contacts():
    res = solve(np.zeros((0, 0)), np.zeros(0), 0.3, 3)
    assert res.converged and res.iterations == 0 and res.r.size == 0 and res.x.size == 0


@pytest.mark.parametrize(
    "kwargs, name",
    [
        (dict(W=np.eye(3), q=np.zeros(4)), "W"),
        (dict(q=np.zeros(5)), "q"),
        (dict(q=np.array([np.nan, 0, 0, 0])), "q"),
        (dict(W=np.full((4, 4), np.inf)), "W"),
        (dict(mu=-0.1), "mu"),
        (dict(mu=np.array([0.1, 0.2, 0.3])), "mu"),
        (dict(dim=4), "dim"),
        (dict(method="bogus"), "method"),
        (dict(tol=0.0), "tol"),
        (dict(max_iter=0), "max_iter"),
        (dict(r0=np.zeros(3)), "r0"),
        (dict(rho=-1.0), "rho"),
        (dict(block_steps=np.ones(3)), "block_steps"),
        (dict(block_steps=np.array([1.0, -1.0])), "block_steps"),
        (dict(block_steps=np.array([1.0, np.nan])), "block_steps"),
    ],
)
def test_validation(kwargs, name):
    args = dict(W=np.eye(4), q=np.array([-1.0, 0.0, -1.0, 0.0]), mu=0.3, dim=2)
    args.update(kwargs)
    with pytest.raises(ValueError, match=name):
        solve(**args)


@pytest.mark.parametrize("method", ["uzawa", "nsgs", "newton", "auto"])
@pytest.mark.parametrize("mu", [0.0, 0.4])
@pytest.mark.parametrize("sparse", [False, True])
def test_block_steps_given_are_the_steps_computed(method, mu, sparse):
    """The caller's block_rho(W) (ContactOperators.block_steps, computed once per W) gives the answer of the solve
    that computes it itself, bit for bit (same numbers, same operations: one process, so exact equality holds), and
    is really what the solve reads: other steps change the error measure and the Uzawa iterates."""
    W, q, _ = random_problem(5, nc=12, dim=3)
    W = sp.csr_matrix(W) if sparse else W
    steps = ls.block_rho(W, 3)
    own = solve(W, q, mu, 3, method=method, tol=TOL)
    given = solve(W, q, mu, 3, method=method, tol=TOL, block_steps=steps)
    assert own.converged and given.converged
    assert np.array_equal(own.r, given.r) and np.array_equal(own.x, given.x)
    assert own.iterations == given.iterations and own.error == given.error
    r = np.abs(np.random.default_rng(2).normal(size=q.size))
    assert natural_map_error(W, q, r, mu, 3, block_steps=steps) == natural_map_error(W, q, r, mu, 3)
    assert natural_map_error(W, q, r, mu, 3, block_steps=0.5 * steps) != natural_map_error(W, q, r, mu, 3)
    if method == "uzawa":
        halved = solve(W, q, mu, 3, method=method, tol=TOL, block_steps=0.5 * steps)
        assert halved.iterations != own.iterations


def test_contact_states_codes():
    # open, stick (|r_t| < mu r_n), slip (|r_t| = mu r_n), frictionless closed contact (slip)
    r = np.array([0.0, 0.0, 1.0, 0.1, 1.0, -0.5, 2.0, 0.0])
    x = np.array([0.3, 0.0, 0.0, 0.0, 0.0, 0.2, 0.0, 1.0])
    states = ls.contact_states(r, x, np.array([0.5, 0.5, 0.5, 0.0]), 2)
    np.testing.assert_array_equal(states, [OPEN, STICK, SLIP, SLIP])
    np.testing.assert_array_equal(ls.contact_states(np.zeros(6), np.ones(6), 0.3, 3), [OPEN, OPEN])
