"""Small local contact problems (W, q, mu) and checks of a solution that do not depend on the solvers: random
well-conditioned problems, every solution of a 2D one by enumeration, De Saxce's conditions on (r, W r + q), a
sphere-flat-like problem on two elastic half-spaces. Used by tests/test_local_solvers.py,
tests/test_local_solver_suite.py, tests/test_frictionless.py, tests/test_working_set.py and (the half-space
problem, at 1000+ contacts) benchmarks/make_sphere_flat_problems.py. Also a fretting cycle of the half-space
problem run by the package's compiled loop, and the q of its increments (tests/test_working_set.py,
benchmarks/bench_local_speed.py)."""

import itertools

import numpy as np
import scipy.sparse as sp

from dolfinx_fretting import cycling, local_solvers


def check_complementarity(W, q, r, mu, dim, rtol=1e-8):
    """De Saxce's conditions per contact: r in K_mu, x_n >= 0 (x + mu|x_t| e_n in the dual cone) and
    r . (x + mu |x_t| e_n) = 0, with x = W r + q recomputed here. Tolerances relative to max |r| and
    max(|x|, |q|) (x alone is ~0 when every contact is closed)."""
    W = W.toarray() if sp.issparse(W) else W
    x = W @ r + q
    R, X = r.reshape(-1, dim), x.reshape(-1, dim)
    mu = np.broadcast_to(mu, len(R))
    rs, xs = max(np.abs(R).max(), 1e-300), max(np.abs(X).max(), np.abs(q).max(), 1e-300)
    xhat = X.copy()
    xhat[:, 0] += mu * np.linalg.norm(X[:, 1:], axis=1)
    assert np.all(R[:, 0] >= -rtol * rs), "negative normal force"
    assert np.all(np.linalg.norm(R[:, 1:], axis=1) <= mu * R[:, 0] + rtol * rs), "force outside the cone"
    assert np.all(X[:, 0] >= -rtol * xs), "penetration"
    assert np.all(np.abs(np.sum(R * xhat, axis=1)) <= rtol * rs * xs), "complementarity r.x^ != 0"
    return x


def enumerate_2d(W, q, mu):
    """All solutions of a 2D problem by trying every (open, stick, slip+, slip-) assignment."""
    nc = len(q) // 2
    sols = []
    for states in itertools.product(("open", "stick", "slip+", "slip-"), repeat=nc):
        A = np.zeros((2 * nc, 2 * nc))
        b = np.zeros(2 * nc)
        for a, s in enumerate(states):
            n, t = 2 * a, 2 * a + 1
            if s == "open":
                A[n, n] = A[t, t] = 1.0
            elif s == "stick":
                A[n], A[t], b[n], b[t] = W[n], W[t], -q[n], -q[t]
            else:  # slip in direction sgn: x_n = 0, r_t = -sgn mu r_n
                sgn = 1.0 if s == "slip+" else -1.0
                A[n], b[n] = W[n], -q[n]
                A[t, t], A[t, n] = 1.0, sgn * mu
        try:
            r = np.linalg.solve(A, b)
        except np.linalg.LinAlgError:
            continue
        x = W @ r + q
        eps = 1e-12 * max(1.0, np.abs(r).max(), np.abs(x).max())
        ok = True
        for a, s in enumerate(states):
            rn, rt, xn, xt = r[2 * a], r[2 * a + 1], x[2 * a], x[2 * a + 1]
            if s == "open":
                ok &= xn >= -eps
            elif s == "stick":
                ok &= rn >= -eps and abs(rt) <= mu * rn + eps
            else:
                ok &= rn >= -eps and (1.0 if s == "slip+" else -1.0) * xt >= -eps
        if ok:
            sols.append((states, r, x))
    return sols


def random_problem(seed, nc, dim=2, mu=0.3):
    rng = np.random.default_rng(seed)
    m = dim * nc
    A = rng.normal(size=(m, m))
    W = A @ A.T / m + np.eye(m)  # SPD, cond ~ 5
    q = rng.normal(size=m)
    q[::dim] -= 0.5  # most contacts pressed
    return W, q, mu


def half_space(n_side: int = 16, h: float = 1.0, nu: float = 0.3, E: float = 1.0) -> tuple[np.ndarray, np.ndarray]:
    """W of two like elastic half-spaces on an ``n_side^2`` grid of contacts (spacing ``h``): Boussinesq's normal
    and Cerruti's tangential point-force compliances (the 1/r decay of the FE W of the sphere-flat scene), the
    self terms from a uniform load on an ``h x h`` square (centre value: ``4 ln(1 + sqrt 2) / h`` for ``1/r``);
    like materials: no normal-tangential coupling. Blocks ordered (n, t1, t2). Returns (W, contact coordinates)."""
    side = (np.arange(n_side) - (n_side - 1) / 2) * h
    xy = np.array([(x, y) for x in side for y in side])
    dx = xy[:, None, 0] - xy[None, :, 0]
    dy = xy[:, None, 1] - xy[None, :, 1]
    dist = np.hypot(dx, dy)
    self_term = 4.0 * np.log(1.0 + np.sqrt(2.0)) / h
    np.fill_diagonal(dist, 1.0)
    inv = 1.0 / dist
    np.fill_diagonal(inv, self_term)
    cx, cy = dx * inv, dy * inv  # direction cosines (0 on the diagonal)
    np.fill_diagonal(cx, np.sqrt(0.5))  # the square's average of cos^2 is 1/2
    np.fill_diagonal(cy, np.sqrt(0.5))
    two_bodies = 2.0 / (np.pi * E)
    nc = xy.shape[0]
    W = np.zeros((3 * nc, 3 * nc))
    W[0::3, 0::3] = two_bodies * (1 - nu**2) * inv
    W[1::3, 1::3] = two_bodies * (1 + nu) * ((1 - nu) + nu * cx**2) * inv
    W[2::3, 2::3] = two_bodies * (1 + nu) * ((1 - nu) + nu * cy**2) * inv
    off = two_bodies * (1 + nu) * nu * cx * cy * inv
    np.fill_diagonal(off, 0.0)
    W[1::3, 2::3] = off
    W[2::3, 1::3] = off
    return W, xy


def sphere_flat_q(xy: np.ndarray, radius: float, approach: float, slip: float) -> np.ndarray:
    """q of a sphere of radius ``radius`` pressed ``approach`` into the flat and moved by ``slip`` along x."""
    q = np.zeros(3 * xy.shape[0])
    q[0::3] = (xy[:, 0] ** 2 + xy[:, 1] ** 2) / (2.0 * radius) - approach
    q[1::3] = -slip
    return q


def sphere_flat_cycle(W: np.ndarray, xy: np.ndarray, radius: float, approach: float, slips: np.ndarray,
                      mu: float = 0.5, wear: float = 0.0, normal_force: float | None = None,
                      hold_block: bool | None = True, loop=cycling, start: dict | None = None,
                      float32_sweeps: bool = False) -> dict:
    """The package's compiled cycle loop on a half-space problem (:func:`half_space`): a sphere of radius ``radius``
    pressed ``approach`` into the flat (or, with ``normal_force``, pressed by that total normal force: the
    force-controlled loop finds the approach) and moved by ``slips[j]`` along x at increment ``j``, each increment
    warm started from the one before, Archard's wear coefficient ``wear`` on a unit tributary area, tol 1e-10.

    The obstacle moves the contacts' local frames as one: its translation (approach, slip, 0) enters every
    contact's rows (normal, t1, t2) with weight -1 (``G``), no other load. ``W`` must be exactly symmetric (given as
    the loop's W^T, as the package's W is). ``loop``: the module of the loop (``dolfinx_fretting.cycling``, or
    another version's for a benchmark; ``hold_block`` None: neither it nor ``float32_sweeps`` is passed, for a version
    without them).
    ``start``: the ``end`` of an earlier call (its wear gap, positions, forces and every increment's forces): this
    cycle continues from there, each increment warm started from the same increment of that cycle (the package's
    default warm start, ``solver.warm_start = "cycle"``; under force control from the increment before, as the
    package's force-controlled loop). Returns the loop's outputs: ``done``, ``status``, ``error``,
    ``rows``, per increment ``r``, ``x``, ``y``, ``wear_gap``, ``states``, the obstacle ``d`` (found where force
    controlled), local ``solves``, the gap ``g0``, and the contact-pattern cache's ``counts`` (``counts[3]``: solves
    on the held block; ``counts[4]``: solves that gathered one)."""
    nc, n = xy.shape[0], len(slips)
    m = 3 * nc
    steps = local_solvers.block_rho(W, 3)
    mu_arr = np.full(nc, mu)
    g0 = (xy[:, 0] ** 2 + xy[:, 1] ** 2) / (2.0 * radius)
    G = np.zeros((m, 3))
    for c in range(3):
        G[c::3, c] = 1.0
    targets = np.zeros((n, 3))
    targets[:, 0] = approach if normal_force is None else normal_force
    targets[:, 1] = slips
    Q, S = np.zeros((1, m)), np.zeros((n, 1))
    tributary, abscissa = np.ones(nc), xy[:, 0].copy()
    if start is None:
        warm, wear_gap, y, r_last, r_warm = 0, np.zeros(nc), np.zeros(m), np.zeros(m), np.zeros((n, m))
    else:
        warm = 1
        wear_gap, y, r_last, r_warm = (start[k].copy() for k in ("wear_gap", "y", "r_last", "r_warm"))
    k = np.full(nc, wear)
    out_r, out_x, out_y = np.zeros((n, m)), np.zeros((n, m)), np.zeros((n, m))
    out_wear, out_states = np.zeros((n, nc)), np.zeros((n, nc), dtype=np.int8)
    rows = np.zeros((n, loop.N_ROW))
    cache = loop.ActivePatternCache(n, nc, 3)
    held = loop.FrictionEvolution.held().arguments()
    hold = () if hold_block is None else (hold_block, float32_sweeps)
    if hold_block is not None and hasattr(loop, "warm_pattern_solve"):   # a version whose loops take warm_pattern
        hold += (False,)
    found, solves = targets.copy(), np.ones(n, dtype=np.int64)
    if normal_force is None:
        done, status, error = loop.run_increments(
            W, steps, mu_arr, 3, g0, wear_gap, G, targets, Q, S, tributary, abscissa, y, r_last, r_warm, warm, k,
            1e-10, 20000, local_solvers._REFRESH, True, out_r, out_x, out_y, out_wear, out_states, rows, False,
            cache.pattern, cache.lu, cache.piv, cache.lu_ok, cache.counts, cache.factor_mu, *held, *hold)
    else:
        # Force along each axis: the sum of the contact forces' components (F = A r); T: the obstacle's translation
        # per unit component (the identity). The first guess: the approach given, a point stiffness as the slope.
        A = np.zeros((3, m))
        for c in range(3):
            A[c, c::3] = 1.0
        d = np.array([approach, 0.0, 0.0]) if start is None else start["d"][-1].copy()
        stiffness = np.full(3, 1.0 / W[0, 0])
        failure, force = np.zeros(4), np.zeros(3)
        done, status, error = loop.run_force_increments(
            W, steps, mu_arr, 3, g0, wear_gap, G, np.eye(3), A, targets, np.array([True, False, False]), d,
            stiffness, 1e-8, 60, Q, S, tributary, abscissa, y, r_last, r_warm, k, 1e-10, 20000,
            local_solvers._REFRESH, True, out_r, out_x, out_y, out_wear, out_states, rows, found, solves, False,
            cache.pattern, cache.lu, cache.piv, cache.lu_ok, cache.counts, failure, force, cache.factor_mu, *held,
            *hold)
    return {"done": done, "status": status, "error": error, "rows": rows, "r": out_r, "x": out_x, "y": out_y,
            "wear_gap": out_wear, "states": out_states, "d": found, "solves": solves, "g0": g0,
            "counts": cache.counts.copy(),
            "end": {"wear_gap": wear_gap, "y": y, "r_last": r_last, "r_warm": out_r.copy(), "d": found}}


def cycle_q(out: dict, j: int) -> np.ndarray:
    """q of increment ``j`` of :func:`sphere_flat_cycle`'s loop, from its outputs, in the loop's arithmetic:
    normal rows ``(g0 + wear gap before) - approach``, tangential ``-slip - y before`` (x: the slip increment)."""
    nc = out["g0"].size
    before_wear = out["wear_gap"][j - 1] if j > 0 else np.zeros(nc)
    before_y = out["y"][j - 1] if j > 0 else np.zeros(3 * nc)
    q = np.empty(3 * nc)
    q[0::3] = (out["g0"] + before_wear) - out["d"][j, 0]
    q[1::3] = -out["d"][j, 1] - before_y[1::3]
    q[2::3] = -out["d"][j, 2] - before_y[2::3]
    return q
