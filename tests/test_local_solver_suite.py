"""The local solvers besides Uzawa: NSGS with exact one-contact solves, semismooth Newton, and "auto".

Every method is held to the same contract as ``method="uzawa"`` (tests/test_local_solvers.py): stop on
``natural_map_error < tol``, warm start projected on the cones, ``LocalResult`` with an honest
non-convergence report. References are independent of the solvers: 2D problems solved by enumerating every
open/stick/slip assignment, De Saxce's conditions checked directly on (r, W r + q), and the Siconos
solutions shipped with the shared FCLIB problems.
"""

import numpy as np
import pytest
import scipy.sparse as sp
from support.fclib_problems import FE, INDEX, NON_UNIQUE, needs_fclib, problem
from support.local_problems import check_complementarity, enumerate_2d, random_problem

from dolfinx_fretting import local_solvers as ls
from dolfinx_fretting.local_solvers import LocalSolverError, natural_map_error, solve

NEW = ("nsgs", "newton", "auto")
TOL = 1e-12
SOL = dict(rtol=1e-9, atol=1e-9)  # as in test_local_solvers.py: cond(W) <= ~20, error < 1e-12


def violation(W, q, r, mu, dim):
    """Largest relative violation of De Saxce's conditions (same measure as tests/test_fclib.py)."""
    W = W.toarray() if sp.issparse(W) else W
    x = W @ r + q
    R, X = r.reshape(-1, dim), x.reshape(-1, dim)
    rs, xs = max(np.abs(R).max(), 1e-300), max(np.abs(X).max(), np.abs(q).max(), 1e-300)
    rt, xt = np.linalg.norm(R[:, 1:], axis=1), np.linalg.norm(X[:, 1:], axis=1)
    dot = R[:, 0] * (X[:, 0] + mu * xt) + np.sum(R[:, 1:] * X[:, 1:], axis=1)
    return max(np.max(-R[:, 0]) / rs, np.max(rt - mu * R[:, 0]) / rs, np.max(-X[:, 0]) / xs,
               np.max(np.abs(dot)) / (rs * xs))


def check_result(res, W, q, mu, dim, tol):
    """What every converged result must satisfy, recomputed independently of the solver."""
    assert res.converged, res.message
    assert res.error < tol and natural_map_error(W, q, res.r, mu, dim) < tol
    Wd = W.toarray() if sp.issparse(W) else W
    np.testing.assert_allclose(res.x, Wd @ res.r + q, rtol=0, atol=1e-12 * max(np.abs(q).max(), 1e-300))
    assert res.iterations == res.sweeps + res.newton_steps
    assert np.all(np.isfinite(res.r)) and np.all(np.isfinite(res.x))


# ---- small random problems against enumeration (2D) and Uzawa + complementarity (3D) ---------------------
@pytest.mark.parametrize("method", NEW)
@pytest.mark.parametrize("mu", [0.0, 0.3, 1.0])
@pytest.mark.parametrize("seed", range(6))
def test_2d_matches_enumeration(method, mu, seed):
    W, q, _ = random_problem(seed, nc=3)
    sols = enumerate_2d(W, q, mu)
    assert sols, "enumeration found no solution"
    res = solve(W, q, mu, 2, method=method, tol=TOL)
    check_result(res, W, q, mu, 2, TOL)
    # The returned r is one of the enumerated solutions (with mu = 1 several may exist; all are checked).
    assert any(np.allclose(res.r, r_e, **SOL) and np.allclose(res.x, x_e, **SOL) for _, r_e, x_e in sols)


@pytest.mark.parametrize("method", NEW)
@pytest.mark.parametrize("dim", [2, 3])
@pytest.mark.parametrize("mu", [0.0, 0.3, 1.0])
def test_matches_uzawa_and_contact_law(method, dim, mu):
    W, q, _ = random_problem(42, nc=20, dim=dim)
    ref = solve(W, q, mu, dim, method="uzawa", tol=TOL)
    res = solve(W, q, mu, dim, method=method, tol=TOL)
    check_result(res, W, q, mu, dim, TOL)
    check_complementarity(W, q, res.r, mu, dim)
    np.testing.assert_allclose(res.r, ref.r, rtol=1e-8, atol=1e-8 * np.abs(ref.r).max())
    assert res.method == method


@pytest.mark.parametrize("method", NEW)
def test_single_contacts_closed_form(method):
    """The closed-form cases of test_local_solvers.py (open, stick, slip, n-t coupling, 3D slip/stick)."""
    cases = [
        (np.diag([2.0, 4.0]), [1.0, 3.0], 0.5, [0.0, 0.0]),
        (np.diag([2.0, 4.0]), [-1.0, 0.2], 0.5, [0.5, -0.05]),
        (np.diag([2.0, 4.0]), [-1.0, 3.0], 0.5, [0.5, -0.25]),
        (np.array([[2.0, 0.5], [0.5, 4.0]]), [-1.0, 3.0], 0.5, [4 / 7, -2 / 7]),
        (np.diag([2.0, 4.0]), [-1.0, 3.0], 0.0, [0.5, 0.0]),
        (np.diag([2.0, 4.0, 4.0]), [-1.0, 1.8, 2.4], 0.5, [0.5, -0.15, -0.2]),
        (np.diag([2.0, 4.0, 4.0]), [-1.0, 0.1, -0.2], 0.5, [0.5, -0.025, 0.05]),
    ]
    for W, q, mu, r_exp in cases:
        res = solve(W, np.array(q), mu, len(q), method=method, tol=TOL)
        assert res.converged, res.message
        np.testing.assert_allclose(res.r, r_exp, **SOL)


@pytest.mark.parametrize("dim", [2, 3])
def test_nsgs_one_contact_is_exact(dim):
    """NSGS solves a single contact exactly: one sweep (or none if r = 0 already solves it) to 1e-13.

    Random SPD blocks with normal-tangential coupling, mu in [0, 2], and every state: the enumeration (2D)
    and the sliding-direction root finding (3D) must find a solution, not approach it."""
    rng = np.random.default_rng(dim)
    states = set()
    for _ in range(300):
        A = rng.normal(size=(dim, dim))
        W = A @ A.T + 0.05 * np.eye(dim)
        q = rng.normal(size=dim)
        mu = rng.uniform(0.0, 2.0)
        res = solve(W, q, mu, dim, method="nsgs", tol=1e-13, max_iter=1)
        assert res.converged and res.iterations <= 1, (W, q, mu, res.message)
        check_complementarity(W, q, res.r, mu, dim)
        states.add(int(ls.contact_states(res.r, res.x, mu, dim)[0]))
    assert states == {ls.OPEN, ls.STICK, ls.SLIP}


# ---- contract: warm start, scale invariance, reports, sparse, validation ----------------------------------
@pytest.mark.parametrize("method", NEW)
@pytest.mark.parametrize("dim", [2, 3])
def test_warm_start_from_solution_needs_no_iteration(method, dim):
    W, q, mu = random_problem(9, nc=25, dim=dim)
    res = solve(W, q, mu, dim, method=method, tol=1e-11)
    again = solve(W, q, mu, dim, method=method, tol=1e-11, r0=res.r)
    assert again.converged and again.iterations == 0 and again.sweeps == again.newton_steps == 0
    np.testing.assert_allclose(again.r, res.r, rtol=1e-14, atol=1e-16)


@pytest.mark.parametrize("method", NEW)
def test_warm_start_is_projected_and_still_converges(method):
    W, q, mu = random_problem(4, nc=15, dim=3)
    r0 = np.random.default_rng(0).normal(size=q.size)  # outside the cones
    res = solve(W, q, mu, 3, method=method, tol=TOL, r0=r0)
    check_result(res, W, q, mu, 3, TOL)
    ref = solve(W, q, mu, 3, method="uzawa", tol=TOL)
    np.testing.assert_allclose(res.r, ref.r, rtol=1e-8, atol=1e-8 * np.abs(ref.r).max())


@pytest.mark.parametrize("method", NEW)
@pytest.mark.parametrize("dim", [2, 3])
def test_scale_invariance(method, dim):
    W, q, mu = random_problem(11, nc=12, dim=dim)
    ref = solve(W, q, mu, dim, method=method, tol=1e-11)
    s, c = 115e3, 4.5e-3  # MPa-sized stiffness, micrometre-sized gaps
    res = solve(W / s, c * q, mu, dim, method=method, tol=1e-11)
    assert ref.converged and res.converged
    # Same iterates up to rounding: the same work (+-1 if the error crosses tol at rounding level).
    assert abs(res.iterations - ref.iterations) <= 1
    np.testing.assert_allclose(res.r, c * s * ref.r, rtol=1e-8, atol=1e-8 * np.abs(c * s * ref.r).max())


@pytest.mark.parametrize("method", NEW)
def test_non_convergence_is_reported(method):
    W, q, mu = random_problem(5, nc=30, dim=3)
    res = solve(W, q, mu, 3, method=method, tol=1e-15, max_iter=1)
    assert not res.converged and res.iterations == 1 and res.error >= 1e-15
    assert "not converged after max_iter = 1" in res.message and "1.0e-15" in res.message
    np.testing.assert_allclose(res.x, W @ res.r + q, rtol=0, atol=1e-13 * np.abs(q).max())
    with pytest.raises(LocalSolverError, match=f"{method!r}.*not converged"):
        solve(W, q, mu, 3, method=method, tol=1e-15, max_iter=1, raise_on_failure=True)


@pytest.mark.parametrize("method", NEW)
def test_sparse_matches_dense(method):
    W, q, mu = random_problem(3, nc=15, dim=3)
    W[np.abs(W) < 0.05] = 0.0
    dense = solve(W, q, mu, 3, method=method, tol=TOL)
    sparse = solve(sp.csr_matrix(W), q, mu, 3, method=method, tol=TOL)
    assert dense.converged and sparse.converged
    np.testing.assert_allclose(sparse.r, dense.r, rtol=1e-9, atol=1e-11)
    assert abs(sparse.iterations - dense.iterations) <= 1


def test_nsgs_relaxation_changes_speed_not_solution():
    W, q, mu = random_problem(13, nc=20, dim=2)
    a = solve(W, q, mu, 2, method="nsgs", tol=TOL)
    b = solve(W, q, mu, 2, method="nsgs", tol=TOL, rho=1.3)
    assert a.converged and b.converged and a.iterations != b.iterations
    np.testing.assert_allclose(b.r, a.r, **SOL)


def test_zero_problem_and_no_contacts():
    for method in NEW:
        res = solve(np.eye(4), np.zeros(4), 0.3, 2, method=method)
        assert res.converged and res.iterations == 0 and res.error == 0.0
        res = solve(np.zeros((0, 0)), np.zeros(0), 0.3, 3, method=method)
        assert res.converged and res.r.size == 0


@pytest.mark.parametrize("kwargs, name", [
    (dict(method="bogus"), "method"),
    (dict(method="NSGS"), "method"),
    (dict(method=None), "method"),
    (dict(method=3), "method"),
    (dict(method="nsgs", rho=2.0), "rho"),
    (dict(method="newton", rho=0.0), "rho"),
    (dict(method="auto", tol=-1.0), "tol"),
    (dict(method="newton", max_iter=0), "max_iter"),
    (dict(method="nsgs", r0=np.full(4, np.nan)), "r0"),
])
def test_validation(kwargs, name):
    args = dict(W=np.eye(4), q=np.array([-1.0, 0.0, -1.0, 0.0]), mu=0.3, dim=2)
    args.update(kwargs)
    with pytest.raises(ValueError, match=name):
        solve(**args)


def test_methods_listed():
    assert ls.METHODS == ("uzawa", "nsgs", "newton", "auto")


# ---- shared FCLIB problems ---------------------------------------------------------------------------------
@needs_fclib
@pytest.mark.parametrize("method", NEW)
@pytest.mark.parametrize("name", FE)
def test_fe_problems(method, name):
    P = problem(name)
    res = solve(P.W, P.q, P.mu, P.dim, method=method, tol=1e-10, max_iter=5000)
    check_result(res, P.W, P.q, P.mu, P.dim, 1e-10)
    # SPD W, unique solution: same bounds as tests/test_fclib.py::test_fe_problems.
    assert np.linalg.norm(res.x - P.x_ref) <= 1e-7 * np.linalg.norm(P.x_ref)
    np.testing.assert_allclose(res.r, P.r_ref, rtol=0, atol=1e-7 * np.abs(P.r_ref).max())
    assert violation(P.W, P.q, res.r, P.mu, P.dim) < 1e-8


@needs_fclib
@pytest.mark.parametrize("method", NEW)
def test_fe_warm_start_from_reference(method):
    """A warm start near the solution (Siconos's, natural-map error ~1e-10) saves most of the work.

    Measured: NSGS 41 and 88 sweeps instead of 232 and 438, Newton 1 step instead of 8 and 10. "auto"
    stays with NSGS from the warm start (88 sweeps, as fast as its cold 30 sweeps + 3 Newton steps), so for
    it only convergence is required."""
    for name in FE:
        P = problem(name)
        cold = solve(P.W, P.q, P.mu, P.dim, method=method, tol=1e-12)
        warm = solve(P.W, P.q, P.mu, P.dim, method=method, tol=1e-12, r0=P.r_ref)
        assert cold.converged and warm.converged
        if method != "auto":
            assert warm.iterations < cold.iterations / 2, (warm.message, cold.message)


# Uzawa has not converged on these after 20000 sweeps (tests/test_fclib.py::SLOW_TO_CONVERGE); here with 2000.
STALLS = ["BoxesStack1-i100000-32", "Capsules-i101-404"]


@needs_fclib
@pytest.mark.parametrize("name", STALLS)
def test_problem_where_uzawa_stalls(name):
    P = problem(name)
    uz = solve(P.W, P.q, P.mu, P.dim, method="uzawa", tol=1e-10, max_iter=2000)
    assert not uz.converged and "not converged" in uz.message
    for method in ("newton", "auto"):
        res = solve(P.W, P.q, P.mu, P.dim, method=method, tol=1e-10, max_iter=300)
        check_result(res, P.W, P.q, P.mu, P.dim, 1e-10)
        assert res.iterations < 200, res.message
        assert violation(P.W, P.q, res.r, P.mu, P.dim) < 1e-7
        # Rank-deficient W: compare x (unique), not r; bound as in tests/test_fclib.py.
        scale = max(np.linalg.norm(P.x_ref), np.linalg.norm(P.q))
        assert np.linalg.norm(res.x - P.x_ref) / scale < 1e-6


@needs_fclib
@pytest.mark.slow
def test_honest_report_where_nothing_converges():
    """RockPile_tob1: no Siconos solver reached 1e-8 in 60 s, nor do ours within 50 iterations."""
    P = problem("RockPile_tob1")
    for method in NEW:
        res = solve(P.W, P.q, P.mu, P.dim, method=method, tol=1e-10, max_iter=50)
        assert not res.converged and res.iterations == 50 and "not converged" in res.message
        assert np.isfinite(res.error) and res.error >= 1e-10
        np.testing.assert_allclose(res.x, P.W @ res.r + P.q, rtol=0, atol=1e-12 * np.abs(P.q).max())


# Problems on which a method does not reach 1e-10 within the iteration caps below (measured; see
# benchmarks/results/solver_suite.md). Everything else must converge to a verified solution.
NOT_CONVERGING = {
    "nsgs": {"BoxesStack1-i100000-32", "Capsules-i100-1090", "Capsules-i101-404", "Capsules-i122-1617",
             "OneObject-i100000-316", "RockPile_tob1", "fc2d_granularflowonwall_02020_00213",
             "fc2d_granularflowonwall_07002_00801", "spheres-in-a-box-98-i10000-256-10"},
    "newton": {"RockPile_tob1", "fc2d_granularflowonwall_07002_00801"},
    "auto": {"RockPile_tob1", "fc2d_granularflowonwall_07002_00801"},
}
CAPS = {"nsgs": 5000, "newton": 500, "auto": 2000}
# Problems whose outcome the BLAS kernel decides (the Newton steps' dense LU): spheres-in-a-box-98 converges in 115
# (newton) and 205 (auto) iterations with OpenBLAS's Haswell, Zen and Nehalem kernels and stalls at 2.32e-8 within the
# caps with its Sandybridge, SkylakeX and Cooperlake kernels (Cooperlake: an AVX-512 machine's default here; measured
# with OPENBLAS_CORETYPE, the same code): either outcome is accepted, each checked as any other (an honest report, or
# a verified answer).
KERNEL_DEPENDENT = {"newton": {"spheres-in-a-box-98-i10000-256-10"}, "auto": {"spheres-in-a-box-98-i10000-256-10"}}


@needs_fclib
@pytest.mark.slow
@pytest.mark.parametrize("method", NEW)
@pytest.mark.parametrize("name", sorted(INDEX))
def test_fclib_problem(method, name):
    P = problem(name)
    res = solve(P.W, P.q, P.mu, P.dim, method=method, tol=1e-10, max_iter=CAPS[method])
    if not res.converged:
        assert name in NOT_CONVERGING[method] | KERNEL_DEPENDENT.get(method, set()), \
            f"{name}: unexpected failure: {res.message}"
        assert "not converged" in res.message and res.error >= 1e-10
        return
    check_result(res, P.W, P.q, P.mu, P.dim, 1e-10)
    assert violation(P.W, P.q, res.r, P.mu, P.dim) < 1e-7
    if P.x_ref is None or name in NON_UNIQUE:
        return
    scale = max(np.linalg.norm(P.x_ref), np.linalg.norm(P.q))
    assert np.linalg.norm(res.x - P.x_ref) / scale < 1e-6
