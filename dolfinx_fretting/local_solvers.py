"""Local frictional contact problem on the Delassus operator: projection, solvers, contact states.

The local problem (paper eq. 28, FCLIB/Siconos form) is: find ``r`` and ``x`` with ::

    x = W r + q,    and for every contact alpha:  -(x^alpha + mu |x_t^alpha| e_n)  in  N_{K_mu}(r^alpha),

i.e. Signorini's conditions on ``(x_n, r_n)`` and Coulomb's law written with De Saxce's modified relative
displacement (paper eq. 22). Vectors are stored contact by contact, each block ordered ``(n, t1[, t2])``
like FCLIB and Siconos (the paper writes ``(t1, t2, n)``). ``K_mu = {r : |r_t| <= mu r_n}`` is the Coulomb
cone; its polar cone is ``K_mu° = {y : mu |y_t| <= -y_n}``.

The solver is the paper's Algorithm 1, a Gauss-Seidel sweep over the contacts, with one correction: eq. (31)
as printed builds the predictor from ``x^{alpha beta}``, which leaves out the contact's own term
``W_aa r^a``, so the exact solution is not a fixed point of that iteration. The predictor here uses the
full current ``x^a = sum_b W_ab r^b + q^a``::

    r* = r^a - rho_a (x^a + mu |x_t^a| e_n),      r^a <- Proj_{K_mu}(r*),

with ``rho_a = 1 / ||W_aa||_2`` (``1/lambda_max`` for a symmetric block), so that the step is a projected
gradient step no longer than the block's curvature allows.

Besides this ``"uzawa"`` method, :func:`solve` offers ``"nsgs"`` (the same Gauss-Seidel sweep with an exact
solve of each contact's own problem, Siconos's NSGS), ``"newton"`` (a safeguarded semismooth Newton on the
Alart-Curnier function) and ``"auto"`` (NSGS, then Newton when NSGS is slow); benchmarks/results/
solver_suite.md compares them on the FCLIB problems. A frictionless problem (``mu = 0`` everywhere) is
solved on its normal rows alone, an LCP on ``W_nn`` (see :func:`solve`).

Convergence is measured by a unit-free natural-map residual (see :func:`natural_map_error`), the same for
every method, not by the relative change of ``r`` of eq. (34), which can be small while far from the
solution.
"""

from __future__ import annotations

import math
import warnings
import weakref
from dataclasses import dataclass

import numba
import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp
import scipy.sparse.linalg as spla

__all__ = [
    "OPEN",
    "STICK",
    "SLIP",
    "METHODS",
    "LocalResult",
    "LocalSolverError",
    "NEAR_MARGIN",
    "block_rho",
    "contact_states",
    "de_saxce_x",
    "natural_map_error",
    "project_coulomb",
    "solve",
]

OPEN = 0   #: Contact state code of a separated contact (r = 0).
STICK = 1  #: Contact state code of a closed contact strictly inside the cone.
SLIP = 2   #: Contact state code of a closed contact on the cone boundary.

#: The methods of :func:`solve`.
METHODS = ("uzawa", "nsgs", "newton", "auto")

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
        iterations: Gauss-Seidel sweeps done, plus Newton steps and gross-slip predictor steps where the method
            takes them (0 when the initial guess already met the tolerance).
        error: Natural-map residual of ``r`` (see :func:`natural_map_error`), the stopping criterion.
        converged: ``error < tol`` with finite values.
        method: Solver name.
        message: Human-readable outcome: iterations, error reached, tolerance.
        change: Relative change ``||r_k - r_{k-1}|| / ||r_k||`` of the last sweep or Newton step (paper
            eq. 34), for information only.
        sweeps: Gauss-Seidel sweeps (Uzawa or NSGS) among ``iterations``.
        newton_steps: Newton steps among ``iterations`` (``"newton"`` and ``"auto"``).
        passes: Passes of the sweeps on the working set (each ended by a check on all contacts); 0 when the
            sweeps ran on all contacts (see ``working_set`` in :func:`solve`).
        working_set: Contacts in the working set at the end (0: all contacts swept).
        joined: Contacts that joined the working set after the start (their gap closed during the solve).
        block_held: The working set's block ``W_AA`` was the one held from the previous solve on this ``W`` (the
            same set; see ``block_steps`` in :func:`solve`), not gathered again.
        predictor_steps: Steps of the gross-slip predictor among ``iterations`` (3D ``"uzawa"`` on the working
            set: each pass first tries it, see :func:`solve`).
    """

    r: np.ndarray
    x: np.ndarray
    iterations: int
    error: float
    converged: bool
    method: str
    message: str
    change: float = 0.0
    sweeps: int = 0
    newton_steps: int = 0
    passes: int = 0
    working_set: int = 0
    joined: int = 0
    block_held: bool = False
    predictor_steps: int = 0


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
def _force_scale(q: np.ndarray, mu: np.ndarray, rho: np.ndarray, dim: int) -> float:
    """Force scale of a problem from its penetrating contacts (see :func:`natural_map_error`).

    ``|| (rho_a (q_n^a, min(mu_a, 1) |q_t^a|))_a ||`` over the contacts with ``q_n^a < 0``; open contacts
    (``q_n >= 0``) add nothing.
    """
    s = 0.0
    for a in range(mu.size):
        o = a * dim
        if not q[o] < 0.0:
            continue
        q2 = q[o + 2] if dim == 3 else 0.0
        t = min(mu[a], 1.0)
        s += (rho[a] * q[o]) ** 2 + (rho[a] * t) ** 2 * (q[o + 1] ** 2 + q2 * q2)
    return math.sqrt(s)


@numba.njit(cache=True)
def _error(r: np.ndarray, x: np.ndarray, mu: np.ndarray, rho: np.ndarray, dim: int, scale: float) -> float:
    """Natural-map residual ||r - P_K(r - rho (x + mu|x_t| e_n))|| / max(scale, ||r||), scale from
    :func:`_force_scale`."""
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
    den = max(scale, math.sqrt(rr))
    if den == 0.0:
        # r = 0 and no contact penetrates (q_n >= 0): r = 0 is an exact solution (s is rounding only).
        return 0.0
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
def _recompute_x_by_rows(W: np.ndarray, q: np.ndarray, r: np.ndarray, x: np.ndarray, rows: np.ndarray) -> None:
    """x[i] = (W r + q)[i] for the rows ``i`` listed, from the rows of a dense W (C-contiguous), skipping r_j = 0:
    each x[i] the same products added in the same order as :func:`_recompute_x` on W^T, so the same bits (four
    rows at a time: four independent sums in flight, each in its own order)."""
    nonzero = np.flatnonzero(r != 0.0)
    values = r[nonzero]
    n = rows.size
    k = 0
    while k + 4 <= n:
        i0, i1, i2, i3 = rows[k], rows[k + 1], rows[k + 2], rows[k + 3]
        w0, w1, w2, w3 = W[i0], W[i1], W[i2], W[i3]
        s0, s1, s2, s3 = q[i0], q[i1], q[i2], q[i3]
        for p in range(nonzero.size):
            j = nonzero[p]
            v = values[p]
            s0 += w0[j] * v
            s1 += w1[j] * v
            s2 += w2[j] * v
            s3 += w3[j] * v
        x[i0], x[i1], x[i2], x[i3] = s0, s1, s2, s3
        k += 4
    for kk in range(k, n):
        i = rows[kk]
        w = W[i]
        s = q[i]
        for p in range(nonzero.size):
            s += w[nonzero[p]] * values[p]
        x[i] = s


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
def _set_contact(Wc: np.ndarray, indptr: np.ndarray, indices: np.ndarray, data: np.ndarray, sparse: bool, dim: int,
                 o: int, pn: float, p1: float, p2: float, r: np.ndarray, x: np.ndarray) -> float:
    """r^a <- (pn, p1[, p2]) keeping x = W r + q up to date; returns |change of r^a|^2."""
    d0 = pn - r[o]
    d1 = p1 - r[o + 1]
    d2 = p2 - (r[o + 2] if dim == 3 else 0.0)
    if d0 != 0.0 or d1 != 0.0 or d2 != 0.0:
        r[o] = pn
        r[o + 1] = p1
        if dim == 3:
            r[o + 2] = p2
        if dim == 3 and not sparse and d0 != 0.0 and d1 != 0.0 and d2 != 0.0:
            # The three columns in one pass over x: each x[i] gets the same three products in the same order as from
            # three passes (the same bits), x read and written once instead of three times.
            row0 = Wc[o]
            row1 = Wc[o + 1]
            row2 = Wc[o + 2]
            for i in range(x.size):
                value = x[i]
                value += row0[i] * d0
                value += row1[i] * d1
                value += row2[i] * d2
                x[i] = value
        else:
            _add_column(Wc, indptr, indices, data, sparse, o, d0, x)
            _add_column(Wc, indptr, indices, data, sparse, o + 1, d1, x)
            if dim == 3:
                _add_column(Wc, indptr, indices, data, sparse, o + 2, d2, x)
        return d0 * d0 + d1 * d1 + d2 * d2
    return 0.0


@numba.njit(cache=True)
def _end_of_sweep(k: int, refresh: int, Wc: np.ndarray, indptr: np.ndarray, indices: np.ndarray, data: np.ndarray,
                  sparse: bool, q: np.ndarray, r: np.ndarray, x: np.ndarray, mu: np.ndarray, rho_err: np.ndarray,
                  dim: int, scale: float, tol: float, change: float) -> tuple[float, int]:
    """Error after sweep k and the outcome: 1 converged, 2 non-finite, -1 go on."""
    if k % refresh == 0:
        _recompute_x(Wc, indptr, indices, data, sparse, q, r, x)
    err = _error(r, x, mu, rho_err, dim, scale)
    if not (math.isfinite(err) and math.isfinite(change)):
        return err, 2
    if err < tol:
        # Confirm on the exact x: the incremental update accumulates rounding.
        _recompute_x(Wc, indptr, indices, data, sparse, q, r, x)
        err = _error(r, x, mu, rho_err, dim, scale)
        if err < tol:
            return err, 1
    return err, -1


@numba.njit(cache=True)
def _uzawa_kernel(Wc: np.ndarray, indptr: np.ndarray, indices: np.ndarray, data: np.ndarray, sparse: bool,
                  q: np.ndarray, mu: np.ndarray, rho: np.ndarray, rho_err: np.ndarray, dim: int,
                  r: np.ndarray, x: np.ndarray, tol: float, max_iter: int, refresh: int
                  ) -> tuple[int, float, float, int]:
    """Gauss-Seidel Uzawa sweeps (paper Algorithm 1, corrected eq. 31). ``x = W r + q`` on entry.

    Returns (sweeps, error, change, status) with status 1 converged, 0 max_iter, 2 non-finite.
    """
    return _uzawa_sweeps(Wc, Wc, indptr, indices, data, sparse, q, mu, rho, rho_err, dim, r, x, tol, max_iter,
                         refresh, _force_scale(q, mu, rho_err, dim))


@numba.njit(cache=True)
def _uzawa_sweeps(Ws: np.ndarray, Wc: np.ndarray, indptr: np.ndarray, indices: np.ndarray, data: np.ndarray,
                  sparse: bool, q: np.ndarray, mu: np.ndarray, rho: np.ndarray, rho_err: np.ndarray, dim: int,
                  r: np.ndarray, x: np.ndarray, tol: float, max_iter: int, refresh: int, scale: float
                  ) -> tuple[int, float, float, int]:
    """:func:`_uzawa_kernel` with the error's force ``scale`` given and the sweeps' incremental updates of ``x``
    read from ``Ws`` (``Wc`` itself, or a float32 copy of it: the exact recomputations of ``x`` use ``Wc``)."""
    nc = mu.size
    err = _error(r, x, mu, rho_err, dim, scale)
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
            dr2 += _set_contact(Ws, indptr, indices, data, sparse, dim, o, pn, p1, p2, r, x)
            r2 += pn * pn + p1 * p1 + p2 * p2
        change = math.sqrt(dr2) / max(math.sqrt(r2), 1e-300)
        err, status = _end_of_sweep(k, refresh, Wc, indptr, indices, data, sparse, q, r, x, mu, rho_err, dim, scale,
                                    tol, change)
        if status >= 0:
            return k, err, change, status
    return max_iter, err, change, 0


# ----------------------------------------------------------------------------------------------------------
# NSGS: Gauss-Seidel with an exact solve of each contact's own problem
# ----------------------------------------------------------------------------------------------------------
# Angles scanned for the 3D sliding direction when the warm-started Newton on the angle fails.
_SCAN = 64
_SCAN_COS = np.cos(2.0 * np.pi * np.arange(_SCAN) / _SCAN)
_SCAN_SIN = np.sin(2.0 * np.pi * np.arange(_SCAN) / _SCAN)


@numba.njit(cache=True)
def _local_res(B: np.ndarray, dim: int, bn: float, b1: float, b2: float, mu: float, rho: float,
               rn: float, r1: float, r2: float) -> float:
    """Squared natural-map residual of one contact's own problem ``x = B r + b`` at ``r``."""
    xn = B[0, 0] * rn + B[0, 1] * r1 + bn
    x1 = B[1, 0] * rn + B[1, 1] * r1 + b1
    x2 = 0.0
    if dim == 3:
        xn += B[0, 2] * r2
        x1 += B[1, 2] * r2
        x2 = B[2, 0] * rn + B[2, 1] * r1 + B[2, 2] * r2 + b2
    nxt = math.sqrt(x1 * x1 + x2 * x2)
    pn, p1, p2 = _project(rn - rho * (xn + mu * nxt), r1 - rho * x1, r2 - rho * x2, mu)
    return (rn - pn) ** 2 + (r1 - p1) ** 2 + (r2 - p2) ** 2


@numba.njit(cache=True)
def _contact_2d(B: np.ndarray, bn: float, bt: float, mu: float, rho: float, rn: float, rt: float
                ) -> tuple[float, float]:
    """Exact solution of one 2D contact's problem ``x = B r + b`` by enumerating its states.

    Open (``b_n >= 0``), stick (``r = -B^-1 b`` inside the cone) and slip in either direction
    (``x_n = 0``, ``r_t = -s mu r_n``, ``s x_t >= 0``) are tried in this order and the first that satisfies
    its conditions is returned. If rounding rejects all of them (a contact at a state boundary, or a singular
    ``B``), the candidate with the smallest residual is kept, the current ``r`` included.
    """
    if bn >= 0.0:
        return 0.0, 0.0
    b00, b01, b10, b11 = B[0, 0], B[0, 1], B[1, 0], B[1, 1]
    det = b00 * b11 - b01 * b10
    stick_n = stick_t = 0.0
    have_stick = abs(det) > 1e-13 * (abs(b00 * b11) + abs(b01 * b10))
    if have_stick:
        stick_n = -(b11 * bn - b01 * bt) / det
        stick_t = (b10 * bn - b00 * bt) / det
        if stick_n >= 0.0 and abs(stick_t) <= mu * stick_n:
            return stick_n, stick_t
    # Sliding with x_t in direction s: x_n = (b00 - s mu b01) r_n + b_n = 0.
    found = 0
    cn = ct = 0.0
    for k in range(2):
        s = 1.0 if k == 0 else -1.0
        den = b00 - s * mu * b01
        if den <= 0.0:
            continue
        pn = -bn / den
        pt = -s * mu * pn
        xt = b10 * pn + b11 * pt + bt
        if s * xt >= 0.0:
            if found == 0 or (rt != 0.0 and (pt > 0.0) == (rt > 0.0)):
                cn, ct = pn, pt  # a second solution: keep the current sliding direction
            found += 1
    if found:
        return cn, ct
    # Fallback: smallest residual among the candidates (rounding at a state boundary).
    best_n, best_t = rn, rt
    best = _local_res(B, 2, bn, bt, 0.0, mu, rho, rn, rt, 0.0)
    cands = np.empty((4, 2))
    nc = 0
    cands[nc, 0], cands[nc, 1] = 0.0, 0.0
    nc += 1
    if have_stick:
        pn, pt, _ = _project(stick_n, stick_t, 0.0, mu)
        cands[nc, 0], cands[nc, 1] = pn, pt
        nc += 1
    for k in range(2):
        s = 1.0 if k == 0 else -1.0
        den = b00 - s * mu * b01
        if den > 0.0:
            cands[nc, 0] = -bn / den
            cands[nc, 1] = -s * mu * cands[nc, 0]
            nc += 1
    for i in range(nc):
        e = _local_res(B, 2, bn, bt, 0.0, mu, rho, cands[i, 0], cands[i, 1], 0.0)
        if e < best:
            best, best_n, best_t = e, cands[i, 0], cands[i, 1]
    return best_n, best_t


@numba.njit(cache=True)
def _slip_h(B: np.ndarray, bn: float, b1: float, b2: float, mu: float, c: float, s: float
            ) -> tuple[float, float, float]:
    """Sliding-direction equation of a 3D contact and its derivative in the angle.

    With ``e = (cos t, sin t)`` and ``r = r_n (1, mu e)``, ``x_n = 0`` gives ``r_n = -b_n / den``,
    ``den = B_nn + mu B_nt . e``, and sliding needs ``x_t`` parallel to ``e``:
    ``h = den * (e_perp . x_t) = e_perp . (-b_n (B_tn + mu B_tt e) + den b_t) = 0`` (a trigonometric
    polynomial of degree 2, at most 4 roots). Returns ``(h, dh/dt, den)``.
    """
    den = B[0, 0] + mu * (B[0, 1] * c + B[0, 2] * s)
    v1 = -bn * (B[1, 0] + mu * (B[1, 1] * c + B[1, 2] * s)) + den * b1
    v2 = -bn * (B[2, 0] + mu * (B[2, 1] * c + B[2, 2] * s)) + den * b2
    h = -s * v1 + c * v2
    dden = mu * (-B[0, 1] * s + B[0, 2] * c)
    dv1 = -bn * mu * (-B[1, 1] * s + B[1, 2] * c) + dden * b1
    dv2 = -bn * mu * (-B[2, 1] * s + B[2, 2] * c) + dden * b2
    dh = -(c * v1 + s * v2) + (-s * dv1 + c * dv2)
    return h, dh, den


@numba.njit(cache=True)
def _slip_candidate(B: np.ndarray, bn: float, b1: float, b2: float, mu: float, t: float
                    ) -> tuple[bool, float, float, float]:
    """Sliding force for the angle ``t`` and whether it satisfies x_n = 0, r_n >= 0, x_t opposed to r_t."""
    c, s = math.cos(t), math.sin(t)
    den = B[0, 0] + mu * (B[0, 1] * c + B[0, 2] * s)
    if not den > 0.0:
        return False, 0.0, 0.0, 0.0
    pn = -bn / den
    p1, p2 = mu * pn * c, mu * pn * s
    x1 = B[1, 0] * pn + B[1, 1] * p1 + B[1, 2] * p2 + b1
    x2 = B[2, 0] * pn + B[2, 1] * p1 + B[2, 2] * p2 + b2
    # x_t must point along -e; |x_t| ~ 0 (at the stick-slip boundary) is accepted.
    along = c * x1 + s * x2
    ok = along <= 1e-12 * (abs(b1) + abs(b2) + abs(bn) * (abs(B[1, 0]) + abs(B[2, 0]) + mu * (
        abs(B[1, 1]) + abs(B[1, 2]) + abs(B[2, 1]) + abs(B[2, 2]))))
    return ok, pn, p1, p2


@numba.njit(cache=True)
def _newton_angle(B: np.ndarray, bn: float, b1: float, b2: float, mu: float, t: float, lower: float,
                  upper: float, bracketed: bool) -> tuple[bool, float]:
    """Root of :func:`_slip_h` in the angle, Newton's method (safeguarded by bisection when bracketed)."""
    h_lower = 0.0
    if bracketed:
        h_lower = _slip_h(B, bn, b1, b2, mu, math.cos(lower), math.sin(lower))[0]
    for _ in range(60):
        h, dh, _ = _slip_h(B, bn, b1, b2, mu, math.cos(t), math.sin(t))
        if h == 0.0:
            return True, t
        if bracketed:
            if (h > 0.0) == (h_lower > 0.0):
                lower, h_lower = t, h
            else:
                upper = t
        step = -h / dh if dh != 0.0 else np.inf
        if bracketed:
            tn = t + step
            if not (min(lower, upper) < tn < max(lower, upper)) or not math.isfinite(tn):
                tn = 0.5 * (lower + upper)
            step = tn - t
            if abs(upper - lower) < 1e-15:
                return True, tn
        else:
            if not math.isfinite(step):
                return False, t
            step = max(-0.5, min(0.5, step))
        t += step
        if abs(step) < 1e-14:
            return True, t
    return bracketed, t


@numba.njit(cache=True)
def _contact_3d(B: np.ndarray, bn: float, b1: float, b2: float, mu: float, rho: float, rn: float,
                r1: float, r2: float, scan_c: np.ndarray, scan_s: np.ndarray) -> tuple[float, float, float]:
    """Exact solution of one 3D contact's problem ``x = B r + b``.

    Open if ``b_n >= 0``; stick if ``r = -B^-1 b`` lies in the cone; otherwise sliding, whose direction
    is a root of :func:`_slip_h`: Newton on the angle from the current direction first, and if that does not
    give a valid sliding solution, all roots bracketed on 64 angles (Newton-bisection). If several are
    valid, or none is (rounding at a state boundary, singular ``B``), the smallest residual wins, the
    current ``r`` included.
    """
    if bn >= 0.0:
        return 0.0, 0.0, 0.0
    if mu == 0.0 and B[0, 0] > 0.0:
        return -bn / B[0, 0], 0.0, 0.0
    # Stick: solve B s = -b (cofactors).
    c00 = B[1, 1] * B[2, 2] - B[1, 2] * B[2, 1]
    c01 = B[1, 2] * B[2, 0] - B[1, 0] * B[2, 2]
    c02 = B[1, 0] * B[2, 1] - B[1, 1] * B[2, 0]
    det = B[0, 0] * c00 + B[0, 1] * c01 + B[0, 2] * c02
    scale = abs(B[0, 0] * c00) + abs(B[0, 1] * c01) + abs(B[0, 2] * c02)
    have_stick = abs(det) > 1e-13 * scale
    stick_n = stick_1 = stick_2 = 0.0
    if have_stick:
        c10 = B[0, 2] * B[2, 1] - B[0, 1] * B[2, 2]
        c11 = B[0, 0] * B[2, 2] - B[0, 2] * B[2, 0]
        c12 = B[0, 1] * B[2, 0] - B[0, 0] * B[2, 1]
        c20 = B[0, 1] * B[1, 2] - B[0, 2] * B[1, 1]
        c21 = B[0, 2] * B[1, 0] - B[0, 0] * B[1, 2]
        c22 = B[0, 0] * B[1, 1] - B[0, 1] * B[1, 0]
        # inverse = adj / det, adj[i, j] = cofactor[j, i]
        stick_n = -(c00 * bn + c10 * b1 + c20 * b2) / det
        stick_1 = -(c01 * bn + c11 * b1 + c21 * b2) / det
        stick_2 = -(c02 * bn + c12 * b1 + c22 * b2) / det
        if stick_n >= 0.0 and math.sqrt(stick_1 * stick_1 + stick_2 * stick_2) <= mu * stick_n:
            return stick_n, stick_1, stick_2
    # Sliding: warm start from the current direction, else from the stick force's (the force that would
    # hold the contact, capped on the cone).
    if r1 != 0.0 or r2 != 0.0:
        t0 = math.atan2(r2, r1)
    elif have_stick and (stick_1 != 0.0 or stick_2 != 0.0):
        t0 = math.atan2(stick_2, stick_1)
    else:
        t0 = math.atan2(-b2, -b1)
    ok, t = _newton_angle(B, bn, b1, b2, mu, t0, 0.0, 0.0, False)
    if ok:
        valid, pn, p1, p2 = _slip_candidate(B, bn, b1, b2, mu, t)
        if valid and abs(_slip_h(B, bn, b1, b2, mu, math.cos(t), math.sin(t))[0]) <= 1e-10 * (
                abs(bn) * (abs(B[1, 0]) + abs(B[2, 0]) + mu * (abs(B[1, 1]) + abs(B[1, 2]) + abs(B[2, 1])
                                                                + abs(B[2, 2])))
                + (abs(B[0, 0]) + mu * (abs(B[0, 1]) + abs(B[0, 2]))) * (abs(b1) + abs(b2))):
            return pn, p1, p2
    # Scan for every root; keep the valid one with the smallest residual.
    best = np.inf
    best_n, best_1, best_2 = rn, r1, r2
    best_valid = False
    n = scan_c.size
    h0 = _slip_h(B, bn, b1, b2, mu, scan_c[0], scan_s[0])[0]
    hprev = h0
    for k in range(n):
        kn = (k + 1) % n
        hk = _slip_h(B, bn, b1, b2, mu, scan_c[kn], scan_s[kn])[0] if kn else h0
        if (hprev > 0.0) != (hk > 0.0) or hk == 0.0:
            lower = 2.0 * np.pi * k / n
            upper = 2.0 * np.pi * (k + 1) / n
            ok, t = _newton_angle(B, bn, b1, b2, mu, 0.5 * (lower + upper), lower, upper, True)
            valid, pn, p1, p2 = _slip_candidate(B, bn, b1, b2, mu, t)
            if pn != 0.0 or p1 != 0.0 or p2 != 0.0:
                e = _local_res(B, 3, bn, b1, b2, mu, rho, pn, p1, p2)
                if (valid and not best_valid) or ((valid == best_valid) and e < best):
                    best, best_n, best_1, best_2, best_valid = e, pn, p1, p2, valid
        hprev = hk
    if best_valid:
        return best_n, best_1, best_2
    # No valid state (rounding, degenerate block): smallest residual, current r and projected stick included.
    cur = _local_res(B, 3, bn, b1, b2, mu, rho, rn, r1, r2)
    if cur < best:
        best, best_n, best_1, best_2 = cur, rn, r1, r2
    if have_stick:
        pn, p1, p2 = _project(stick_n, stick_1, stick_2, mu)
        e = _local_res(B, 3, bn, b1, b2, mu, rho, pn, p1, p2)
        if e < best:
            best, best_n, best_1, best_2 = e, pn, p1, p2
    return best_n, best_1, best_2


@numba.njit(cache=True)
def _nsgs_kernel(Wc: np.ndarray, indptr: np.ndarray, indices: np.ndarray, data: np.ndarray, sparse: bool,
                 blocks: np.ndarray, q: np.ndarray, mu: np.ndarray, rho_err: np.ndarray, dim: int,
                 r: np.ndarray, x: np.ndarray, tol: float, max_iter: int, refresh: int, omega: float,
                 scan_c: np.ndarray, scan_s: np.ndarray) -> tuple[int, float, float, int]:
    """Gauss-Seidel sweeps with an exact solve of each contact's own problem. ``x = W r + q`` on entry.

    For contact ``a`` with the others fixed, ``x^a = W_aa r^a + b^a`` with ``b^a = x^a - W_aa r^a``, and
    ``r^a`` is replaced by the exact solution of that one-contact problem (:func:`_contact_2d`,
    :func:`_contact_3d`), relaxed by ``omega`` (then projected on the cone) when ``omega != 1``.

    Returns (sweeps, error, change, status) like :func:`_uzawa_kernel`.
    """
    return _nsgs_sweeps(Wc, Wc, indptr, indices, data, sparse, blocks, q, mu, rho_err, dim, r, x, tol, max_iter,
                        refresh, omega, scan_c, scan_s, _force_scale(q, mu, rho_err, dim))


@numba.njit(cache=True)
def _nsgs_sweeps(Ws: np.ndarray, Wc: np.ndarray, indptr: np.ndarray, indices: np.ndarray, data: np.ndarray,
                 sparse: bool, blocks: np.ndarray, q: np.ndarray, mu: np.ndarray, rho_err: np.ndarray, dim: int,
                 r: np.ndarray, x: np.ndarray, tol: float, max_iter: int, refresh: int, omega: float,
                 scan_c: np.ndarray, scan_s: np.ndarray, scale: float) -> tuple[int, float, float, int]:
    """:func:`_nsgs_kernel` with the error's ``scale`` given and the incremental updates read from ``Ws`` (see
    :func:`_uzawa_sweeps`)."""
    nc = mu.size
    err = _error(r, x, mu, rho_err, dim, scale)
    if err < tol:
        return 0, err, 0.0, 1
    change = np.inf
    for k in range(1, max_iter + 1):
        dr2 = 0.0
        r2 = 0.0
        for a in range(nc):
            o = a * dim
            B = blocks[a]
            rn = r[o]
            r1 = r[o + 1]
            if dim == 3:
                rt2 = r[o + 2]
                bn = x[o] - (B[0, 0] * rn + B[0, 1] * r1 + B[0, 2] * rt2)
                b1 = x[o + 1] - (B[1, 0] * rn + B[1, 1] * r1 + B[1, 2] * rt2)
                b2 = x[o + 2] - (B[2, 0] * rn + B[2, 1] * r1 + B[2, 2] * rt2)
                pn, p1, p2 = _contact_3d(B, bn, b1, b2, mu[a], rho_err[a], rn, r1, rt2, scan_c, scan_s)
            else:
                rt2 = 0.0
                bn = x[o] - (B[0, 0] * rn + B[0, 1] * r1)
                b1 = x[o + 1] - (B[1, 0] * rn + B[1, 1] * r1)
                pn, p1 = _contact_2d(B, bn, b1, mu[a], rho_err[a], rn, r1)
                p2 = 0.0
            if omega != 1.0:
                pn, p1, p2 = _project(rn + omega * (pn - rn), r1 + omega * (p1 - r1),
                                      rt2 + omega * (p2 - rt2), mu[a])
            dr2 += _set_contact(Ws, indptr, indices, data, sparse, dim, o, pn, p1, p2, r, x)
            r2 += pn * pn + p1 * p1 + p2 * p2
        change = math.sqrt(dr2) / max(math.sqrt(r2), 1e-300)
        err, status = _end_of_sweep(k, refresh, Wc, indptr, indices, data, sparse, q, r, x, mu, rho_err, dim, scale,
                                    tol, change)
        if status >= 0:
            return k, err, change, status
    return max_iter, err, change, 0


# ----------------------------------------------------------------------------------------------------------
# Sweeps on the working set (the closed and nearly closed contacts), then a check on every contact
# ----------------------------------------------------------------------------------------------------------
#: A contact with no force joins the working set of the restricted sweeps when its gap ``x_n`` at the warm start is
#: below this share of the problem's deepest penetration ``max(-q_n)``: the ring just outside the contact, whose
#: gaps are the ones an increment may close. Any value >= 0 meets the same criterion on the whole problem; a larger
#: one costs longer rows, a smaller one risks a pass more, and, at 0, the same bits: touching contacts (x_n = 0,
#: r = 0) are then left out, and where the full sweeps' rounding dips their gap below 0 for a sweep they get forces
#: of 1e-19 that the restricted sweeps do not (FCLIB NESpheres_30_1). 0 was 1.1-1.8x faster on the sphere-flat
#: increments (benchmarks/results/local_speed.md); 0.05 keeps the full sweeps' bits on every problem tested.
#: (The compiled cycle loop reads it when numba compiles cycling.py: clear its cache after changing it.)
NEAR_MARGIN = 0.05

#: The 3D working-set Uzawa solve (:func:`solve`'s default and the compiled cycle loops) first tries
#: :func:`_gross_slip_predictor` on each pass. Its answer meets the same criterion as the sweeps' but is another
#: point within it (r within 1.8e-8 of the sweeps' on the sphere's half-space cycles at tol 1e-10).
#: (The compiled cycle loop reads it when numba compiles cycling.py: clear its cache after changing it.)
GROSS_SLIP_PREDICTOR = True


@numba.njit(cache=True)
def _nothing_held() -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Nothing held (:func:`_restricted_core`'s ``held_member``, ``held_block``, ``held_block32``, ``held_loaded``,
    ``held_factor``, ``held_loaded_block32``): an empty set, block, float32 block, loaded set, factor and float32
    loaded block."""
    return (np.zeros(0, dtype=np.bool_), np.zeros((0, 0)), np.zeros((0, 0), dtype=np.float32),
            np.zeros(0, dtype=np.int64), np.zeros((0, 0)), np.zeros((0, 0), dtype=np.float32))


@numba.njit(cache=True)
def _gather_block(A: np.ndarray, by_rows: bool, rows: np.ndarray) -> np.ndarray:
    """``(W_AA)^T`` C-contiguous (the sweeps' columns of ``W_AA`` as rows) for the rows and columns ``rows`` of ``W``,
    given as ``A = W`` (``by_rows``) or ``A = W^T``: the same values, gathered."""
    ma = rows.size
    block = np.empty((ma, ma))
    if by_rows:
        # block[j, i] = W[rows[i], rows[j]], a tile of 32 x 32 at a time: the reads run along rows of W and the writes
        # stay within the tile's 32 rows of the block (in cache), not one strided write per entry.
        for i0 in range(0, ma, 32):
            i1 = min(i0 + 32, ma)
            for j0 in range(0, ma, 32):
                j1 = min(j0 + 32, ma)
                for i in range(i0, i1):
                    source = A[rows[i]]
                    for j in range(j0, j1):
                        block[j, i] = source[rows[j]]
    else:
        for i in range(ma):
            source = A[rows[i]]
            for j in range(ma):
                block[i, j] = source[rows[j]]
    return block


# ----------------------------------------------------------------------------------------------------------
# Gross-slip predictor: the normal forces solved exactly, the slip directions by fixed point
# ----------------------------------------------------------------------------------------------------------
#: The predictor stops when a step does not divide the best error by at least 2 (stick, a reversal, a contact
#: opening or closing): the sweeps go on from its last output that did, or from its start when none did.
PREDICTOR_CONTRACTION = 0.5
#: At most this many predictor steps a pass (a step costs ~0.6 sweeps at 2025 contacts: gross_slip.md).
PREDICTOR_STEPS = 20
#: Anderson's mixing (:func:`_anderson_mix`) combines the last ``PREDICTOR_DEPTH + 1`` outputs (``PREDICTOR_DEPTH``
#: differences).
PREDICTOR_DEPTH = 4


@numba.njit(cache=True)
def _cholesky_solve(factor: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``P^{-1} b`` for ``P = L L^T`` (``factor = L``, lower, C-contiguous): both triangles read along ``L``'s rows."""
    n = b.size
    y = b.copy()
    for i in range(n):
        row = factor[i]
        value = y[i]
        for k in range(i):
            value -= row[k] * y[k]
        y[i] = value / row[i]
    for i in range(n - 1, -1, -1):
        y[i] /= factor[i, i]
        value = y[i]
        row = factor[i]
        for k in range(i):
            y[k] -= row[k] * value
    return y


@numba.njit(cache=True)
def _add_moves32(block32: np.ndarray, positions: np.ndarray, moves: np.ndarray, x: np.ndarray) -> None:
    """``x[positions] += B moves`` for ``block32 = B^T`` float32 (rows = ``B``'s columns, C-contiguous), summed in
    float64, skipping zero moves."""
    added = np.zeros(positions.size)
    for p in range(positions.size):
        move = moves[p]
        if move == 0.0:
            continue
        row = block32[p]
        for s in range(added.size):
            added[s] += row[s] * move
    for s in range(positions.size):
        x[positions[s]] += added[s]


@numba.njit(cache=True)
def _anderson_mix(outputs: np.ndarray, residuals: np.ndarray, outputs_x: np.ndarray, last: int, stored: int,
                  loaded: np.ndarray, r: np.ndarray, x: np.ndarray) -> None:
    """Anderson's mixing of the last ``stored`` steps (rows of the ring buffers, ``last`` the newest): the
    combination of their outputs whose residuals' combination is least (weights summing to 1), written to the
    loaded contacts' rows of ``r`` and to ``x`` (the same combination of the outputs' ``x``: ``W r + q`` is affine in
    ``r``, so the mix of exact ones is the mixed ``r``'s, and a mix of float32-updated ones carries the same mix of
    their offsets). Fewer than two steps, or a singular system: ``r``, ``x`` are left as they are (the newest
    output)."""
    if stored < 2:
        return
    size = outputs.shape[0]
    others = np.empty(stored - 1, dtype=np.int64)
    k = 0
    for back in range(1, stored):
        others[k] = (last - back) % size
        k += 1
    n = stored - 1
    differences = np.empty((n, residuals.shape[1]))
    for c in range(n):
        differences[c] = residuals[last] - residuals[others[c]]
    gram = differences @ differences.T
    rhs = differences @ residuals[last]
    for c in range(n):
        gram[c, c] *= 1.0 + 1e-10   # a tiny ridge: steps with nearly equal residuals leave gram singular
    try:
        weights = np.linalg.solve(gram, rhs)
    except Exception:
        return
    for c in range(n):
        if not math.isfinite(weights[c]):
            return
    mixed = outputs[last].copy()
    mixed_x = outputs_x[last].copy()
    for c in range(n):
        mixed -= weights[c] * (outputs[last] - outputs[others[c]])
        mixed_x -= weights[c] * (outputs_x[last] - outputs_x[others[c]])
    for i in range(loaded.size):
        o = 3 * loaded[i]
        for c in range(3):
            r[o + c] = mixed[3 * i + c]
    x[:] = mixed_x


@numba.njit(cache=True)
def _gross_slip_predictor(Wa: np.ndarray, q: np.ndarray, mu: np.ndarray, rho_err: np.ndarray, scale: float,
                          contacts: np.ndarray, r: np.ndarray, x: np.ndarray, tol: float, max_steps: int,
                          held_loaded: np.ndarray, held_factor: np.ndarray, held_loaded_block32: np.ndarray,
                          stats: np.ndarray) -> tuple[int, float, int, float, np.ndarray, np.ndarray, np.ndarray]:
    """Steps towards the answer of a 3D sub-problem in gross slip, cheaper than the sweeps there.

    ``Wa = (W_AA)^T`` C-contiguous (``W`` symmetric), ``q``, ``mu``, ``rho_err``, ``r``, ``x = W_AA r + q`` (exact)
    the working set's (``contacts``: their indices in the whole problem), ``scale`` the whole problem's force
    scale. The loaded contacts ``L`` (``r_n > 0`` at the start) are taken to slide; a step

    - solves their normal rows exactly with the tangential forces held: ``r_n <- r_n - W_LL^{-1} x_n`` (a Cholesky
      factor of ``W_LL``'s normal rows and columns);
    - puts each on its cone against its slip, ``r_t = -mu r_n x_t / |x_t|`` (De Saxce's law for a sliding
      contact), and updates the loaded contacts' ``x`` by ``W_LL`` times the change of ``r``, ``W_LL`` (all three
      rows and columns of each loaded contact) read from a float32 copy and summed in float64: the step's output,
      whose error is measured (the other contacts of the set have ``r = 0`` and their ``x`` of the last exact
      formation);
    - mixes the last ``PREDICTOR_DEPTH + 1`` outputs (Anderson, :func:`_anderson_mix`) into the next step's input
      (the loaded contacts' forces, and ``x`` as the same mix of the outputs' ones).

    Why float32 there: the step is memory-bound, and at 2025 contacts the float32 ``W_LL`` (18.5 MB) is 2.5x fewer
    bytes than ``Wa``'s loaded rows (46 MB) and mostly stays in this machine's 32 MB cache from step to step. Its
    updates leave the loaded rows of ``x`` off ``W_AA r + q`` by ~6e-8 of ``W``'s entries times the change of ``r``
    since ``x`` was last formed exactly (an offset that does not fall with the steps), and the set's other contacts
    keep their ``x`` of then (one that closes meanwhile goes unseen until the next exact ``x``); so wherever a
    decision rests on a step's error (below the tolerance: converged; not halving the best error: stop), ``x`` is
    first formed exactly on the whole set from ``Wa`` (float64) and the error measured again. Every answer and every
    stop is judged on an exact ``x``, and the output handed on has its exact ``x`` and error; keeping an output
    that halved the error is judged on the updated ``x`` (a wrong keep costs steps, not the answer). A claim of
    convergence the exact ``x`` denies (the offset hid the rest) is not a stop: the steps go on from the exact ``x``
    while its error is below ``PREDICTOR_CONTRACTION`` times that of the last output kept on an exact ``x``.

    A sliding contact with ``x_n = 0`` and ``r_t`` so directed is an exact zero of the natural map, so in gross
    slip the error falls as the normal forces and the directions settle: on the sphere's half-space cycle at mu 0.8
    (benchmarks/results/gross_slip.md) 4-5 steps from the increment before where the sweeps take ~20 (7-8 at the
    first increment after a reversal; near the stroke's end, where the slip slows, 2 steps and the sweeps finish).
    Where a contact sticks, opens or closes at the answer it does not: the predictor stops at the first output
    that does not divide the best error by ``1 / PREDICTOR_CONTRACTION``, at the tolerance, at a negative normal
    force, at a loaded contact without slip (``x_t = 0``), or after ``max_steps``; ``r``, ``x`` are then the last
    output that halved the error, or the start (then untouched: the sweeps' own iterates follow): inside the
    cones, ``x`` exact.

    ``held_loaded``/``held_factor``/``held_loaded_block32``: the loaded contacts (indices in the whole problem), the
    factor and the float32 ``W_LL`` of an earlier call on the same ``W`` (the caller vouches): used again while the
    loaded set is the same. ``stats`` (int64, 3) gets: calls that stepped, steps, factorisations.
    Returns (1 converged / 0 not, error, steps, the relative change of ``r`` of the last step kept (eq. 34, as the
    sweeps report it; 0 if none), the loaded contacts, factor and float32 ``W_LL`` to hold: the held ones, new ones,
    or empty arrays when no factor was made).
    """
    na = mu.size
    nothing_i = np.zeros(0, dtype=np.int64)
    nothing_f = np.zeros((0, 0))
    nothing_32 = np.zeros((0, 0), dtype=np.float32)
    count = 0
    for a in range(na):
        if r[3 * a] > 0.0:
            count += 1
    if count == 0:
        return 0, 0.0, 0, 0.0, held_loaded, held_factor, held_loaded_block32
    loaded = np.empty(count, dtype=np.int64)   # positions in the set
    k = 0
    for a in range(na):
        o = 3 * a
        if r[o] > 0.0:
            if x[o + 1] == 0.0 and x[o + 2] == 0.0:   # no direction to slide in
                return 0, 0.0, 0, 0.0, held_loaded, held_factor, held_loaded_block32
            loaded[k] = a
            k += 1
    key = contacts[loaded]
    loaded_rows = 3 * count
    positions = np.empty(loaded_rows, dtype=np.int64)   # the loaded contacts' rows in the set
    for i in range(count):
        for c in range(3):
            positions[3 * i + c] = 3 * loaded[i] + c
    if (held_factor.shape[0] == count and held_loaded_block32.shape[0] == loaded_rows
            and np.array_equal(held_loaded, key)):
        factor = held_factor
        loaded_block32 = held_loaded_block32
    else:
        block = np.empty((count, count))
        for i in range(count):
            row = Wa[3 * loaded[i]]
            for j in range(count):
                block[i, j] = row[3 * loaded[j]]
        for i in range(count):   # Cholesky reads one triangle: a W that is not symmetric is not for it
            for j in range(i):
                if block[i, j] != block[j, i]:
                    return 0, 0.0, 0, 0.0, nothing_i, nothing_f, nothing_32
        try:
            factor = np.linalg.cholesky(block)
        except Exception:  # not positive definite (a rank-deficient W): the sweeps' business
            return 0, 0.0, 0, 0.0, nothing_i, nothing_f, nothing_32
        loaded_block32 = np.empty((loaded_rows, loaded_rows), dtype=np.float32)   # (W_LL)^T, as Wa
        for p in range(loaded_rows):
            row = Wa[positions[p]]
            for s in range(loaded_rows):
                loaded_block32[p, s] = row[positions[s]]
        stats[2] += 1
    stats[0] += 1
    err = _error(r, x, mu, rho_err, 3, scale)
    best, best_r, best_x = err, r.copy(), x.copy()
    best_exact = True   # best_x is W_AA best_r + q formed from Wa
    exact_err = err     # the error of the last output kept whose x was formed exactly (the start's at first)
    rn = np.empty(count)
    for i in range(count):
        rn[i] = r[3 * loaded[i]]
    steps = 0
    empty_i = np.zeros(1, dtype=np.int64)
    empty_f = np.zeros(1)
    # Anderson's mixing: ring buffers of the last PREDICTOR_DEPTH + 1 outputs, their x and their residuals.
    outputs = np.zeros((PREDICTOR_DEPTH + 1, loaded_rows))
    residuals = np.zeros((PREDICTOR_DEPTH + 1, loaded_rows))
    outputs_x = np.zeros((PREDICTOR_DEPTH + 1, x.size))
    inputs = np.empty(loaded_rows)
    moves = np.empty(loaded_rows)
    stored = 0
    change = 0.0
    while steps < max_steps:
        for p in range(loaded_rows):
            inputs[p] = r[positions[p]]
        # x_n = W_LL r_n + (the rest, held): the r_n that zeroes it is r_n - W_LL^{-1} x_n.
        gaps = np.empty(count)
        for i in range(count):
            gaps[i] = x[3 * loaded[i]]
        correction = _cholesky_solve(factor, gaps)
        for i in range(count):
            rn[i] -= correction[i]
        steps += 1
        negative = False
        for i in range(count):
            if rn[i] < 0.0:
                negative = True
        if negative:
            break
        for i in range(count):
            a = loaded[i]
            o = 3 * a
            slip = math.sqrt(x[o + 1] ** 2 + x[o + 2] ** 2)
            r[o] = rn[i]
            r[o + 1] = -mu[a] * rn[i] * x[o + 1] / slip
            r[o + 2] = -mu[a] * rn[i] * x[o + 2] / slip
        for p in range(loaded_rows):
            moves[p] = r[positions[p]] - inputs[p]
        _add_moves32(loaded_block32, positions, moves, x)
        err = _error(r, x, mu, rho_err, 3, scale)
        claimed = err < tol
        exact = False
        if claimed or not err < PREDICTOR_CONTRACTION * best:   # a decision (NaN included): on the exact x
            _recompute_x(Wa, empty_i, empty_i, empty_f, False, q, r, x)
            err = _error(r, x, mu, rho_err, 3, scale)
            exact = True
        # A claim of convergence the exact x denies is the float32 offset (it grows with the change of r since the
        # last exact x) hiding the rest of the error: the steps go on from the exact x while it halved the error of
        # the last output kept on an exact x.
        drifted = claimed and err < PREDICTOR_CONTRACTION * exact_err
        if not (err < tol or err < PREDICTOR_CONTRACTION * best or drifted):   # NaN included
            break   # the sweeps start from the best output that halved the error, or from the start
        best = err
        best_r[:] = r
        best_x[:] = x
        best_exact = exact
        if exact:
            exact_err = err
        moved = 0.0
        size = 0.0
        for p in range(loaded_rows):
            moved += moves[p] ** 2
            size += r[positions[p]] ** 2
        change = math.sqrt(moved) / max(math.sqrt(size), 1e-300)   # eq. (34) of the step, as the sweeps report it
        if err < tol:
            break
        slot = stored % (PREDICTOR_DEPTH + 1)
        for p in range(loaded_rows):
            outputs[slot, p] = r[positions[p]]
            residuals[slot, p] = moves[p]
        outputs_x[slot] = x
        stored += 1
        _anderson_mix(outputs, residuals, outputs_x, slot, min(stored, PREDICTOR_DEPTH + 1), loaded, r, x)
        zero_slip = False
        for i in range(count):
            o = 3 * loaded[i]
            rn[i] = r[o]
            if x[o + 1] == 0.0 and x[o + 2] == 0.0:
                zero_slip = True
        if zero_slip:
            break
    stats[1] += steps
    r[:] = best_r
    if best_exact:
        x[:] = best_x
    else:   # an output that halved the error but decided nothing: its exact x (and error), for the sweeps
        _recompute_x(Wa, empty_i, empty_i, empty_f, False, q, r, x)
        best = _error(r, x, mu, rho_err, 3, scale)
    return (1 if best < tol else 0), best, steps, change, key, factor, loaded_block32


@numba.njit(cache=True)
def _member_rows(member: np.ndarray, dim: int) -> np.ndarray:
    """The rows of ``W`` of the contacts ``member`` (bool, one a contact), ascending: ``dim`` a contact."""
    rows = np.empty(np.count_nonzero(member) * dim, dtype=np.int64)
    k = 0
    for a in range(member.size):
        if member[a]:
            for c in range(dim):
                rows[k] = a * dim + c
                k += 1
    return rows


@numba.njit(cache=True)
def _x_from_held_block(A: np.ndarray, by_rows: bool, held_member: np.ndarray, held_block: np.ndarray, q: np.ndarray,
                       r: np.ndarray, x: np.ndarray, dim: int) -> bool:
    """``x = W r + q`` on the held set's rows from the held block ``(W_AA)^T`` instead of ``W``'s rows (``A = W``,
    ``by_rows``), when every force of ``r`` lies in the held set (a warm start from the solve before): ``W``'s
    columns outside the set then meet zero forces, and the block's columns give each row the same products in the
    same order (ascending columns, zeros skipped) as :func:`_recompute_x_by_rows` on ``W``: the same bits, read
    along the block's contiguous rows (the loaded contacts' columns of ``W_AA``) instead of gathered from ``W``'s
    rows (the start's ``x`` 9.3-9.6 -> 6.0-6.5 ms at 2025 contacts, gross_slip.md). Returns whether it did (not when
    it does not apply, or when the held set and block do not match in size)."""
    nc = q.size // dim
    if (not by_rows or held_block.shape[0] == 0 or held_member.size != nc
            or np.count_nonzero(held_member) * dim != held_block.shape[0]):
        return False
    for a in range(nc):
        if not held_member[a]:
            for c in range(dim):
                if r[a * dim + c] != 0.0:
                    return False
    rows = _member_rows(held_member, dim)
    qa = q[rows]
    ra = r[rows]
    xa = np.empty(rows.size)
    _recompute_x(held_block, np.zeros(1, dtype=np.int64), np.zeros(1, dtype=np.int64), np.zeros(1), False, qa, ra,
                 xa)
    for i in range(rows.size):
        x[rows[i]] = xa[i]
    return True


@numba.njit(cache=True)
def _restricted_core(A: np.ndarray, by_rows: bool, x_ready: bool, blocks: np.ndarray, q: np.ndarray, mu: np.ndarray,
                     rho: np.ndarray, rho_err: np.ndarray, dim: int, r: np.ndarray, x: np.ndarray, tol: float,
                     max_iter: int, refresh: int, nsgs: bool, omega: float, scan_c: np.ndarray, scan_s: np.ndarray,
                     margin_factor: float, single: bool, stats: np.ndarray, predict: bool,
                     held_member: np.ndarray, held_block: np.ndarray, held_block32: np.ndarray, held_loaded: np.ndarray,
                     held_factor: np.ndarray, held_loaded_block32: np.ndarray
                     ) -> tuple[int, float, float, int, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray,
                                np.ndarray]:
    """Uzawa (``nsgs`` False) or NSGS sweeps on the working set only, with a final check on all contacts.

    Dense ``W`` only, given as ``A = W`` (``by_rows``: no transposed copy to make, a solve's own ``W``) or
    ``A = W^T`` C-contiguous (the compiled loop's ``Wc``); ``x = W r + q`` on entry when ``x_ready``. The working
    set is the contacts with a force and those whose gap ``x_n`` is below ``margin_factor * max(-q_n)``; the sweeps
    run on the gathered ``W_AA`` (rows ``dim |A|`` long instead of ``m``, and a matrix that may fit in cache), in
    float32 for the incremental updates of ``x`` when ``single`` (the exact recomputations stay float64).

    Why it is the full sweeps' answer: a contact with ``r^a = 0`` and ``x_n^a >= 0`` is left at ``r^a = 0`` by
    a sweep (Uzawa's predictor ``-rho (x_n + mu |x_t|, x_t)`` lies in the polar cone exactly when ``x_n >= 0``,
    and projects to 0; NSGS's one-contact problem is open when ``b_n = x_n >= 0``) and adds exactly 0 to the
    natural-map error (whose force scale is the full problem's). So while every contact outside the set keeps
    ``x_n >= 0`` the restricted sweeps are the full ones, iterate for iterate. Once they converge, ``x = W r + q``
    is recomputed on all rows and the error on all contacts; a contact outside with ``x_n < 0`` (the only way
    the two errors can differ) joins the set, with any other below the margin, and the sweeps go on from there.
    The answer meets the same criterion as the full sweeps', on the whole problem.

    Two savings for a caller that solves again and again on one ``W``:
    ``x_ready`` False (``by_rows`` only): ``x`` is formed here on the rows the sweeps read, the normal rows of every
    contact (the set is chosen from them) and the set's other rows; the outside contacts' other rows wait for the
    check after the sweeps (an outside contact has ``x_n >= margin >= 0``, so it adds exactly 0 to the error
    whatever its ``x_t``: 0 stands in for it until then, and ``x`` is complete on return); when every force of the
    start lies in the held set, that set's rows come from the held block (:func:`_x_from_held_block`, the same bits).
    ``held_block`` (``held_block32``: its float32 copy, or an empty array) is ``(W_AA)^T`` of a previous solve for
    the set ``held_member``: a pass on the same set uses it instead of gathering ``W_AA`` again (the caller vouches
    that it is this ``W``'s: the same values, so the same bits). Empty arrays: nothing held.

    ``predict`` (3D Uzawa only): each pass first tries :func:`_gross_slip_predictor` on the set (``held_loaded``,
    ``held_factor``, ``held_loaded_block32``: its factor and float32 block of an earlier solve, or empty arrays) and
    sweeps only if it does not converge, from its best iterate.

    ``stats`` (int64, 7) gets: passes, working-set size at the end, contacts that joined after the start, passes
    that swept the held block, then the predictor's passes that stepped, steps and factorisations.
    Returns (iterations, error, change, status, member, block, block32, loaded, factor, loaded_block32): sweeps plus
    predictor steps over all passes, status 1 converged, 0 max_iter, 2 non-finite (as :func:`_uzawa_kernel`); the
    last pass's set, its ``(W_AA)^T`` and the float32 copy (empty unless ``single``; empty blocks when no pass ran),
    and the predictor's loaded contacts, factor and float32 loaded block, for the caller to hold.
    """
    nc = mu.size
    m = q.size
    scale = _force_scale(q, mu, rho_err, dim)
    stats[0] = 0
    stats[1] = 0
    stats[2] = 0
    stats[3] = 0
    stats[4] = 0
    stats[5] = 0
    stats[6] = 0
    predict = predict and dim == 3 and not nsgs
    deepest = 0.0
    for a in range(nc):
        deepest = max(deepest, -q[a * dim])
    margin = margin_factor * deepest
    # formed: the contacts whose rows of x are all formed before the set is chosen (none, or the held set's)
    formed = np.zeros(nc, dtype=np.bool_)
    if not x_ready:
        if _x_from_held_block(A, by_rows, held_member, held_block, q, r, x, dim):
            formed = held_member
        normal = np.empty(nc - np.count_nonzero(formed), dtype=np.int64)
        k = 0
        for a in range(nc):
            if not formed[a]:
                normal[k] = a * dim
                k += 1
        _recompute_x_by_rows(A, q, r, x, normal)
    member = np.zeros(nc, dtype=np.bool_)
    for a in range(nc):
        o = a * dim
        loaded = r[o] != 0.0 or r[o + 1] != 0.0 or (dim == 3 and r[o + 2] != 0.0)
        member[a] = loaded or x[o] < margin
    if not x_ready:
        count = 0
        for a in range(nc):
            if member[a] and not formed[a]:
                count += 1
        tangential = np.empty(count * (dim - 1), dtype=np.int64)
        k = 0
        for a in range(nc):
            for c in range(1, dim):
                if not member[a]:
                    x[a * dim + c] = 0.0  # formed at the check
                elif not formed[a]:
                    tangential[k] = a * dim + c
                    k += 1
        _recompute_x_by_rows(A, q, r, x, tangential)
    err = _error(r, x, mu, rho_err, dim, scale)
    empty_i = np.zeros(1, dtype=np.int64)
    empty_f = np.zeros(1)
    if err < tol and not x_ready:
        # The answer is the start: x on every row, and the error of the whole x (a non-finite x_t would show).
        _recompute_x_by_rows(A, q, r, x, np.arange(m))
        err = _error(r, x, mu, rho_err, dim, scale)
    if err < tol:
        return (0, err, 0.0, 1, member, np.zeros((0, 0)), np.zeros((0, 0), dtype=np.float32), held_loaded, held_factor,
                held_loaded_block32)
    total = 0
    change = np.inf
    status = 0
    while True:
        stats[0] += 1
        na = 0
        for a in range(nc):
            if member[a]:
                na += 1
        stats[1] = na
        ma = na * dim
        rows = _member_rows(member, dim)
        same = held_block.shape[0] == ma and np.array_equal(held_member, member)
        Wa = held_block if same else _gather_block(A, by_rows, rows)  # (W_AA)^T, C-contiguous, like Wc
        if same:
            stats[3] += 1
        if not single:
            Wa32 = np.zeros((0, 0), dtype=np.float32)
        elif same and held_block32.shape[0] == ma:
            Wa32 = held_block32
        else:
            Wa32 = Wa.astype(np.float32)
        qa = np.empty(ma)
        ra = np.empty(ma)
        xa = np.empty(ma)
        for i in range(ma):
            qa[i] = q[rows[i]]
            ra[i] = r[rows[i]]
            xa[i] = x[rows[i]]
        mua = np.empty(na)
        rhoa = np.empty(na)
        rho_erra = np.empty(na)
        blocks_a = np.empty((na if nsgs else 1, dim, dim))
        for k in range(na):
            a = rows[k * dim] // dim
            mua[k] = mu[a]
            rhoa[k] = rho[a]
            rho_erra[k] = rho_err[a]
            if nsgs:
                blocks_a[k] = blocks[a]
        left = max_iter - total
        if left <= 0:
            if not x_ready:
                _recompute_x_by_rows(A, q, r, x, np.arange(m))
            return total, err, change, 0, member, Wa, Wa32, held_loaded, held_factor, held_loaded_block32
        predicted = False
        if predict:
            contacts = np.empty(na, dtype=np.int64)
            for k in range(na):
                contacts[k] = rows[k * dim] // dim
            (outcome, predicted_err, steps, predicted_change, held_loaded, held_factor,
             held_loaded_block32) = _gross_slip_predictor(Wa, qa, mua, rho_erra, scale, contacts, ra, xa, tol,
                                                          min(PREDICTOR_STEPS, left), held_loaded, held_factor,
                                                          held_loaded_block32, stats[4:])
            total += steps
            predicted = outcome == 1
            left = max_iter - total
        if predicted:
            its, err, change, status = 0, predicted_err, predicted_change, 1
        elif left <= 0:
            its, status = 0, 0
        elif nsgs and single:
            its, err, change, status = _nsgs_sweeps(Wa32, Wa, empty_i, empty_i, empty_f, False, blocks_a, qa, mua,
                                                    rho_erra, dim, ra, xa, tol, left, refresh, omega, scan_c, scan_s,
                                                    scale)
        elif nsgs:
            its, err, change, status = _nsgs_sweeps(Wa, Wa, empty_i, empty_i, empty_f, False, blocks_a, qa, mua,
                                                    rho_erra, dim, ra, xa, tol, left, refresh, omega, scan_c,
                                                    scan_s, scale)
        elif single:
            its, err, change, status = _uzawa_sweeps(Wa32, Wa, empty_i, empty_i, empty_f, False, qa, mua, rhoa,
                                                     rho_erra, dim, ra, xa, tol, left, refresh, scale)
        else:
            its, err, change, status = _uzawa_sweeps(Wa, Wa, empty_i, empty_i, empty_f, False, qa, mua, rhoa,
                                                     rho_erra, dim, ra, xa, tol, left, refresh, scale)
        total += its
        for i in range(ma):
            r[rows[i]] = ra[i]
        # The check on every contact: x on all rows, exactly, and the error of the whole problem.
        if by_rows and status == 1:
            # The set's rows of x are exact (the sub-problem's convergence is confirmed on x recomputed from
            # W_AA, the same bits as from W); the other rows from W's rows.
            outside = np.empty(m - ma, dtype=np.int64)
            k = 0
            for a in range(nc):
                if not member[a]:
                    for c in range(dim):
                        outside[k] = a * dim + c
                        k += 1
            for i in range(ma):
                x[rows[i]] = xa[i]
            _recompute_x_by_rows(A, q, r, x, outside)
        elif by_rows:
            _recompute_x_by_rows(A, q, r, x, np.arange(m))
        else:
            _recompute_x(A, empty_i, empty_i, empty_f, False, q, r, x)
        if status == 2:
            return total, err, change, 2, member, Wa, Wa32, held_loaded, held_factor, held_loaded_block32
        err = _error(r, x, mu, rho_err, dim, scale)
        if status != 1:
            return total, err, change, status, member, Wa, Wa32, held_loaded, held_factor, held_loaded_block32
        if err < tol:
            return total, err, change, 1, member, Wa, Wa32, held_loaded, held_factor, held_loaded_block32
        added = 0
        for a in range(nc):
            if not member[a] and x[a * dim] < margin:
                member[a] = True
                added += 1
        stats[2] += added
        if added == 0:
            # Not reached in exact arithmetic (the outside terms are exact zeros): finish with full sweeps.
            left = max_iter - total
            if left <= 0:
                return total, err, change, 0, member, Wa, Wa32, held_loaded, held_factor, held_loaded_block32
            Wc = np.ascontiguousarray(A.T) if by_rows else A
            if nsgs:
                its, err, change, status = _nsgs_sweeps(Wc, Wc, empty_i, empty_i, empty_f, False, blocks, q, mu,
                                                        rho_err, dim, r, x, tol, left, refresh, omega, scan_c,
                                                        scan_s, scale)
            else:
                its, err, change, status = _uzawa_sweeps(Wc, Wc, empty_i, empty_i, empty_f, False, q, mu, rho,
                                                         rho_err, dim, r, x, tol, left, refresh, scale)
            stats[1] = nc
            if status == 0:  # the sweeps update x step by step: a failed solve reports the x of its r, x = W r + q
                _recompute_x(Wc, empty_i, empty_i, empty_f, False, q, r, x)
            return total + its, err, change, status, member, Wa, Wa32, held_loaded, held_factor, held_loaded_block32


# ----------------------------------------------------------------------------------------------------------
# Semismooth Newton on the Alart-Curnier function
# ----------------------------------------------------------------------------------------------------------
@numba.njit(cache=True)
def _alart_curnier(r: np.ndarray, x: np.ndarray, mu: np.ndarray, rho: np.ndarray, dim: int,
                   F: np.ndarray, M: np.ndarray) -> float:
    """Alart-Curnier function ``F(r)`` and the blocks ``M`` of one element of its generalized Jacobian.

    Per contact, with ``d_n = r_n - rho_n x_n``, ``d_t = r_t - rho_t x_t`` (``rho[a] = (rho_n, rho_t)``)
    and ``R = mu max(0, d_n)``::

        F_n = r_n - max(0, d_n),      F_t = r_t - P_{|.| <= R}(d_t)

    and ``dF/dr = (I - M) + M diag(rho) W`` with ``M`` block diagonal: ``M_nn = [d_n > 0]``; sticking
    (``|d_t| < R``): ``M_tt = I``; sliding: ``M_tt = R/|d_t| (I - u u^T)``, ``M_tn = mu [d_n > 0] u``,
    ``u = d_t/|d_t|``. An open contact has ``M = 0`` (its Newton step sets ``r`` to 0).

    Returns ``||F||^2 / 2``.
    """
    nc = mu.size
    th = 0.0
    for a in range(nc):
        o = a * dim
        ra, rt = rho[a, 0], rho[a, 1]
        for i in range(dim):
            for j in range(dim):
                M[a, i, j] = 0.0
        dn = r[o] - ra * x[o]
        pn = dn if dn > 0.0 else 0.0
        F[o] = r[o] - pn
        R = mu[a] * pn
        z1 = r[o + 1] - rt * x[o + 1]
        z2 = r[o + 2] - rt * x[o + 2] if dim == 3 else 0.0
        nz = math.sqrt(z1 * z1 + z2 * z2)
        if dn > 0.0:
            M[a, 0, 0] = 1.0
        if nz <= R:
            p1, p2 = z1, z2
            if R > 0.0:
                for i in range(1, dim):
                    M[a, i, i] = 1.0
        else:
            u1, u2 = z1 / nz, z2 / nz
            p1, p2 = R * u1, R * u2
            if dn > 0.0:
                M[a, 1, 0] = mu[a] * u1
                if dim == 3:
                    M[a, 2, 0] = mu[a] * u2
                    f = R / nz
                    M[a, 1, 1] = f * (1.0 - u1 * u1)
                    M[a, 1, 2] = -f * u1 * u2
                    M[a, 2, 1] = -f * u2 * u1
                    M[a, 2, 2] = f * (1.0 - u2 * u2)
        F[o + 1] = r[o + 1] - p1
        th += F[o] * F[o] + F[o + 1] * F[o + 1]
        if dim == 3:
            F[o + 2] = r[o + 2] - p2
            th += F[o + 2] * F[o + 2]
    return 0.5 * th


@numba.njit(cache=True)
def _ac_merit(r: np.ndarray, x: np.ndarray, mu: np.ndarray, rho: np.ndarray, dim: int) -> float:
    """``||F(r)||^2 / 2`` of :func:`_alart_curnier` without the Jacobian."""
    th = 0.0
    for a in range(mu.size):
        o = a * dim
        ra, rt = rho[a, 0], rho[a, 1]
        dn = r[o] - ra * x[o]
        pn = dn if dn > 0.0 else 0.0
        R = mu[a] * pn
        z1 = r[o + 1] - rt * x[o + 1]
        z2 = r[o + 2] - rt * x[o + 2] if dim == 3 else 0.0
        nz = math.sqrt(z1 * z1 + z2 * z2)
        if nz > R:
            z1 *= R / nz
            z2 *= R / nz
        th += (r[o] - pn) ** 2 + (r[o + 1] - z1) ** 2
        if dim == 3:
            th += (r[o + 2] - z2) ** 2
    return 0.5 * th


# ----------------------------------------------------------------------------------------------------------
# Frictionless (mu = 0): the normal problem alone
# ----------------------------------------------------------------------------------------------------------
@numba.njit(cache=True)
def _lcp_scale(q: np.ndarray, rho: np.ndarray) -> float:
    """:func:`_force_scale` of the normal problem: ``|| (rho_a max(-q_a, 0))_a ||``."""
    s = 0.0
    for a in range(q.size):
        if q[a] < 0.0:
            s += (rho[a] * q[a]) ** 2
    return math.sqrt(s)


@numba.njit(cache=True)
def _lcp_error(r: np.ndarray, x: np.ndarray, rho: np.ndarray, scale: float) -> float:
    """:func:`_error` of the normal problem: ``||r - max(0, r - rho x)|| / max(scale, ||r||)``.

    Term by term the same floating-point operations as :func:`_error` with ``mu = 0`` on ``(r_n, 0)``.
    """
    s = 0.0
    rr = 0.0
    for a in range(r.size):
        p = r[a] - rho[a] * x[a]
        if p <= 0.0:
            p = 0.0
        s += (r[a] - p) ** 2
        rr += r[a] ** 2
    den = max(scale, math.sqrt(rr))
    if den == 0.0:
        return 0.0
    return math.sqrt(s) / den


@numba.njit(cache=True)
def _tangential_x(W: np.ndarray, q: np.ndarray, r: np.ndarray, dim: int, x: np.ndarray) -> None:
    """Tangential rows of ``x = W r + q`` for an ``r`` with only normal entries (dense ``W``), summed in the
    order of :func:`_recompute_x` (so bit for bit the full solvers' ``x``)."""
    m = q.size
    for i in range(m):
        if i % dim == 0:
            continue
        s = q[i]
        for j in range(0, m, dim):
            if r[j] != 0.0:
                s += W[i, j] * r[j]
        x[i] = s


@numba.njit(cache=True)
def _lcp_kernel(Wc: np.ndarray, indptr: np.ndarray, indices: np.ndarray, data: np.ndarray, sparse: bool,
                q: np.ndarray, step: np.ndarray, exact: bool, omega: float, rho_err: np.ndarray, r: np.ndarray,
                x: np.ndarray, tol: float, max_iter: int, refresh: int) -> tuple[int, float, float, int]:
    """Projected Gauss-Seidel sweeps on the normal problem ``x = W_nn r + q``, ``0 <= r  _|_  x >= 0``.

    Contact ``a``: ``exact`` (PGS, NSGS with ``mu = 0``): ``r_a <- max(0, -b_a / W_aa)`` with
    ``b_a = x_a - W_aa r_a``, the exact one-contact solution, relaxed by ``omega``; otherwise the Uzawa step
    ``r_a <- max(0, r_a - step_a x_a)``. ``x = W_nn r + q`` on entry, kept up to date by columns and
    recomputed every ``refresh`` sweeps and before declaring convergence.

    Returns (sweeps, error, change, status) like :func:`_uzawa_kernel`.
    """
    n = r.size
    scale = _lcp_scale(q, rho_err)
    err = _lcp_error(r, x, rho_err, scale)
    if err < tol:
        return 0, err, 0.0, 1
    change = np.inf
    for k in range(1, max_iter + 1):
        dr2 = 0.0
        r2 = 0.0
        for a in range(n):
            ra = r[a]
            d = step[a]
            if exact and d > 0.0:
                b = x[a] - d * ra
                p = -b / d if b < 0.0 else 0.0
                if omega != 1.0:
                    p = ra + omega * (p - ra)
            else:
                p = ra - (rho_err[a] if exact else d) * x[a]
            if p <= 0.0:  # (a NaN stays, to be reported)
                p = 0.0
            dd = p - ra
            if dd != 0.0:
                r[a] = p
                _add_column(Wc, indptr, indices, data, sparse, a, dd, x)
                dr2 += dd * dd
            r2 += p * p
        change = math.sqrt(dr2) / max(math.sqrt(r2), 1e-300)
        if k % refresh == 0:
            _recompute_x(Wc, indptr, indices, data, sparse, q, r, x)
        err = _lcp_error(r, x, rho_err, scale)
        if not (math.isfinite(err) and math.isfinite(change)):
            return k, err, change, 2
        if err < tol:
            _recompute_x(Wc, indptr, indices, data, sparse, q, r, x)
            err = _lcp_error(r, x, rho_err, scale)
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


def _check_problem(W, q, mu, dim, values_checked: bool = False
                   ) -> tuple[np.ndarray | sp.csc_matrix, np.ndarray, np.ndarray, int]:
    """The problem as the solvers take it, checked; ``values_checked``: W's values were checked by an earlier call
    (the W held, see :class:`_HeldBlock`), not read again."""
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
    # A finite sum has only finite terms (a NaN or inf term makes it NaN or inf): one vectorised read of W, no
    # temporary of W's size (np.isfinite's: ~8 ms a solve at 1000 contacts); the exact test only if it is not.
    if not values_checked and not (math.isfinite(float(np.sum(values))) or np.all(np.isfinite(values))):
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


def _block_steps(W: np.ndarray | sp.spmatrix, dim: int, given: np.ndarray | None) -> np.ndarray:
    """``given`` (the caller's :func:`block_rho` of this ``W``, checked for its shape and sign only: the caller
    vouches that ``W`` has not changed since) or :func:`block_rho` computed now."""
    if given is None:
        return block_rho(W, dim)
    steps = np.asarray(given, dtype=float)
    nc = W.shape[0] // dim
    if steps.shape != (nc,):
        raise ValueError(f"block_steps: expected block_rho(W, dim) of shape ({nc},) for this W, got shape "
                         f"{steps.shape}")
    bad = np.flatnonzero(~(np.isfinite(steps) & (steps > 0.0)))
    if bad.size:
        raise ValueError(f"block_steps: expected block_rho(W, dim), finite values > 0, got {steps[bad[0]]!r} at "
                         f"contact {int(bad[0])}")
    return steps


def natural_map_error(W: np.ndarray | sp.spmatrix, q: np.ndarray, r: np.ndarray, mu: float | np.ndarray,
                      dim: int, block_steps: np.ndarray | None = None) -> float:
    """Unit-free natural-map residual of a candidate solution ``r``.

    With ``x = W r + q``, ``rho_a = 1/||W_aa||_2`` (:func:`block_rho`) and ``P`` the projection on ``K_mu``::

        error = sqrt( sum_a || r^a - P(r^a - rho_a (x^a + mu_a |x_t^a| e_n)) ||^2 ) / max(S, ||r||)

    It vanishes exactly at solutions (fixed point of the De Saxce projection, paper eqs. 22-23). The
    numerator is a force residual; the denominator is the force scale of the problem: the forces ``||r||``
    themselves, and, so that ``r = 0`` or a poor first iterate is not measured against nothing, the scale
    ``S`` of the loads on the penetrating contacts::

        S = || (rho_a (q_n^a, min(mu_a, 1) |q_t^a|))_a ||   over the contacts with q_n^a < 0.

    ``rho_a q_n^a`` is the force that would push contact ``a`` back alone; ``rho_a mu_a |q_t^a|`` is the
    size of the friction term ``rho_a mu_a |x_t|`` of the natural map at ``r = 0``, whose cancellation in
    the projection limits the accuracy the residual can reach at a sliding contact (capped at ``mu = 1`` so
    that ``S <= ||rho q||``). Open contacts (``q_n >= 0``) add nothing: their gaps are not loads. The scale
    used before, ``||rho q||``, counted them, so one loaded node among many open ones (a tiny load, a
    generous candidate window) was measured against the open gaps and its own force could never be solved
    to the tolerance. Since ``S <= ||rho q||``, this measure is never looser than that one.

    Numerator and denominator are forces, and under ``W -> s W``, ``q -> c q`` (so ``r -> (c/s) r``) both
    scale by ``c/s``: the error does not depend on the units of the problem. It is Siconos's fc3d
    natural-map error with the unit step replaced by ``rho_a`` and ``||q||`` by ``S``. With ``mu = 0`` the
    tangential terms of the numerator vanish when ``r_t = 0`` and ``S`` only sees ``q_n``, so the error of
    ``(r_n, 0)`` is that of the normal problem ``(W_nn, q_n)`` with the same ``rho_a``. If no contact
    penetrates, ``r = 0`` is an exact solution and its error is 0 (:func:`solve` then returns it at once).

    Args:
        W: Delassus matrix (dense or scipy sparse).
        q: Free relative displacement, length ``dim nc``.
        r: Candidate contact forces.
        mu: Friction coefficient(s), scalar or one per contact.
        dim: 2 or 3.
        block_steps: ``block_rho(W, dim)`` when the caller holds it for this ``W`` (computed here otherwise).

    Returns:
        The residual.
    """
    W, q, mu_arr, dim = _check_problem(W, q, mu, dim)
    r = _check_vector(r, q.size, "r")
    rho = _block_steps(W, dim, block_steps)
    x = W @ r + q
    return float(_error(r, np.ascontiguousarray(x), mu_arr, rho, dim, _force_scale(q, mu_arr, rho, dim)))


def _check_vector(v, m: int, name: str) -> np.ndarray:
    v = np.array(v, dtype=float)
    if v.shape != (m,):
        raise ValueError(f"{name}: expected shape ({m},), got {v.shape}")
    if not np.all(np.isfinite(v)):
        raise ValueError(f"{name}: contains non-finite values")
    return v


@dataclass
class _Problem:
    """Checked problem data shared by the solver drivers."""

    W: np.ndarray | sp.csc_matrix
    q: np.ndarray
    mu: np.ndarray
    dim: int
    rho_err: np.ndarray
    Wc: np.ndarray
    indptr: np.ndarray
    indices: np.ndarray
    data: np.ndarray
    sparse: bool
    blocks: np.ndarray | None = None

    @property
    def nc(self) -> int:
        """Number of contacts."""
        return self.mu.size

    def x_of(self, r: np.ndarray) -> np.ndarray:
        """``W r + q`` computed afresh."""
        x = np.empty(self.q.size)
        _recompute_x(self.Wc, self.indptr, self.indices, self.data, self.sparse, self.q, r, x)
        return x

    def error(self, r: np.ndarray, x: np.ndarray) -> float:
        """:func:`natural_map_error` of ``r`` given its ``x = W r + q``."""
        return float(_error(r, x, self.mu, self.rho_err, self.dim,
                            _force_scale(self.q, self.mu, self.rho_err, self.dim)))

    def nsgs(self, r: np.ndarray, x: np.ndarray, tol: float, max_iter: int, omega: float = 1.0
             ) -> tuple[int, float, float, int]:
        """Up to ``max_iter`` NSGS sweeps in place (:func:`_nsgs_kernel`): (sweeps, error, change, status)."""
        if self.blocks is None:
            self.blocks = np.ascontiguousarray(_diag_blocks(self.W, self.dim))
        return _nsgs_kernel(self.Wc, self.indptr, self.indices, self.data, self.sparse, self.blocks, self.q,
                            self.mu, self.rho_err, self.dim, r, x, float(tol), int(max_iter), _REFRESH,
                            float(omega), _SCAN_COS, _SCAN_SIN)


def _newton_direction(P: _Problem, F: np.ndarray, M: np.ndarray, rho: np.ndarray, eta: float
                      ) -> np.ndarray | None:
    """Solve ``(J + eta M) d = -F`` with ``J = (I - M) + M rho W`` (see :func:`_alart_curnier`).

    Open contacts (``M_a = 0``) have ``d_a = -F_a``; the system is solved on the others only, by LU
    (dense) or SuperLU (sparse). ``eta M`` is ``W -> W + (eta / rho_a) I`` on the active rows, a
    proximal regularization that makes ``J`` invertible when ``W`` is rank-deficient.

    Returns None if the matrix is singular or the step is not finite.
    """
    dim, nc = P.dim, P.nc
    d = -F
    act = np.flatnonzero(np.any(M.reshape(nc, -1) != 0.0, axis=1))
    if act.size == 0:
        return d
    idx = (act[:, None] * dim + np.arange(dim)).ravel()
    rc = np.empty((act.size, dim))
    rc[:, 0] = rho[act, 0]
    rc[:, 1:] = rho[act, 1:2]
    RM = M[act] * rc[:, None, :]
    D = np.eye(dim)[None] - M[act] + eta * M[act]
    d_open = d.copy()
    d_open[idx] = 0.0
    rhs = -F[idx]
    if np.any(d_open):
        Wd = (P.W @ d_open)[idx]
        rhs -= np.einsum("aij,aj->ai", RM, Wd.reshape(-1, dim)).ravel()
    nA = act.size
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        try:
            if P.sparse:
                Wcc = P.W[idx][:, idx]
                ptr = np.arange(nA + 1)
                RMb = sp.bsr_matrix((RM, ptr[:-1], ptr), shape=(idx.size, idx.size))
                Db = sp.bsr_matrix((D, ptr[:-1], ptr), shape=(idx.size, idx.size))
                J = (Db + RMb @ Wcc).tocsc()
                sol = spla.splu(J).solve(rhs)
            else:
                Wcc = P.W[np.ix_(idx, idx)]
                J = np.einsum("aij,ajk->aik", RM, Wcc.reshape(nA, dim, idx.size)).reshape(idx.size, idx.size)
                Jv = J.reshape(nA, dim, nA, dim)
                Jv[np.arange(nA), :, np.arange(nA), :] += D
                sol = _dense_lu_solve(J, rhs)
                if sol is None:
                    return None
        except (RuntimeError, ValueError, np.linalg.LinAlgError):
            return None
    if not np.all(np.isfinite(sol)):
        return None
    d[idx] = sol
    return d


def _dense_lu_solve(A: np.ndarray, rhs: np.ndarray) -> np.ndarray | None:
    """LU solve of a dense system, or None when a pivot is below 1e-15 of the largest (numerically singular)."""
    lu, piv = sla.lu_factor(A, check_finite=False)
    u = np.abs(np.diag(lu))
    if not u.min() > 1e-15 * u.max():
        return None
    return sla.lu_solve((lu, piv), rhs, check_finite=False)


@dataclass
class _Counts:
    """Work done by a driver: Gauss-Seidel sweeps and Newton steps."""

    sweeps: int = 0
    steps: int = 0
    fallbacks: int = 0
    passes: int = 0
    working_set: int = 0
    joined: int = 0
    block_held: bool = False
    predictor_steps: int = 0

    @property
    def total(self) -> int:
        return self.sweeps + self.steps + self.predictor_steps


# Newton safeguards (see _newton_driver), chosen on the FCLIB problems (benchmarks/results/solver_suite.md).
_NEWTON_MEMORY = 10         # non-monotone line search: compare with the largest of the last 10 merits
_NEWTON_STALL = 10          # safeguard when 10 steps in a row do not halve the best error
_NEWTON_FALLBACK = 10       # first NSGS fallback: 10 sweeps, doubled while Newton makes no progress
_NEWTON_ETA = (1e-6, 1e-2)  # proximal regularization eta = clip(error, 1e-6, 1e-2)


def _ac_rho(P: _Problem, factor: float) -> np.ndarray:
    """Alart-Curnier parameters ``(rho_n, rho_t)`` per contact: ``factor / ||W_aa||_2`` for both.

    (Separate ``1/W_nn`` and ``1/||W_tt||_2`` were tried: no better on the FCLIB problems, and worse on
    fc2d_granularflowonwall_02020_00213.)
    """
    return np.repeat(P.rho_err[:, None] * factor, 2, axis=1)


def _newton_driver(P: _Problem, r: np.ndarray, x: np.ndarray, tol: float, max_iter: int,
                   rho_factor: float, n: _Counts) -> tuple[float, float, int]:
    """Semismooth Newton on the Alart-Curnier function, safeguarded, in place on ``r`` and ``x``.

    - Direction: ``(J + eta M) d = -F`` (:func:`_newton_direction`) with ``eta = clip(error, 1e-6, 1e-2)``:
      a proximal term ``W -> W + (eta/rho_a) I`` that keeps the matrix invertible when ``W`` is
      rank-deficient or slightly indefinite (multibody problems) and costs little near the solution.
    - Step: non-monotone Armijo rule (Grippo-Lampariello-Lucidi) on the merit ``||F||^2/2`` against the
      largest of the last 10 merits, at most 30 halvings. A monotone rule stalls on several FCLIB problems,
      the active set creeping by one contact per step.
    - Safeguard, when the direction fails (singular matrix, no acceptable step) or 10 steps in a row do not
      halve the best natural-map error: from a nonzero start, the first time, Newton starts again from
      ``r = 0`` (Newton from a warm start far from the solution stalls on some rank-deficient problems where
      it converges from 0); otherwise NSGS sweeps (10, doubled each time Newton made no progress since the
      previous fallback, at most 1000), after which Newton resumes with a fresh line-search memory.

    ``x = W r + q`` is recomputed exactly after every step. ``n.total`` (sweeps + steps) is capped by
    ``max_iter``.

    Returns (error, change, status) with status 1 converged, 0 max_iter, 2 non-finite.
    """
    rho = _ac_rho(P, rho_factor)
    F = np.empty(r.size)
    M = np.empty((P.nc, P.dim, P.dim))
    err = P.error(r, x)
    change = 0.0
    if err < tol:
        return err, change, 1
    fb = _NEWTON_FALLBACK
    progress = True  # Newton halved the best error since the last fallback
    restarted = not np.any(r)
    hist: list[float] = []
    best_err, since_best = err, 0
    while n.total < max_iter:
        th = _alart_curnier(r, x, P.mu, rho, P.dim, F, M)
        hist = (hist + [th])[-_NEWTON_MEMORY:]
        eta = min(max(err, _NEWTON_ETA[0]), _NEWTON_ETA[1])
        d = _newton_direction(P, F, M, rho, eta)
        accepted = False
        if d is not None:
            Wd = P.W @ d
            ref = max(hist)
            alpha = 1.0
            for _ in range(30):
                r_new = r + alpha * d
                if _ac_merit(r_new, x + alpha * Wd, P.mu, rho, P.dim) <= ref - 1e-4 * alpha * th:
                    accepted = True
                    break
                alpha *= 0.5
        n.steps += 1
        if accepted:
            change = alpha * np.linalg.norm(d) / max(np.linalg.norm(r_new), 1e-300)
            r[:] = r_new
            x[:] = P.x_of(r)
            err = P.error(r, x)
            if not (math.isfinite(err) and math.isfinite(change)):
                return err, change, 2
            if err < tol:
                return err, change, 1
            if err < 0.5 * best_err:
                best_err, since_best, progress = err, 0, True
            else:
                since_best += 1
        if accepted and since_best < _NEWTON_STALL:
            continue
        n.fallbacks += 1
        hist, since_best = [], 0
        if not restarted:
            restarted = True
            r[:] = 0.0
            x[:] = P.q
            err = P.error(r, x)
            best_err, progress = err, True
            continue
        fb = fb if progress else min(2 * fb, 1000)
        k = min(fb, max_iter - n.total)
        if k <= 0:
            break
        its, err, change, status = P.nsgs(r, x, tol, k)
        n.sweeps += its
        if status != 0:
            return err, change, status
        progress = False
        best_err = min(best_err, err)
    return err, change, 0


class _HeldBlock:
    """The working set's block of the last solve on a ``W`` whose :func:`block_rho` the caller holds, for the next
    solve on it (a gross-slip cycle's increments sweep the same set, and gathering ``W_AA`` reads ``W`` at every
    one): the set, ``(W_AA)^T`` and its float32 copy (or an empty array), and the gross-slip predictor's loaded
    contacts, Cholesky factor and float32 loaded block (or empty arrays). Keyed on the identity of the caller's
    ``W`` and ``block_steps`` arrays (weak references: the block goes with its ``W``), and dropped when ``W``'s
    diagonal or the steps' values are not those held (a ``W`` rebuilt in place). Its ``W`` had its values checked
    (finite) when it was first solved on."""

    def __init__(self, W: np.ndarray, steps: np.ndarray, member: np.ndarray, block: np.ndarray, block32: np.ndarray,
                 loaded: np.ndarray, factor: np.ndarray, loaded_block32: np.ndarray):
        self._W = weakref.ref(W, _forget_block)
        self._steps = weakref.ref(steps)
        self._diagonal = W.diagonal().copy()
        self._step_values = steps.copy()
        self.member, self.block, self.block32 = member, block, block32
        self.loaded, self.factor, self.loaded_block32 = loaded, factor, loaded_block32

    def serves(self, W: object, steps: object) -> bool:
        """Whether ``W`` and ``steps`` are the very arrays held, with the diagonal and the steps held."""
        return (self._W() is W and self._steps() is steps and np.array_equal(W.diagonal(), self._diagonal)
                and np.array_equal(steps, self._step_values))

    def owned_by(self, ref: weakref.ref) -> bool:
        """Whether ``ref`` is the weak reference to this block's ``W``."""
        return self._W is ref


# The one block held (the package solves on one W at a time): see _HeldBlock.
_held: list[_HeldBlock | None] = [None]


def _forget_block(ref: weakref.ref) -> None:
    """Drop the held block when its ``W`` is freed (the block is tens of MB at 1000+ contacts)."""
    if _held[0] is not None and _held[0].owned_by(ref):
        _held[0] = None


def _holdable(W: object, steps: object) -> bool:
    """Whether a working-set solve on ``W`` with these steps may hold its block for the next: the caller gives
    :func:`block_rho` of ``W`` (it holds ``W``) and both are float64 arrays the solver uses as they are (no copy)."""
    return (steps is not None and isinstance(W, np.ndarray) and W.dtype == np.float64 and W.flags.c_contiguous
            and W.ndim == 2 and isinstance(steps, np.ndarray) and steps.dtype == np.float64)


def solve(W: np.ndarray | sp.spmatrix, q: np.ndarray, mu: float | np.ndarray, dim: int,
          method: str = "uzawa", tol: float = 1e-10, max_iter: int = 10000, r0: np.ndarray | None = None,
          rho: float | None = None, raise_on_failure: bool = False,
          block_steps: np.ndarray | None = None, working_set: bool = True,
          float32_sweeps: bool = False, hold_block: bool = True,
          gross_slip_predictor: bool = GROSS_SLIP_PREDICTOR) -> LocalResult:
    """Solve the local frictional contact problem ``x = W r + q``, ``r`` and ``x`` satisfying Coulomb's law.

    Every method stops when :func:`natural_map_error` ``< tol`` (checked on ``x = W r + q`` recomputed
    exactly), starts from ``r0`` projected on the cones (zero by default), and reports non-convergence in
    the returned :class:`LocalResult` (``converged=False`` with a message) or by raising. If no contact
    penetrates (``q_n >= 0`` everywhere) it returns the exact solution ``r = 0`` at once.

    Methods:

    - ``"uzawa"``: the paper's Algorithm 1 as a Gauss-Seidel sweep over contacts, with eq. (31)
      corrected to use the full local ``x^a`` (own term ``W_aa r^a`` included)::

          r* = r^a - rho_a (x^a + mu |x_t^a| e_n),   r^a <- Proj_K(r*),   x += W[:, a] (r^a_new - r^a_old)

      ``x`` is updated incrementally, so a sweep costs one column product per contact whose force changed
      (``O(m^2)`` dense, ``O(nnz)`` sparse), and is recomputed exactly every 200 sweeps and before declaring
      convergence. ``iterations`` counts sweeps; ``rho`` multiplies the step ``1/||W_aa||_2``.
    - ``"nsgs"``: non-smooth Gauss-Seidel (Siconos's NSGS idea): the same sweep, but each contact's force is
      replaced by the exact solution of its own one-contact problem ``x^a = W_aa r^a + b^a`` with the others
      fixed (2D: open / stick / slip+ / slip- enumerated; 3D: open, stick, or sliding with the direction
      found as a root of a trigonometric equation). Same cost per sweep as ``"uzawa"``, no step length, and
      usually far fewer sweeps, above all when the blocks ``W_aa`` are ill-conditioned. ``iterations``
      counts sweeps; ``rho`` (in ``(0, 2)``) relaxes the update, ``r^a <- P_K(r^a + rho (r^a_exact -
      r^a))``.
    - ``"newton"``: semismooth Newton on the Alart-Curnier function (parameter ``rho_a = 1/||W_aa||_2``,
      times ``rho``), with a vanishing proximal regularization of the Jacobian (rank-deficient ``W``), a
      non-monotone Armijo line search on ``||F||^2``, and safeguards when it stalls: one restart from
      ``r = 0`` if it started elsewhere, then NSGS sweeps (see ``_newton_driver``). One dense LU (sparse
      LU for a sparse ``W``) of the closed contacts' rows per step, ``O(m^3)`` dense: about ``m/8`` sweeps'
      worth. ``iterations`` counts Newton steps plus fallback sweeps.
    - ``"auto"`` (recommended): NSGS in windows of 10 sweeps while the error's rate over the last window
      projects fewer remaining sweeps than ``m`` (the measured cost of about 10 Newton steps), then
      ``"newton"`` from there. Easy problems (FE contact, most small ones) are solved by NSGS alone; slow
      ones (rank-deficient multibody ``W``) get Newton. No dense Newton above 6000 unknowns. ``iterations``
      counts sweeps plus Newton steps; ``rho`` is passed to the Newton phase.

    Frictionless problems (``mu = 0`` for every contact) are solved on the normal rows only: the cone is then
    the half-line ``r_t = 0``, ``r_n >= 0``, so ``r_t = 0`` and ``r_n`` solves the LCP ``x_n = W_nn r_n + q_n``,
    ``0 <= r_n _|_ x_n >= 0`` on the ``nc x nc`` matrix of the normal rows and columns; ``x = W r + q`` is
    then formed in full (the tangential rows give the slip). The error is the same natural-map error (with
    ``mu = 0`` it only sees the normal rows). Per method: ``"uzawa"`` does the same sweeps restricted to the
    normal rows (the iterates, ``r`` and ``x`` are bit for bit those of the full-dimension sweep, which
    touches twice or three times as many entries of ``W``); ``"nsgs"`` is projected Gauss-Seidel (exact
    one-contact solves ``r_a = max(0, r_a - x_a / W_aa)``, relaxed by ``rho``: the iterates of the
    full-dimension NSGS with ``mu = 0``); ``"newton"`` is a primal-dual active-set
    (semismooth) Newton on ``r - max(0, r - rho x)``, one Cholesky of the active block per step, with an
    Armijo rule and projected Gauss-Seidel sweeps as the safeguard (see ``_lcp_newton``); ``"auto"``
    is projected Gauss-Seidel, then that Newton by the same rule as for the full problem (``nc``
    unknowns). On FE contact the Newton needs a handful of steps where the sweeps need about a hundred,
    but below a few hundred contacts a step costs some tens of sweeps (benchmarks/results/
    frictionless.md).

    A sparse ``W`` is used as CSC (columns are what the sweeps need); a dense one through its transpose.

    Args:
        W: Delassus matrix ``(m, m)``, ``m = dim * nc``, dense array or scipy sparse matrix.
        q: Free relative displacement, length ``m`` (gaps in the normal rows).
        mu: Friction coefficient, scalar or one per contact, ``>= 0``.
        dim: 2 or 3.
        method: One of :data:`METHODS`: ``"uzawa"``, ``"nsgs"``, ``"newton"``, ``"auto"``.
        tol: Tolerance on the unit-free natural-map error.
        max_iter: Maximum number of iterations (sweeps, Newton steps, or their sum; see the methods).
        r0: Initial guess (warm start), projected on the cones; zero by default.
        rho: Optional factor: Uzawa step, NSGS relaxation, Alart-Curnier parameter (see the methods).
        raise_on_failure: Raise :class:`LocalSolverError` instead of returning ``converged=False``.
        block_steps: ``block_rho(W, dim)`` (the per-contact steps ``1/||W_aa||_2``) when the caller holds it for
            this very ``W`` (e.g. ``ContactOperators.block_steps``): the same numbers, not computed again at
            every solve (its batched SVD was ~26 % of a 3D cycle). None: computed here. Given (float64 arrays, as
            the package's), the caller also vouches that ``W`` is not changed in place while it solves on it: the
            working set's block ``W_AA`` (and the check that ``W`` is finite) is then kept from one solve to the
            next on the same ``W`` and ``block_steps`` arrays, and used again while the set is the same
            (:attr:`LocalResult.block_held`); a new ``W`` or new steps start afresh. ``hold_block=False`` opts out.
        working_set: ``"uzawa"`` and ``"nsgs"`` on a dense ``W``: sweep only the contacts with a force and those
            whose gap at the start is below :data:`NEAR_MARGIN` times the deepest penetration, on their own rows
            and columns ``W_AA``, then check the whole problem (``x = W r + q`` on all rows, the error on all
            contacts); a contact outside whose gap closed joins and the sweeps go on. The same iterates as the
            full sweeps while no outside gap closes, and always the same stopping criterion on the whole
            problem; a sweep costs ``O(|A|^2)`` instead of ``O(|A| m)`` (benchmarks/results/local_speed.md).
            False: every contact swept on the full ``W``.
        float32_sweeps: With ``working_set``: the sweeps' incremental updates of ``x`` read a float32 copy of
            ``W_AA`` (half the memory traffic); ``x`` is recomputed exactly in float64 every 200 sweeps and
            before convergence is declared, so the stopping criterion is unchanged, but the iterates differ
            from the float64 ones by rounding (answers within the tolerance, not the same bits).
        hold_block: With ``block_steps`` and ``working_set``: use the block held from the previous solve on this
            ``W`` and hold this solve's for the next (see ``block_steps``). False: neither (the block is gathered
            and ``W`` checked at this solve, and what is held is left as it is).
        gross_slip_predictor: 3D ``"uzawa"`` with ``working_set`` on a symmetric ``W`` whose loaded contacts'
            normal block is positive definite: each pass first takes the loaded contacts to slide: their normal
            forces solved exactly (a Cholesky factor of their ``W_nn``, held with the block) with the tangential
            forces held, each put on its cone against its slip, their ``x`` updated from a float32 copy of their
            block (held too; every decision judged on ``x`` formed exactly), the last outputs mixed
            (Anderson), again while each output halves the error (:func:`_gross_slip_predictor`); the sweeps go
            on from its last output if it stops short of the tolerance (stick, a reversal), from the start if
            its first output did not halve the error. Same stopping criterion, same ``max_iter`` (steps count
            as iterations, :attr:`LocalResult.predictor_steps`); the answer is another point within the
            tolerance, not the sweeps' bits. In gross slip 4-5 steps (~0.6 sweeps' cost each at 2025 contacts)
            where the sweeps take ~20 (benchmarks/results/gross_slip.md). False: the sweeps alone.

    Returns:
        A :class:`LocalResult`. ``converged`` is False (with a message) when ``max_iter`` is reached or a
        non-finite value appears; ``r`` is then the last iterate and ``x = W r + q`` its displacement.

    Raises:
        ValueError: invalid argument (the message names it).
        LocalSolverError: no convergence and ``raise_on_failure``.
    """
    if not isinstance(method, str) or method not in METHODS:
        raise ValueError(f"method: expected one of {METHODS}, got {method!r}")
    holding = (W, block_steps) if hold_block and _holdable(W, block_steps) else None
    held = _held[0] if holding is not None and _held[0] is not None and _held[0].serves(W, block_steps) else None
    W, q, mu_arr, dim = _check_problem(W, q, mu, dim, values_checked=held is not None)
    m = q.size
    nc = m // dim
    if block_steps is not None:  # bad input refused before any work
        block_steps = _block_steps(W, dim, block_steps)
    if not (isinstance(tol, (int, float, np.floating)) and math.isfinite(tol) and tol > 0):
        raise ValueError(f"tol: expected a finite number > 0, got {tol!r}")
    if isinstance(max_iter, bool) or not isinstance(max_iter, (int, np.integer)) or max_iter < 1:
        raise ValueError(f"max_iter: expected an integer >= 1, got {max_iter!r}")
    if rho is not None and not (isinstance(rho, (int, float, np.floating)) and math.isfinite(rho)
                                and rho > 0):
        raise ValueError(f"rho: expected a finite factor > 0, got {rho!r}")
    if method == "nsgs" and rho is not None and not rho < 2.0:
        raise ValueError(f"rho: the NSGS relaxation factor must lie in (0, 2), got {rho!r}")
    r = np.zeros(m) if r0 is None else _check_vector(r0, m, "r0")

    if nc == 0:
        return LocalResult(np.zeros(0), np.zeros(0), 0, 0.0, True, method, "no contacts", 0.0)
    if not np.any(q[::dim] < 0.0):
        # No contact penetrates: r = 0 is an exact solution (x = q, x_n >= 0), whatever W. From a nonzero warm
        # start the sweeps would only approach it, with an error relative to ||r|| that need not fall.
        return LocalResult(np.zeros(m), q.copy(), 0, 0.0, True, method, "no contact penetrates (q_n >= 0): r = 0",
                           0.0)

    counts = _Counts()
    rho_factor = 1.0 if rho is None else float(rho)
    rho_err = block_rho(W, dim) if block_steps is None else block_steps
    normal_only = not np.any(mu_arr)
    if normal_only:
        r, x, err, change, status = _solve_normal(W, q, dim, method, float(tol), int(max_iter), r, rho_factor,
                                                  counts, rho_err)
    else:
        r, x, err, change, status = _solve_full(W, q, mu_arr, dim, method, float(tol), int(max_iter), r,
                                                r0 is not None, rho_factor, counts, rho_err, bool(working_set),
                                                bool(float32_sweeps), holding, held, bool(gross_slip_predictor))
    its = counts.total
    converged = status == 1 and bool(np.all(np.isfinite(r)))
    unit = {"uzawa": "sweeps", "nsgs": "sweeps"}.get(method, "iterations")
    gs = "projected Gauss-Seidel" if normal_only else "NSGS"
    detail = "" if method in ("uzawa", "nsgs") else f" ({counts.sweeps} {gs} sweeps, {counts.steps} Newton steps)"
    if counts.predictor_steps:
        unit = "iterations"
        detail = f" ({counts.sweeps} sweeps, {counts.predictor_steps} gross-slip predictor steps)"
    detail += " on the normal problem (mu = 0)" if normal_only else ""
    if converged:
        message = f"converged in {its} {unit}{detail}: error {err:.3e} < tol {tol:.1e}"
    elif status == 2:
        message = (f"non-finite value after {its} {unit}{detail} (error {err}, change {change}); "
                   f"tolerance {tol:.1e} not reached")
    else:
        message = (f"not converged after max_iter = {its} {unit}{detail}: error {err:.3e} >= tol {tol:.1e} "
                   f"(last relative change of r {change:.3e})")
    if not converged and raise_on_failure:
        raise LocalSolverError(f"local solver {method!r}: {message}")
    return LocalResult(r, x, int(its), float(err), converged, method, message, float(change),
                       int(counts.sweeps), int(counts.steps), counts.passes, counts.working_set, counts.joined,
                       counts.block_held, counts.predictor_steps)


def _storage(W: np.ndarray | sp.csc_matrix) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, bool]:
    """The kernels' view of W: (W^T dense, C-contiguous, or a dummy; CSC indptr, indices, data; sparse)."""
    if sp.issparse(W):
        return (np.zeros((1, 1)), W.indptr.astype(np.int64), W.indices.astype(np.int64),
                np.ascontiguousarray(W.data), True)
    empty_i = np.zeros(1, dtype=np.int64)
    return np.ascontiguousarray(W.T), empty_i, empty_i, np.zeros(1), False


def _solve_full(W: np.ndarray | sp.csc_matrix, q: np.ndarray, mu_arr: np.ndarray, dim: int, method: str, tol: float,
                max_iter: int, r: np.ndarray, warm: bool, rho_factor: float, counts: _Counts,
                rho_err: np.ndarray | None = None, working_set: bool = True, float32_sweeps: bool = False,
                holding: tuple[np.ndarray, np.ndarray] | None = None, held: _HeldBlock | None = None,
                predictor: bool = GROSS_SLIP_PREDICTOR) -> tuple[np.ndarray, np.ndarray, float, float, int]:
    """The frictional problem in full dimension: (r, x, error, change, status), see :func:`solve` (``rho_err``:
    :func:`block_rho` of ``W``, computed here if None; ``holding``: the caller's (W, block_steps) whose working set's
    block is held for the next solve, ``held``: the block held for them, see :class:`_HeldBlock`; ``predictor``:
    ``gross_slip_predictor``)."""
    rho_err = block_rho(W, dim) if rho_err is None else rho_err
    if warm:
        # A warm start from another problem may lie outside the cones.
        _project_all(r, mu_arr, dim)
    if working_set and method in ("uzawa", "nsgs") and not sp.issparse(W):
        # The sweeps on the closed and nearly closed contacts, read from W's rows (no transposed copy of W).
        W = np.ascontiguousarray(W)
        x = np.empty(q.size)  # formed by the kernel on the rows it reads, complete on return
        nsgs = method == "nsgs"
        blocks = np.ascontiguousarray(_diag_blocks(W, dim)) if nsgs else np.zeros((1, dim, dim))
        stats = np.zeros(7, dtype=np.int64)
        held_arrays = (_nothing_held() if held is None
                       else (held.member, held.block, held.block32, held.loaded, held.factor, held.loaded_block32))
        counts.sweeps, err, change, status, member, block, block32, loaded, factor, loaded_block32 = _restricted_core(
            W, True, False, blocks, q, mu_arr, rho_err * (1.0 if nsgs else rho_factor), rho_err, dim, r, x, tol,
            max_iter, _REFRESH, nsgs, rho_factor if nsgs else 1.0, _SCAN_COS, _SCAN_SIN, NEAR_MARGIN, float32_sweeps,
            stats, predictor, *held_arrays)
        counts.passes, counts.working_set, counts.joined = (int(v) for v in stats[:3])
        counts.predictor_steps = int(stats[5])
        counts.sweeps -= counts.predictor_steps
        counts.block_held = held is not None and block is held.block
        if holding is not None and block.shape[0] > 0 and not counts.block_held:
            _held[0] = _HeldBlock(holding[0], holding[1], member, block, block32, loaded, factor, loaded_block32)
        elif counts.block_held:
            if float32_sweeps and held.block32.shape[0] == 0:
                held.block32 = block32
            held.loaded, held.factor, held.loaded_block32 = loaded, factor, loaded_block32
        if nsgs and status != 2 and not _in_cones(r, mu_arr, dim):
            # As after the full NSGS below: a rounding step outside the cones is projected if that is as good.
            rp = r.copy()
            _project_all(rp, mu_arr, dim)
            xp = np.empty(q.size)
            _recompute_x_by_rows(W, q, rp, xp, np.arange(q.size))
            ep = float(_error(rp, xp, mu_arr, rho_err, dim, _force_scale(q, mu_arr, rho_err, dim)))
            if ep < tol or ep <= err:
                r, x, err = rp, xp, ep
                status = 1 if ep < tol else status
        return r, x, err, change, status
    Wc, indptr, indices, data, sparse = _storage(W)
    x = np.empty(q.size)
    _recompute_x(Wc, indptr, indices, data, sparse, q, r, x)
    if method == "uzawa":
        its, err, change, status = _uzawa_kernel(Wc, indptr, indices, data, sparse, q, mu_arr, rho_err * rho_factor,
                                                 rho_err, dim, r, x, tol, max_iter, _REFRESH)
        counts.sweeps = its
    else:
        P = _Problem(W, q, mu_arr, dim, rho_err, Wc, indptr, indices, data, sparse)
        if method == "nsgs":
            counts.sweeps, err, change, status = P.nsgs(r, x, tol, max_iter, rho_factor)
        elif method == "newton":
            err, change, status = _newton_driver(P, r, x, tol, max_iter, rho_factor, counts)
        else:
            err, change, status = _auto_driver(P, r, x, tol, max_iter, rho_factor, counts)
        if status != 2 and not _in_cones(r, mu_arr, dim):
            # Newton iterates may leave the cones by rounding: keep the projection if it is as good.
            rp = r.copy()
            _project_all(rp, mu_arr, dim)
            xp = P.x_of(rp)
            ep = P.error(rp, xp)
            if ep < tol or ep <= err:
                r, x, err = rp, xp, ep
                status = 1 if ep < tol else status
    if status == 0:
        # Report the x of the returned r, not the incrementally updated one.
        _recompute_x(Wc, indptr, indices, data, sparse, q, r, x)
    return r, x, err, change, status


def _solve_normal(W: np.ndarray | sp.csc_matrix, q: np.ndarray, dim: int, method: str, tol: float, max_iter: int,
                  r: np.ndarray, rho_factor: float, counts: _Counts, rho_err: np.ndarray | None = None
                  ) -> tuple[np.ndarray, np.ndarray, float, float, int]:
    """The frictionless problem on its normal rows alone: (r, x, error, change, status), see :func:`solve`.

    With ``mu = 0`` the cone is the half-line ``{r_n >= 0, r_t = 0}``, so ``r_t = 0`` and the normal forces
    solve the LCP ``x_n = W_nn r_n + q_n``, ``0 <= r_n _|_ x_n >= 0`` (``W_nn``: the normal rows and columns
    of ``W``); the tangential rows only give the slip ``x_t = W_tn r_n + q_t`` afterwards. The error is
    :func:`natural_map_error` of the full problem (same ``rho_a`` from the full blocks, same scale: the
    tangential terms vanish with ``mu = 0``).
    """
    nc = q.size // dim
    rows = np.arange(nc) * dim
    rho_err = block_rho(W, dim) if rho_err is None else rho_err
    Wn = sp.csc_matrix(W[rows][:, rows]) if sp.issparse(W) else np.ascontiguousarray(W[np.ix_(rows, rows)])
    N = _NormalProblem(Wn, np.ascontiguousarray(q[rows]), rho_err)
    rn = np.ascontiguousarray(r[rows])
    rn[~(rn > 0.0)] = 0.0  # projection on the half-line (a warm start may lie outside)
    xn = N.x_of(rn)
    if method == "uzawa":
        counts.sweeps, err, change, status = N.sweeps(rn, xn, tol, max_iter, rho_err * rho_factor, False, 1.0)
    elif method == "nsgs":
        counts.sweeps, err, change, status = N.sweeps(rn, xn, tol, max_iter, N.diag, True, rho_factor)
    else:
        if method == "newton":
            err, change, status = _lcp_newton(N, rn, xn, tol, max_iter, rho_factor, counts)
        else:
            err, change, status = _sweeps_then_newton(
                lambda k: N.sweeps(rn, xn, tol, k, N.diag, True, 1.0),
                lambda: _lcp_newton(N, rn, xn, tol, max_iter, rho_factor, counts),
                N.error(rn, xn), nc, N.sparse, tol, max_iter, counts)
        if status != 2 and np.any(rn < 0.0):
            rp = np.maximum(rn, 0.0)  # Newton iterates may leave r >= 0 by rounding
            xp = N.x_of(rp)
            ep = N.error(rp, xp)
            if ep < tol or ep <= err:
                rn, xn, err = rp, xp, ep
                status = 1 if ep < tol else status
    if status != 1:
        xn = N.x_of(rn)  # the x of the returned r, not the incrementally updated one
    r_full = np.zeros(q.size)
    r_full[rows] = rn
    x = np.empty(q.size)
    if sp.issparse(W):
        _recompute_x(np.zeros((1, 1)), W.indptr.astype(np.int64), W.indices.astype(np.int64), W.data, True, q, r_full,
                     x)
    else:
        _tangential_x(W, q, r_full, dim, x)
    x[rows] = xn
    return r_full, x, err, change, status


@dataclass
class _NormalProblem:
    """The normal problem ``x = W_nn r + q_n`` of a frictionless local problem (see :func:`_solve_normal`)."""

    W: np.ndarray | sp.csc_matrix
    q: np.ndarray
    rho_err: np.ndarray

    def __post_init__(self):
        self.Wc, self.indptr, self.indices, self.data, self.sparse = _storage(self.W)
        self.scale = _lcp_scale(self.q, self.rho_err)
        self.diag = np.ascontiguousarray(self.W.diagonal() if self.sparse else np.diag(self.W))

    def x_of(self, r: np.ndarray) -> np.ndarray:
        """``W_nn r + q_n`` computed afresh."""
        x = np.empty(self.q.size)
        _recompute_x(self.Wc, self.indptr, self.indices, self.data, self.sparse, self.q, r, x)
        return x

    def error(self, r: np.ndarray, x: np.ndarray) -> float:
        """The natural-map error (:func:`_lcp_error`)."""
        return float(_lcp_error(r, x, self.rho_err, self.scale))

    def sweeps(self, r: np.ndarray, x: np.ndarray, tol: float, max_iter: int, step: np.ndarray, exact: bool,
               omega: float) -> tuple[int, float, float, int]:
        """Up to ``max_iter`` Gauss-Seidel sweeps in place (:func:`_lcp_kernel`)."""
        return _lcp_kernel(self.Wc, self.indptr, self.indices, self.data, self.sparse, self.q,
                           np.ascontiguousarray(step, dtype=float), exact, float(omega), self.rho_err, r, x,
                           float(tol), int(max_iter), _REFRESH)

    def active_solve(self, act: np.ndarray) -> np.ndarray | None:
        """``r`` with ``r_A`` solving ``W_AA r_A = -q_A`` and 0 elsewhere; None if ``W_AA`` is singular."""
        r = np.zeros(self.q.size)
        if not act.any():
            return r
        idx = np.flatnonzero(act)
        rhs = -self.q[idx]
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            try:
                if self.sparse:
                    sol = spla.splu(sp.csc_matrix(self.W[idx][:, idx])).solve(rhs)
                else:
                    A = self.W[np.ix_(idx, idx)]
                    try:  # W_AA is SPD for an SPD W: Cholesky
                        sol = sla.cho_solve(sla.cho_factor(A, check_finite=False), rhs, check_finite=False)
                    except np.linalg.LinAlgError:
                        sol = _dense_lu_solve(A, rhs)
                        if sol is None:
                            return None
            except (RuntimeError, ValueError, np.linalg.LinAlgError):
                return None
        if not np.all(np.isfinite(sol)):
            return None
        r[idx] = sol
        return r


def _lcp_newton(N: _NormalProblem, r: np.ndarray, x: np.ndarray, tol: float, max_iter: int, rho_factor: float,
                n: _Counts) -> tuple[float, float, int]:
    """Semismooth Newton (primal-dual active set) on ``F(r) = r - max(0, r - rho x)``, safeguarded, in place.

    With the active set ``A = {r - rho x > 0}`` (``rho = rho_factor / ||W_aa||_2``), the Newton iterate is
    ``r_A`` solving ``W_AA r_A = -q_A``, ``r = 0`` elsewhere (one Cholesky of ``W_AA``). The step is
    damped by an Armijo rule on ``||F||^2 / 2`` (at most 30 halvings); when no step is acceptable, ``W_AA``
    is singular, or 10 steps in a row do not halve the best error, projected Gauss-Seidel sweeps follow (10,
    doubled each time Newton made no progress since the previous fallback, at most 1000) and Newton resumes.
    PGS converges on its own for an SPD ``W_nn``, so the safeguard makes the whole globally convergent.
    ``n.total`` (sweeps + steps) is capped by ``max_iter``.

    Returns (error, change, status) with status 1 converged, 0 max_iter, 2 non-finite.
    """
    rho = N.rho_err * rho_factor
    err = N.error(r, x)
    change = 0.0
    if err < tol:
        return err, change, 1
    fb = _NEWTON_FALLBACK
    progress = True
    best_err, since_best = err, 0

    def merit(rv, xv):
        return 0.5 * float(np.sum((rv - np.maximum(rv - rho * xv, 0.0)) ** 2))

    while n.total < max_iter:
        th = merit(r, x)
        r_new = N.active_solve(r - rho * x > 0.0)
        n.steps += 1
        accepted = False
        if r_new is not None:
            d = r_new - r
            x_new = N.x_of(r_new)
            Wd = x_new - x
            alpha = 1.0
            for _ in range(30):
                if merit(r + alpha * d, x + alpha * Wd) <= (1.0 - 1e-4 * alpha) * th:
                    accepted = True
                    break
                alpha *= 0.5
        if accepted:
            r_next = r_new if alpha == 1.0 else r + alpha * d
            change = alpha * np.linalg.norm(d) / max(np.linalg.norm(r_next), 1e-300)
            r[:] = r_next
            x[:] = x_new if alpha == 1.0 else N.x_of(r)
            err = N.error(r, x)
            if not (math.isfinite(err) and math.isfinite(change)):
                return err, change, 2
            if err < tol:
                return err, change, 1
            if err < 0.5 * best_err:
                best_err, since_best, progress = err, 0, True
            else:
                since_best += 1
            if since_best < _NEWTON_STALL:
                continue
        n.fallbacks += 1
        since_best = 0
        fb = fb if progress else min(2 * fb, 1000)
        k = min(fb, max_iter - n.total)
        if k <= 0:
            break
        np.maximum(r, 0.0, out=r)  # the sweeps start inside the half-line
        x[:] = N.x_of(r)
        its, err, change, status = N.sweeps(r, x, tol, k, N.diag, True, 1.0)
        n.sweeps += its
        if status != 0:
            return err, change, status
        progress = False
        best_err = min(best_err, err)
    return err, change, 0


def _in_cones(r: np.ndarray, mu: np.ndarray, dim: int) -> bool:
    R = r.reshape(-1, dim)
    return bool(np.all(R[:, 0] >= 0.0) and np.all(np.linalg.norm(R[:, 1:], axis=1) <= mu * R[:, 0]))


# "auto": NSGS windows of 10 sweeps, Newton once the projected remaining sweeps exceed m (10 Newton steps at
# about m/8 sweeps each, measured); no dense Newton above 6000 unknowns (an LU costs minutes there).
_AUTO_WINDOW = 10
_AUTO_DENSE_MAX = 6000


def _auto_driver(P: _Problem, r: np.ndarray, x: np.ndarray, tol: float, max_iter: int, rho_factor: float,
                 n: _Counts) -> tuple[float, float, int]:
    """NSGS while it is cheaper than Newton, then Newton (see :func:`solve`, ``method="auto"``)."""
    return _sweeps_then_newton(lambda k: P.nsgs(r, x, tol, k),
                               lambda: _newton_driver(P, r, x, tol, max_iter, rho_factor, n),
                               P.error(r, x), r.size, P.sparse, tol, max_iter, n)


def _sweeps_then_newton(sweeps, newton, err: float, m: int, sparse: bool, tol: float, max_iter: int, n: _Counts
                        ) -> tuple[float, float, int]:
    """The ``"auto"`` policy: ``sweeps(k)`` (in place; returns (sweeps, error, change, status)) in windows
    of 10 while the error's rate over the last window projects fewer remaining sweeps than ``m`` unknowns,
    then ``newton()``; sweeps only for a dense problem above 6000 unknowns."""
    if err < tol:
        return err, 0.0, 1
    newton_ok = sparse or m <= _AUTO_DENSE_MAX
    change = 0.0
    while n.total < max_iter:
        prev = err
        its, err, change, status = sweeps(min(_AUTO_WINDOW, max_iter - n.total))
        n.sweeps += its
        if status != 0:
            return err, change, status
        if not newton_ok:
            continue
        rate = (err / prev) ** (1.0 / its) if prev > 0.0 else 0.0
        remaining = math.log(tol / err) / math.log(rate) if 0.0 < rate < 1.0 else np.inf
        if remaining > m:
            break
    if n.total >= max_iter:
        return err, change, 0
    return newton()


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
