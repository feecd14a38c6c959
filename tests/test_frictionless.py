"""Frictionless problems solved on the normal rows alone, and the force scale of the natural-map error.

With ``mu = 0`` :func:`local_solvers.solve` solves the LCP on ``W_nn``. References, independent of that
path: the full-dimension solvers (``local_solvers._solve_full``, the code every frictional problem goes
through) on the same problem, the Siconos solution shipped with the FE-condensed FCLIB Hertz problem, the
complementarity conditions checked directly on ``(r, W r + q)``, and closed forms.
"""

import numpy as np
import pytest
import scipy.sparse as sp
from support.fclib_problems import FCLIB_DIR, needs_fclib
from support.local_problems import check_complementarity, random_problem

from dolfinx_fretting import fclib
from dolfinx_fretting import local_solvers as ls
from dolfinx_fretting.local_solvers import METHODS, natural_map_error, solve

TOL = 1e-12
# cond(W) <= ~20 and error < 1e-12: r and x agree with another solution of the (unique) problem to ~1e-11;
# 1e-9 keeps a margin and still rejects a wrong active set (differences of O(0.1)).
SOL = dict(rtol=1e-9, atol=1e-9)


def full_dimension(W, q, dim, method, tol=TOL, max_iter=100000, working_set=False):
    """The same problem through the full-dimension (frictional) code path, with mu = 0: by default its sweeps on
    every contact (the iterates the normal rows' sweeps reproduce bit for bit); ``working_set``: the sweeps on the
    closed and nearly closed contacts (solve's default for a dense W), another sequence of iterates."""
    W, q, mu, dim = ls._check_problem(W, q, 0.0, dim)
    counts = ls._Counts()
    r, x, err, _, status = ls._solve_full(W, q, mu, dim, method, tol, max_iter, np.zeros(q.size), False, 1.0, counts,
                                          working_set=working_set)
    assert status == 1
    return r, x, counts.total


@pytest.mark.parametrize("method", METHODS)
@pytest.mark.parametrize("dim", [2, 3])
@pytest.mark.parametrize("seed", range(4))
def test_normal_only_equals_full_dimension(method, dim, seed):
    W, q, _ = random_problem(seed, nc=20, dim=dim)
    res = solve(W, q, 0.0, dim, method=method, tol=TOL, max_iter=100000)
    assert res.converged and "normal problem (mu = 0)" in res.message, res.message
    r_f, x_f, its_f = full_dimension(W, q, dim, method)
    R = res.r.reshape(-1, dim)
    assert np.all(R[:, 1:] == 0.0) and np.all(R[:, 0] >= 0.0)
    np.testing.assert_allclose(res.r, r_f, **SOL)
    np.testing.assert_allclose(res.x, x_f, **SOL)
    np.testing.assert_allclose(res.x, W @ res.r + q, rtol=0, atol=1e-13 * np.abs(q).max())
    assert natural_map_error(W, q, res.r, 0.0, dim) < TOL
    check_complementarity(W, q, res.r, 0.0, dim)
    if method in ("uzawa", "nsgs"):
        # The same sweeps restricted to the normal rows: the same iterates, bit for bit.
        assert res.iterations == its_f
        np.testing.assert_array_equal(res.r, r_f)
        np.testing.assert_array_equal(res.x, x_f)
        # The full path's default (sweeps on the working set, then a check on all contacts): the same solution
        r_w, x_w, _ = full_dimension(W, q, dim, method, working_set=True)
        np.testing.assert_allclose(r_w, r_f, **SOL)
        np.testing.assert_allclose(x_w, x_f, **SOL)


def test_per_contact_zero_mu_and_mixed_mu():
    W, q, _ = random_problem(3, nc=12)
    a = solve(W, q, np.zeros(12), 2, tol=TOL)
    assert "normal problem" in a.message
    np.testing.assert_array_equal(a.r, solve(W, q, 0.0, 2, tol=TOL).r)
    mu = np.zeros(12)
    mu[5] = 0.3  # one frictional contact: the full problem
    b = solve(W, q, mu, 2, tol=TOL)
    assert b.converged and "normal problem" not in b.message
    check_complementarity(W, q, b.r, mu, 2)


def test_error_of_the_normal_problem_is_the_full_error():
    """natural_map_error of (r_n, 0) on the full problem with mu = 0 is the normal problem's error with the
    rho of the full blocks: the same floating-point value."""
    rng = np.random.default_rng(7)
    for dim in (2, 3):
        W, q, _ = random_problem(11, nc=15, dim=dim)
        r = np.zeros(q.size)
        r[::dim] = np.abs(rng.normal(size=15)) * (rng.random(15) < 0.6)
        rho = ls.block_rho(W, dim)
        Wn = np.ascontiguousarray(W[::dim, ::dim])
        qn, rn = np.ascontiguousarray(q[::dim]), np.ascontiguousarray(r[::dim])
        xn = Wn @ rn + qn
        e_normal = ls._lcp_error(rn, xn, rho, ls._lcp_scale(qn, rho))
        x = W @ r + q
        e_full = ls._error(r, x, np.zeros(15), rho, dim, ls._force_scale(q, np.zeros(15), rho, dim))
        assert e_full == pytest.approx(e_normal, rel=1e-14)  # x rows computed by different products
        assert natural_map_error(W, q, r, 0.0, dim) == pytest.approx(e_normal, rel=1e-14)


def test_sparse_matches_dense():
    W, q, _ = random_problem(5, nc=25, dim=3)
    for method in METHODS:
        d = solve(W, q, 0.0, 3, method=method, tol=TOL)
        s = solve(sp.csr_matrix(W), q, 0.0, 3, method=method, tol=TOL)
        assert s.converged, s.message
        np.testing.assert_allclose(s.r, d.r, **SOL)
        np.testing.assert_allclose(s.x, d.x, **SOL)


@pytest.mark.parametrize("method", METHODS)
def test_warm_start_projected_and_from_solution(method):
    W, q, _ = random_problem(2, nc=10)
    ref = solve(W, q, 0.0, 2, method=method, tol=TOL)
    again = solve(W, q, 0.0, 2, method=method, tol=TOL, r0=ref.r)
    assert again.converged and again.iterations == 0
    # A warm start outside the half-line (negative r_n, nonzero r_t) is projected, then solved.
    junk = np.random.default_rng(0).normal(size=q.size)
    res = solve(W, q, 0.0, 2, method=method, tol=TOL, r0=junk)
    assert res.converged, res.message
    np.testing.assert_allclose(res.r, ref.r, **SOL)


@pytest.mark.parametrize("method", METHODS)
def test_non_convergence_is_reported(method):
    W, q, _ = random_problem(4, nc=30)
    res = solve(W, q, 0.0, 2, method=method, tol=1e-15, max_iter=1)
    assert not res.converged and "not converged" in res.message and "normal problem" in res.message
    assert res.error >= 1e-15 and res.iterations == 1
    np.testing.assert_allclose(res.x, W @ res.r + q, rtol=0, atol=1e-13 * np.abs(q).max())
    with pytest.raises(ls.LocalSolverError, match="normal problem"):
        solve(W, q, 0.0, 2, method=method, tol=1e-15, max_iter=1, raise_on_failure=True)


def test_newton_safeguard_on_a_singular_normal_block():
    """W_nn of rank 4 (20 contacts): the active blocks are singular, so Newton falls back on projected
    Gauss-Seidel sweeps; the LCP still has the solution r* built in, and the result meets the contact law."""
    rng = np.random.default_rng(3)
    nc, dim = 20, 2
    B = rng.normal(size=(nc * dim, 4))
    W = B @ B.T
    W[1::2, 1::2] += np.eye(nc)  # tangential rows only: W_nn = (B B^T)_nn stays rank 4
    r_star = np.where(rng.random(nc) < 0.5, rng.random(nc), 0.0)
    x_star = np.where(r_star > 0, 0.0, rng.random(nc))
    q = np.zeros(nc * dim)
    q[::2] = x_star - W[::2, ::2] @ r_star
    q[1::2] = rng.normal(size=nc)
    for method in ("newton", "auto"):
        res = solve(W, q, 0.0, dim, method=method, tol=1e-10, max_iter=100000)
        assert res.converged, res.message
        assert res.sweeps > 0  # the safeguard was needed
        check_complementarity(W, q, res.r, 0.0, dim, rtol=1e-7)
        # x is unique even when r is not (W_nn singular): x_n = x*.
        np.testing.assert_allclose(res.x[::2], x_star, rtol=0, atol=1e-7 * np.abs(q).max())


@needs_fclib
@pytest.mark.parametrize("method", METHODS)
def test_fe_hertz_frictionless(method):
    """The FE-condensed frictionless Hertz problem (getfem): the Siconos solution, the full-dimension solve."""
    P = fclib.load(FCLIB_DIR / "getfem_hertz2d_frictionless.npz")
    assert np.all(P.mu == 0.0)
    res = solve(P.W, P.q, P.mu, P.dim, method=method, tol=1e-10, max_iter=20000)
    assert res.converged and "normal problem" in res.message, res.message
    # As in tests/test_fclib.py: residuals ~1e-10, cond(W) ~ 1e3: 1e-7 relative.
    assert np.linalg.norm(res.x - P.x_ref) <= 1e-7 * np.linalg.norm(P.x_ref)
    np.testing.assert_allclose(res.r, P.r_ref, rtol=0, atol=1e-7 * np.abs(P.r_ref).max())
    r_f, x_f, _ = full_dimension(P.W, P.q, P.dim, method, tol=1e-10)
    np.testing.assert_allclose(res.r, r_f, rtol=0, atol=1e-7 * np.abs(r_f).max())


def test_scene_delassus_matrix():
    """W of the built-in Hertz scene (coarse contact mesh): normal-only and full-dimension solves agree,
    for a preload that closes part of the candidates."""
    from mpi4py import MPI

    from dolfinx_fretting.scenes import load_scene
    from dolfinx_fretting.simulation import ContactModel

    model = ContactModel(load_scene("hertz", ["geometry.contact_mesh_size=0.02", "output.xdmf=false",
                                              "output.plots=false"]), MPI.COMM_SELF)
    cs = model.contact
    W = model.W
    q = np.zeros(cs.nc * cs.dim)
    q[::cs.dim] = cs.gap0 - 2e-4  # 0.2 um approach: the central candidates penetrate, the outer ones stay open
    q[1::cs.dim] = 1e-4           # and a tangential offset, which a frictionless contact ignores
    closed = 0
    for method in METHODS:
        res = solve(W, q, 0.0, cs.dim, method=method, tol=1e-12, max_iter=100000)
        assert res.converged, res.message
        r_f, x_f, _ = full_dimension(W, q, cs.dim, method)
        np.testing.assert_allclose(res.r, r_f, rtol=0, atol=1e-9 * np.abs(r_f).max())
        np.testing.assert_allclose(res.x, x_f, rtol=0, atol=1e-9 * np.abs(q).max())
        check_complementarity(W, q, res.r, 0.0, cs.dim)
        closed = int(np.count_nonzero(res.r[::cs.dim]))
    assert 1 < closed < cs.nc


# ---- the force scale of the error -----------------------------------------------------------------------
@pytest.mark.parametrize("mu", [0.0, 0.3])
def test_one_loaded_contact_among_open_ones(mu):
    """Contact 0 pressed by 1e-6, 29 others open by 1: the force of the loaded contact is solved to the
    tolerance of its own size. (With the former scale ||rho q||, dominated by the open gaps, the Uzawa
    stopped at ~1e-4 relative error in that force.)"""
    W, _, _ = random_problem(9, nc=30)
    q = np.zeros(60)
    q[::2] = 1.0
    q[0] = -1e-6
    res = solve(W, q, mu, 2, method="uzawa", tol=1e-10, max_iter=100000)
    assert res.converged, res.message
    # Closed form: the others stay open (x_n = 1 + W_n0 r_0 > 0 here), so contact 0 is alone: with mu = 0
    # r_0n = 1e-6 / W_00; with mu = 0.3 and q_t = 0 it sticks, r_0 = -W_aa^-1 q_a.
    B = W[:2, :2]
    r0 = np.array([1e-6 / B[0, 0], 0.0]) if mu == 0.0 else np.linalg.solve(B, -q[:2])
    assert mu == 0.0 or abs(r0[1]) <= mu * r0[0]
    assert np.all(res.r[2:] == 0.0)
    # error < 1e-10 relative to ||r||, cond(B) ~ 5: 1e-8 relative, where the former scale gave ~1e-4.
    np.testing.assert_allclose(res.r[:2], r0, rtol=0, atol=1e-8 * np.abs(r0).max())


def test_force_scale_ignores_open_contacts_and_caps_friction():
    rho = np.array([2.0, 3.0, 5.0])
    q = np.array([-1.0, 4.0, 10.0, 100.0, -2.0, 0.5])
    mu = np.array([0.5, 0.9, 3.0])
    # contact 0: (2 * -1, 2 * 0.5 * 4); contact 1 open; contact 2: (5 * -2, 5 * min(3, 1) * 0.5)
    expected = np.sqrt(4.0 + 16.0 + 100.0 + 6.25)
    assert ls._force_scale(q, mu, rho, 2) == pytest.approx(expected, rel=1e-15)
    assert ls._force_scale(q, mu, rho, 2) <= np.sqrt(np.sum((np.repeat(rho, 2) * q) ** 2))
    assert ls._force_scale(np.abs(q), mu, rho, 2) == 0.0


# ---- runs ---------------------------------------------------------------------------------------------------
def test_frictionless_cycles_compiled_equals_python(tmp_path):
    """Example 1's block with mu = 0, 3 cycles: the compiled loop (normal-only sweeps, no pattern reuse so
    that every increment goes through them) and the per-increment Python path agree; the run says it modelled
    the contact normal-only. Frictionless contact still slips, so Archard wear (k p |slip|) grows."""
    from dolfinx_fretting.plots import read_table
    from dolfinx_fretting.scenes import load_scene
    from dolfinx_fretting.simulation import run_scene

    common = ["geometry.nx=20", "geometry.ny=20", "output.xdmf=false", "output.plots=false", "loading.cycles=3",
              "contact.mu=0.0", "solver.local_tol=1e-12", "output.contact_profiles=false",
              "solver.pattern_reuse=false"]
    fast = run_scene(load_scene("stromberg-block", common), tmp_path / "fast", quiet=True)
    slow = run_scene(load_scene("stromberg-block", common + ["solver.cycle_kernel=false"]), tmp_path / "slow",
                     quiet=True)
    assert fast["cycle_path"] == "compiled" and slow["cycle_path"] == "python"
    assert "normal-only" in fast["modelled"]["friction"] and "normal-only" in slow["modelled"]["friction"]
    assert fast["max_wear_depth"] > 0 and fast["n_stick"] == 0 and fast["dissipated_energy"] == 0.0
    for key in ("max_wear_depth", "wear_area", "normal_force", "max_pressure"):
        # Two solutions of each increment to a natural-map error < 1e-12: equal to ~1e-10 relative.
        assert fast[key] == pytest.approx(slow[key], rel=1e-8), key
    a, b = read_table(tmp_path / "fast" / "history.csv"), read_table(tmp_path / "slow" / "history.csv")
    assert np.array_equal(a["n_slip"], b["n_slip"]) and np.all(a["tangential_force"] == 0.0)
    assert np.allclose(a["normal_force"], b["normal_force"], rtol=1e-8, atol=0)


def test_frictionless_hertz_run_same_as_full_dimension(tmp_path, monkeypatch):
    """The frictionless Hertz run (force-controlled preload): with the normal-only Uzawa, the same run as
    with every local problem solved in full dimension (the path before), bit for bit, since the sweeps are
    the same; and the peak pressure is Hertz's (1 % at h = 20 um, as in tests/test_hertz.py)."""
    from dolfinx_fretting.scenes import load_scene
    from dolfinx_fretting.simulation import run_scene

    ov = ["output.xdmf=false", "output.plots=false", "contact.mu=0.0", "loading.tangential_force=0.0",
          "geometry.contact_mesh_size=0.02"]
    normal = run_scene(load_scene("hertz", ov), tmp_path / "normal", quiet=True)

    def as_full(W, q, dim, method, tol, max_iter, r, rho_factor, counts, rho_err=None):
        return ls._solve_full(W, q, np.zeros(q.size // dim), dim, method, tol, max_iter, r, True, rho_factor,
                              counts, rho_err)

    monkeypatch.setattr(ls, "_solve_normal", as_full)
    full = run_scene(load_scene("hertz", ov), tmp_path / "full", quiet=True)
    for key in ("normal_force", "max_pressure", "contact_width", "n_slip", "n_open", "local_iterations"):
        assert normal[key] == full[key], key
    assert normal["max_pressure"] == pytest.approx(normal["hertz_max_pressure"], rel=0.01)


@pytest.mark.parametrize("method", METHODS)
@pytest.mark.parametrize("mu", [0.0, 0.5])
def test_no_penetration_gives_zero_forces_from_any_warm_start(method, mu):
    """q_n >= 0 everywhere (one gap exactly 0): r = 0 is the exact solution (x = q satisfies the law). From a
    warm start of the previous, loaded increment the Uzawa sweep only approaches it geometrically at the
    zero-gap contact, with an error relative to ||r|| that stays ~rho W_aa: the solver must return r = 0."""
    W, q, _ = random_problem(8, nc=10)
    q[::2] = np.abs(q[::2]) + 0.1
    q[4] = 0.0
    r0 = np.zeros(20)
    r0[::2] = 1.0
    res = solve(W, q, mu, 2, method=method, tol=1e-12, r0=r0)
    assert res.converged and res.iterations == 0 and res.error == 0.0, res.message
    assert np.all(res.r == 0.0) and np.array_equal(res.x, q)
    assert natural_map_error(W, q, res.r, mu, 2) == 0.0
