"""Local frictional contact problem on the Delassus operator: projection, Uzawa solver, contact states.

The local problem (paper eq. 28, FCLIB/Siconos form) is: find ``r`` and ``x`` with

    x = W r + q,    and for every contact alpha:  -(x^alpha + mu |x_t^alpha| e_n)  in  N_{K_mu}(r^alpha),

i.e. Signorini's conditions on ``(x_n, r_n)`` and Coulomb's law written with De Saxce's modified relative
displacement (paper eq. 22). Vectors are stored contact by contact, each block ordered ``(n, t1[, t2])``
like FCLIB and Siconos (the paper writes ``(t1, t2, n)``). ``K_mu = {r : |r_t| <= mu r_n}`` is the Coulomb
cone; its polar cone is ``K_mu° = {y : mu |y_t| <= -y_n}``.

The solver is the paper's Algorithm 1, a Gauss-Seidel sweep over the contacts, with one correction: eq. (31)
as printed builds the predictor from ``x^{alpha beta}``, which leaves out the contact's own term
``W_aa r^a``, so the exact solution is not a fixed point of that iteration. The predictor here uses the
full current ``x^a = sum_b W_ab r^b + q^a``:

    r* = r^a - rho_a (x^a + mu |x_t^a| e_n),      r^a <- Proj_{K_mu}(r*),

with ``rho_a = 1 / ||W_aa||_2`` (``1/lambda_max`` for a symmetric block), so that the step is a projected
gradient step no longer than the block's curvature allows.

Convergence is measured by a unit-free natural-map residual (see :func:`natural_map_error`), not by the
relative change of ``r`` of eq. (34), which can be small while far from the solution.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numba
import numpy as np
import scipy.sparse as sp

__all__ = [
    "OPEN",
    "STICK",
    "SLIP",
    "METHODS",
    "LocalResult",
    "LocalSolverError",
    "block_rho",
    "contact_states",
    "de_saxce_x",
    "natural_map_error",
    "project_coulomb",
    "solve",
]

OPEN = 0   #: Contact state code: separated, r = 0.
STICK = 1  #: Contact state code: closed, strictly inside the cone.
SLIP = 2   #: Contact state code: closed, on the cone boundary.

METHODS = ("uzawa",)

# Sweeps between exact recomputations of x = W r + q, bounding the drift of the incremental update.
_REFRESH = 200


class LocalSolverError(RuntimeError):
    """The local solver did not converge (raised only with ``raise_on_failure=True``)."""


@dataclass
class LocalResult:
    """Solution of a local problem.

    Attributes:
        r: Contact forces, ``(n, t...)`` per contact, length ``dim * nc``.
        x: Relative displacements ``W r + q`` (recomputed exactly at exit).
        iterations: Gauss-Seidel sweeps done (0 when the initial guess already met the tolerance).
        error: Natural-map residual of ``r`` (see :func:`natural_map_error`), the stopping criterion.
        converged: ``error < tol`` with finite values.
        method: Solver name.
        message: Human-readable outcome: iterations, error reached, tolerance.
        change: Relative change ``||r_k - r_{k-1}|| / ||r_k||`` of the last sweep (paper eq. 34),
            for information only.
    """

    r: np.ndarray
    x: np.ndarray
    iterations: int
    error: float
    converged: bool
    method: str
    message: str
    change: float = 0.0


# ----------------------------------------------------------------------------------------------------------
# Projection onto the Coulomb cone
# ----------------------------------------------------------------------------------------------------------
@numba.njit(cache=True)
def _project(rn: float, t1: float, t2: float, mu: float) -> tuple[float, float, float]:
    """Euclidean projection of (rn, t1, t2) onto K_mu (paper eq. 24 in (n, t) order); t2 = 0 in 2D."""
    nt = math.sqrt(t1 * t1 + t2 * t2)
    # Separating first: with mu = 0 and r = (r_n < 0, 0) the sticking test 0 <= 0 * r_n also holds.
    if mu * nt <= -rn:                     # separating: inside the polar cone (also r = 0)
        return 0.0, 0.0, 0.0
    if nt <= mu * rn:                      # sticking: inside the cone
        return rn, t1, t2
    # Sliding: orthogonal projection on the generator (1, mu t/|t|) / sqrt(1 + mu^2); here nt > 0 since
    # nt > mu rn and mu nt > -rn cannot both hold with nt = 0.
    a = (rn + mu * nt) / (1.0 + mu * mu)
    s = mu * a / nt
    return a, s * t1, s * t2


def project_coulomb(r: np.ndarray, mu: float) -> np.ndarray:
    """Project one contact force onto the Coulomb cone ``K_mu = {r_n >= 0, |r_t| <= mu r_n}``.

    Paper eq. (24) with the components ordered ``(n, t1[, t2])``:

    - separating (``mu |r_t| <= -r_n``, r in the polar cone): ``0``;
    - sticking (``|r_t| <= mu r_n``): ``r``;
    - sliding: ``r - (|r_t| - mu r_n) / (1 + mu^2) * (r_t/|r_t| - mu e_n)``, which is
      ``(r_n + mu |r_t|) / (1 + mu^2) * (1, mu r_t/|r_t|)``, the orthogonal projection on the cone's surface.

    Args:
        r: One contact's force, length 2 or 3, ordered ``(n, t1[, t2])``. A ``(nc, dim)`` array projects
            every row.
        mu: Friction coefficient, ``>= 0``.

    Returns:
        The projection, same shape as ``r``.
    """
    r = np.asarray(r, dtype=float)
    mu = _check_mu_scalar(mu)
    if r.ndim not in (1, 2) or r.shape[-1] not in (2, 3):
        raise ValueError(f"r: expected shape (2,), (3,) or (nc, 2|3), got {r.shape}")
    rows = np.atleast_2d(r)
    out = np.empty_like(rows)
    for i, row in enumerate(rows):
        t2 = row[2] if row.size == 3 else 0.0
        pn, p1, p2 = _project(row[0], row[1], t2, mu)
        out[i, :2] = pn, p1
        if row.size == 3:
            out[i, 2] = p2
    return out.reshape(r.shape)


@numba.njit(cache=True)
def _project_all(r: np.ndarray, mu: np.ndarray, dim: int) -> None:
    """Project every contact's block of ``r`` onto its cone, in place."""
    for a in range(mu.size):
        o = a * dim
        t2 = r[o + 2] if dim == 3 else 0.0
        pn, p1, p2 = _project(r[o], r[o + 1], t2, mu[a])
        r[o] = pn
        r[o + 1] = p1
        if dim == 3:
            r[o + 2] = p2


def de_saxce_x(x: np.ndarray, mu: float | np.ndarray) -> np.ndarray:
    """De Saxce's modified relative displacement ``x + mu |x_t| e_n`` (paper eq. 22).

    Args:
        x: One contact's ``(n, t1[, t2])`` vector, or a ``(nc, dim)`` array of them.
        mu: Friction coefficient(s): a scalar, or one per row of a 2-D ``x``.

    Returns:
        The modified vector, same shape as ``x``.
    """
    x = np.array(x, dtype=float)
    if x.ndim not in (1, 2) or x.shape[-1] not in (2, 3):
        raise ValueError(f"x: expected shape (2,), (3,) or (nc, 2|3), got {x.shape}")
    mu = np.asarray(mu, dtype=float)
    if np.any(mu < 0) or not np.all(np.isfinite(mu)):
        raise ValueError("mu: friction coefficients must be finite and >= 0")
    x[..., 0] += mu * np.linalg.norm(x[..., 1:], axis=-1)
    return x


# ----------------------------------------------------------------------------------------------------------
# Residual and solver kernels
# ----------------------------------------------------------------------------------------------------------
@numba.njit(cache=True)
def _blocked_norm(v: np.ndarray, rho: np.ndarray, dim: int) -> float:
    """|| (rho_a v^a)_a ||."""
    s = 0.0
    for a in range(rho.size):
        for k in range(dim):
            s += (rho[a] * v[a * dim + k]) ** 2
    return math.sqrt(s)


@numba.njit(cache=True)
def _error(r: np.ndarray, x: np.ndarray, mu: np.ndarray, rho: np.ndarray, dim: int, qnorm: float) -> float:
    """Natural-map residual ||r - P_K(r - rho (x + mu|x_t| e_n))|| / max(||rho q||, ||r||)."""
    s = 0.0
    rr = 0.0
    for a in range(mu.size):
        o = a * dim
        x2 = x[o + 2] if dim == 3 else 0.0
        r2 = r[o + 2] if dim == 3 else 0.0
        nxt = math.sqrt(x[o + 1] ** 2 + x2 * x2)
        ra = rho[a]
        pn, p1, p2 = _project(r[o] - ra * (x[o] + mu[a] * nxt), r[o + 1] - ra * x[o + 1], r2 - ra * x2, mu[a])
        s += (r[o] - pn) ** 2 + (r[o + 1] - p1) ** 2 + (r2 - p2) ** 2
        rr += r[o] ** 2 + r[o + 1] ** 2 + r2 * r2
    den = max(qnorm, math.sqrt(rr))
    if den == 0.0:
        # q = 0 and r = 0: r = 0 is the exact solution and s = 0.
        return math.sqrt(s)
    return math.sqrt(s) / den


@numba.njit(cache=True)
def _recompute_x(Wc: np.ndarray, indptr: np.ndarray, indices: np.ndarray, data: np.ndarray, sparse: bool,
                 q: np.ndarray, r: np.ndarray, x: np.ndarray) -> None:
    """x = W r + q, by columns of W (rows of Wc = W^T when dense, CSC when sparse), skipping r_j = 0."""
    m = q.size
    for i in range(m):
        x[i] = q[i]
    for j in range(m):
        rj = r[j]
        if rj == 0.0:
            continue
        if sparse:
            for p in range(indptr[j], indptr[j + 1]):
                x[indices[p]] += data[p] * rj
        else:
            for i in range(m):
                x[i] += Wc[j, i] * rj


@numba.njit(cache=True)
def _add_column(Wc: np.ndarray, indptr: np.ndarray, indices: np.ndarray, data: np.ndarray, sparse: bool,
                j: int, d: float, x: np.ndarray) -> None:
    """x += W[:, j] d."""
    if d == 0.0:
        return
    if sparse:
        for p in range(indptr[j], indptr[j + 1]):
            x[indices[p]] += data[p] * d
    else:
        row = Wc[j]
        for i in range(x.size):
            x[i] += row[i] * d


@numba.njit(cache=True)
def _uzawa_kernel(Wc: np.ndarray, indptr: np.ndarray, indices: np.ndarray, data: np.ndarray, sparse: bool,
                  q: np.ndarray, mu: np.ndarray, rho: np.ndarray, rho_err: np.ndarray, dim: int,
                  r: np.ndarray, x: np.ndarray, tol: float, max_iter: int, refresh: int
                  ) -> tuple[int, float, float, int]:
    """Gauss-Seidel Uzawa sweeps (paper Algorithm 1, corrected eq. 31). ``x = W r + q`` on entry.

    Returns (sweeps, error, change, status) with status 1 converged, 0 max_iter, 2 non-finite.
    """
    nc = mu.size
    qnorm = _blocked_norm(q, rho_err, dim)
    err = _error(r, x, mu, rho_err, dim, qnorm)
    if err < tol:
        return 0, err, 0.0, 1
    change = np.inf
    for k in range(1, max_iter + 1):
        dr2 = 0.0
        r2 = 0.0
        for a in range(nc):
            o = a * dim
            ra = rho[a]
            x2 = x[o + 2] if dim == 3 else 0.0
            rt2 = r[o + 2] if dim == 3 else 0.0
            nxt = math.sqrt(x[o + 1] ** 2 + x2 * x2)
            # Predictor on De Saxce's modified displacement with the full local x (own term included).
            pn, p1, p2 = _project(r[o] - ra * (x[o] + mu[a] * nxt), r[o + 1] - ra * x[o + 1],
                                  rt2 - ra * x2, mu[a])
            d0 = pn - r[o]
            d1 = p1 - r[o + 1]
            d2 = p2 - rt2
            if d0 != 0.0 or d1 != 0.0 or d2 != 0.0:
                r[o] = pn
                r[o + 1] = p1
                _add_column(Wc, indptr, indices, data, sparse, o, d0, x)
                _add_column(Wc, indptr, indices, data, sparse, o + 1, d1, x)
                if dim == 3:
                    r[o + 2] = p2
                    _add_column(Wc, indptr, indices, data, sparse, o + 2, d2, x)
                dr2 += d0 * d0 + d1 * d1 + d2 * d2
            r2 += pn * pn + p1 * p1 + p2 * p2
        change = math.sqrt(dr2) / max(math.sqrt(r2), 1e-300)
        if k % refresh == 0:
            _recompute_x(Wc, indptr, indices, data, sparse, q, r, x)
        err = _error(r, x, mu, rho_err, dim, qnorm)
        if not (math.isfinite(err) and math.isfinite(change)):
            return k, err, change, 2
        if err < tol:
            # Confirm on the exact x: the incremental update accumulates rounding.
            _recompute_x(Wc, indptr, indices, data, sparse, q, r, x)
            err = _error(r, x, mu, rho_err, dim, qnorm)
            if err < tol:
                return k, err, change, 1
    return max_iter, err, change, 0


# ----------------------------------------------------------------------------------------------------------
# Python front end
# ----------------------------------------------------------------------------------------------------------
def _check_mu_scalar(mu: float) -> float:
    try:
        mu = float(mu)
    except (TypeError, ValueError):
        raise ValueError(f"mu: expected a number, got {mu!r}") from None
    if not math.isfinite(mu) or mu < 0:
        raise ValueError(f"mu: friction coefficient must be finite and >= 0, got {mu}")
    return mu


def _as_mu(mu: float | np.ndarray, nc: int) -> np.ndarray:
    arr = np.asarray(mu, dtype=float)
    if arr.ndim == 0:
        arr = np.full(nc, float(arr))
    elif arr.shape != (nc,):
        raise ValueError(f"mu: expected a scalar or an array of nc = {nc} coefficients, "
                         f"got shape {arr.shape}")
    if not np.all(np.isfinite(arr)) or np.any(arr < 0):
        raise ValueError("mu: friction coefficients must be finite and >= 0")
    return np.ascontiguousarray(arr)


def _check_problem(W, q, mu, dim) -> tuple[np.ndarray | sp.csc_matrix, np.ndarray, np.ndarray, int]:
    if dim not in (2, 3) or isinstance(dim, bool):
        raise ValueError(f"dim: expected 2 or 3, got {dim!r}")
    q = np.asarray(q, dtype=float)
    if q.ndim != 1:
        raise ValueError(f"q: expected a 1-D array, got shape {q.shape}")
    m = q.size
    if m % dim:
        raise ValueError(f"q: length {m} is not a multiple of dim = {dim}")
    if not np.all(np.isfinite(q)):
        raise ValueError("q: contains non-finite values")
    if sp.issparse(W):
        W = sp.csc_matrix(W, dtype=float, copy=True)
        W.sum_duplicates()
        values = W.data
    else:
        W = np.asarray(W, dtype=float)
        values = W
    if W.shape != (m, m):
        raise ValueError(f"W: expected shape ({m}, {m}) to match q, got {W.shape}")
    if not np.all(np.isfinite(values)):
        raise ValueError("W: contains non-finite values")
    return W, q, _as_mu(mu, m // dim), int(dim)


def _diag_blocks(W: np.ndarray | sp.spmatrix, dim: int) -> np.ndarray:
    nc = W.shape[0] // dim
    if sp.issparse(W):
        # Block-diagonal part: rows and columns in the same contact.
        coo = sp.coo_matrix(W)
        keep = coo.row // dim == coo.col // dim
        blocks = np.zeros((nc, dim, dim))
        np.add.at(blocks, (coo.row[keep] // dim, coo.row[keep] % dim, coo.col[keep] % dim), coo.data[keep])
        return blocks
    idx = np.arange(nc)[:, None] * dim + np.arange(dim)
    return W[idx[:, :, None], idx[:, None, :]]


def block_rho(W: np.ndarray | sp.spmatrix, dim: int) -> np.ndarray:
    """Per-contact step ``rho_a = 1 / ||W_aa||_2`` (``1/lambda_max(W_aa)`` for a symmetric block).

    A contact whose diagonal block is zero (or below ``1e-14`` of the largest) gets the step of the largest
    block, so the value stays finite and still scales as ``1/W``. If ``W`` is zero, ``rho = 1``.

    Args:
        W: Delassus matrix, dense or scipy sparse, ``(dim nc, dim nc)``.
        dim: 2 or 3.

    Returns:
        ``rho``, one value per contact.
    """
    blocks = _diag_blocks(W, dim)
    if blocks.shape[0] == 0:
        return np.zeros(0)
    norms = np.linalg.norm(blocks, ord=2, axis=(1, 2))
    top = norms.max()
    if top == 0.0:
        return np.ones_like(norms)
    norms = np.where(norms > 1e-14 * top, norms, top)
    return 1.0 / norms


def natural_map_error(W: np.ndarray | sp.spmatrix, q: np.ndarray, r: np.ndarray, mu: float | np.ndarray,
                      dim: int) -> float:
    """Unit-free natural-map residual of a candidate solution ``r``.

    With ``x = W r + q``, ``rho_a = 1/||W_aa||_2`` (:func:`block_rho`) and ``P`` the projection on ``K_mu``:

        error = sqrt( sum_a || r^a - P(r^a - rho_a (x^a + mu_a |x_t^a| e_n)) ||^2 ) / max(||rho q||, ||r||)

    where ``(rho q)^a = rho_a q^a``. It vanishes exactly at solutions (fixed point of the De Saxce projection,
    paper eqs. 22-23). Numerator and denominator are forces, and under ``W -> s W``, ``q -> c q`` (so
    ``r -> (c/s) r``) both scale by ``c/s``: the error does not depend on the units of the problem. It is
    Siconos's fc3d natural-map error with the unit step replaced by ``rho_a`` and ``||q||`` by
    ``||rho q||``. If ``q = 0`` and ``r = 0`` it is 0.

    Args:
        W: Delassus matrix (dense or scipy sparse).
        q: Free relative displacement, length ``dim nc``.
        r: Candidate contact forces.
        mu: Friction coefficient(s), scalar or one per contact.
        dim: 2 or 3.

    Returns:
        The residual.
    """
    W, q, mu_arr, dim = _check_problem(W, q, mu, dim)
    r = _check_vector(r, q.size, "r")
    rho = block_rho(W, dim)
    x = W @ r + q
    return float(_error(r, np.ascontiguousarray(x), mu_arr, rho, dim, _blocked_norm(q, rho, dim)))


def _check_vector(v, m: int, name: str) -> np.ndarray:
    v = np.array(v, dtype=float)
    if v.shape != (m,):
        raise ValueError(f"{name}: expected shape ({m},), got {v.shape}")
    if not np.all(np.isfinite(v)):
        raise ValueError(f"{name}: contains non-finite values")
    return v


def solve(W: np.ndarray | sp.spmatrix, q: np.ndarray, mu: float | np.ndarray, dim: int,
          method: str = "uzawa", tol: float = 1e-10, max_iter: int = 10000, r0: np.ndarray | None = None,
          rho: float | None = None, raise_on_failure: bool = False) -> LocalResult:
    """Solve the local frictional contact problem ``x = W r + q``, ``r`` and ``x`` satisfying Coulomb's law.

    ``method="uzawa"`` is the paper's Algorithm 1 as a Gauss-Seidel sweep over contacts, with eq. (31)
    corrected to use the full local ``x^a`` (own term ``W_aa r^a`` included)::

        r* = r^a - rho_a (x^a + mu |x_t^a| e_n),   r^a <- Proj_K(r*),   x += W[:, a] (r^a_new - r^a_old)

    ``x`` is updated incrementally, so a sweep costs one column product per contact whose force changed
    (``O(m^2)`` dense, ``O(nnz)`` sparse), and is recomputed exactly every 200 sweeps and before declaring
    convergence. The iteration stops when :func:`natural_map_error` ``< tol``.

    A sparse ``W`` is used as CSC (columns are what the update needs); a dense one through its transpose.

    Args:
        W: Delassus matrix ``(m, m)``, ``m = dim * nc``, dense array or scipy sparse matrix.
        q: Free relative displacement, length ``m`` (gaps in the normal rows).
        mu: Friction coefficient, scalar or one per contact, ``>= 0``.
        dim: 2 or 3.
        method: ``"uzawa"``.
        tol: Tolerance on the unit-free natural-map error.
        max_iter: Maximum number of sweeps.
        r0: Initial guess (warm start), projected on the cones; zero by default.
        rho: Optional factor multiplying the default per-contact step ``1/||W_aa||_2``.
        raise_on_failure: Raise :class:`LocalSolverError` instead of returning ``converged=False``.

    Returns:
        A :class:`LocalResult`. ``converged`` is False (with a message) when ``max_iter`` is reached or a
        non-finite value appears.

    Raises:
        ValueError: invalid argument (the message names it).
        LocalSolverError: no convergence and ``raise_on_failure``.
    """
    if method not in METHODS:
        raise ValueError(f"method: expected one of {METHODS}, got {method!r}")
    W, q, mu_arr, dim = _check_problem(W, q, mu, dim)
    m = q.size
    nc = m // dim
    if not (isinstance(tol, (int, float, np.floating)) and math.isfinite(tol) and tol > 0):
        raise ValueError(f"tol: expected a finite number > 0, got {tol!r}")
    if isinstance(max_iter, bool) or not isinstance(max_iter, (int, np.integer)) or max_iter < 1:
        raise ValueError(f"max_iter: expected an integer >= 1, got {max_iter!r}")
    if rho is not None and not (isinstance(rho, (int, float, np.floating)) and math.isfinite(rho)
                                and rho > 0):
        raise ValueError(f"rho: expected a finite factor > 0, got {rho!r}")
    r = np.zeros(m) if r0 is None else _check_vector(r0, m, "r0")

    if nc == 0:
        return LocalResult(np.zeros(0), np.zeros(0), 0, 0.0, True, method, "no contacts", 0.0)

    rho_err = block_rho(W, dim)
    rho_vec = rho_err * (1.0 if rho is None else float(rho))
    if r0 is not None:
        # A warm start from another problem may lie outside the cones.
        _project_all(r, mu_arr, dim)

    empty_i = np.zeros(1, dtype=np.int64)
    empty_f = np.zeros(1)
    if sp.issparse(W):
        Wc = np.zeros((1, 1))
        indptr = W.indptr.astype(np.int64)
        indices = W.indices.astype(np.int64)
        data = np.ascontiguousarray(W.data)
        sparse = True
    else:
        Wc = np.ascontiguousarray(W.T)
        indptr, indices, data = empty_i, empty_i, empty_f
        sparse = False
    x = np.empty(m)
    _recompute_x(Wc, indptr, indices, data, sparse, q, r, x)
    its, err, change, status = _uzawa_kernel(Wc, indptr, indices, data, sparse, q, mu_arr, rho_vec, rho_err,
                                              dim, r, x, float(tol), int(max_iter), _REFRESH)
    converged = status == 1
    if status == 0:
        # Report the x of the returned r, not the incrementally updated one.
        _recompute_x(Wc, indptr, indices, data, sparse, q, r, x)
    if converged:
        message = f"converged in {its} sweeps: error {err:.3e} < tol {tol:.1e}"
    elif status == 2:
        message = (f"non-finite value after {its} sweeps (error {err}, change {change}); "
                   f"tolerance {tol:.1e} not reached")
    else:
        message = (f"not converged after max_iter = {its} sweeps: error {err:.3e} >= tol {tol:.1e} "
                   f"(last relative change of r {change:.3e})")
    if not converged and raise_on_failure:
        raise LocalSolverError(f"local solver {method!r}: {message}")
    return LocalResult(r, x, int(its), float(err), converged, method, message, float(change))


def contact_states(r: np.ndarray, x: np.ndarray, mu: float | np.ndarray, dim: int,
                   tol: float = 1e-6) -> np.ndarray:
    """Classify each contact of a solution as OPEN, STICK or SLIP.

    At a solution an open contact has ``r = 0`` (``x_n >= 0``), a sticking one ``|r_t| < mu r_n``
    (``x_t = 0``) and a slipping one ``|r_t| = mu r_n`` (``x_t`` opposed to ``r_t``). The test uses the
    forces, which are well scaled at convergence, while ``x_t`` of a sticking contact is only zero to the
    solver's tolerance:

    - OPEN if ``r_n <= tol * max_b |r^b|`` (all OPEN if ``r = 0``);
    - SLIP if ``|r_t| >= (1 - tol) mu r_n`` (so every closed frictionless contact slips);
    - STICK otherwise.

    Args:
        r: Contact forces, ``(n, t...)`` per contact.
        x: Relative displacements ``W r + q`` of the same solution (checked for shape; the force test
            decides).
        mu: Friction coefficient(s).
        dim: 2 or 3.
        tol: Relative tolerance of the two tests.

    Returns:
        ``int8`` array of codes, one per contact.
    """
    if dim not in (2, 3):
        raise ValueError(f"dim: expected 2 or 3, got {dim!r}")
    r = np.asarray(r, dtype=float)
    x = np.asarray(x, dtype=float)
    if r.ndim != 1 or r.size % dim:
        raise ValueError(f"r: expected a 1-D array of length multiple of dim = {dim}, got shape {r.shape}")
    if x.shape != r.shape:
        raise ValueError(f"x: expected shape {r.shape} like r, got {x.shape}")
    nc = r.size // dim
    mu_arr = _as_mu(mu, nc)
    R = r.reshape(nc, dim)
    rn = R[:, 0]
    rt = np.linalg.norm(R[:, 1:], axis=1)
    scale = np.linalg.norm(R, axis=1).max(initial=0.0)
    states = np.full(nc, STICK, dtype=np.int8)
    states[rt >= (1.0 - tol) * mu_arr * rn] = SLIP
    states[rn <= tol * scale] = OPEN
    return states
