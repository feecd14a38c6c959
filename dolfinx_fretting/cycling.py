"""Compiled loop over the increments of fretting cycles: displacement or pressure control, and force control.

When no load is force controlled, an increment's right-hand side is known in advance:

    q_abs = g0 + g_w - G D + sum_l s_l q_l      (normal rows: gaps; tangential rows: positions)
    q     = q_abs - y_prev   in the tangential rows  (so x_t is the slip increment, paper eq. 3)

with D the obstacle's rigid translation (each zone's in turn with several contact zones), G its local effect
(``ContactSet.rigid_modes``; block-diagonal over the zones), s_l the factor of load l and q_l = H K^-1 f_l the
contact displacement per unit factor of that load. So a whole cycle (thousands in a run) can run in one compiled
call:
local Uzawa solve (:mod:`dolfinx_fretting.local_solvers`; on the normal rows alone when ``mu = 0``, with
the same iterates; else on the working set of closed and nearly closed contacts, its block ``W_AA`` held from one
local solve to the next while the set is the same, as ``local_solvers.solve`` holds it), then
:func:`dolfinx_fretting.wear.commit_increment`.
Python only sees a cycle's outputs. The result is the same as the per-increment Python path (a test
checks it); only the warm start may differ: ``warm = 1`` starts each increment from the same increment of
the previous cycle (the state is nearly periodic, so few sweeps are needed), ``warm = 0`` from the
previous increment (the straightforward choice).

In 2D the loop can also reuse the previous cycle's *contact pattern* (``active = True``): the state of
every contact (open, stick, slip with the sign of its friction force) at the same increment of the
previous cycle turns the local problem into a linear one,

    open:  r = 0;     stick:  (W r + q)_n = 0, (W r + q)_t = 0;     slip:  (W r + q)_n = 0, r_t = s mu r_n,

whose LU factors are cached per increment of the cycle and reused while the pattern holds. Its solution
is accepted only if it meets the same natural-map tolerance as the Uzawa iteration (so it is then exact to
rounding); otherwise the Uzawa sweeps start from it. Patterns change rarely once the wear is under way,
so most increments cost one triangular solve and one residual check.

Finite sliding's loop (W changes with every pairing, so nothing can be cached per increment) tries instead the
pattern of each solve's warm start (``warm_pattern = True``: :func:`warm_pattern_solve`, an LU of the closed
contacts' unknowns only, the pattern corrected from a failed answer up to ``PATTERN_ATTEMPTS`` times), under
force control too: the increment-by-increment path of finite sliding tries the same, so the two stay equal to
rounding while both give exact local solutions (the root finder's trials then meet ``force_tol`` on other values
than the sweeps' answers: the answers moved by up to 1.5e-7 relative, ``benchmarks/results/sliding_speed.md``).

A prescribed force makes its obstacle component unknown: q is affine in the obstacle's components d,
``q_abs(d) = q_abs(0) - G T d`` (T: the translation per unit component), and the total force along them is
``F = A r``. :func:`run_force_increments` finds d per increment by the stepwise path's load control
(``increments._local_with_control`` and :func:`~dolfinx_fretting.loading.find_displacement`: Gauss-Seidel sweeps
over the controlled components, each a bracketing then an Illinois regula falsi, every trial one local solve warm
started from the previous trial), step for step, so its answers are the stepwise path's to rounding. It tries no
cached pattern: the root finder would stop on other trials and move the answers by the local tolerance's effect.

A failed increment stops the loop: the converged increments before it are committed (their wear is
legitimate), the failed one leaves no trace in ``wear_gap``, ``y`` or ``r_warm``.

Friction that evolves with the dissipated energy (:class:`~dolfinx_fretting.laws.EvolvingFriction` of a table,
variable ``"energy"``) runs inside the loop too (:class:`FrictionEvolution`): before each increment every contact of
such a zone takes ``mu = interp(E)`` from its table at its accumulated energy density E (``np.interp``'s formula),
the wear rate ``k = k0 + k1 mu`` (Archard: k1 = 0; Fouvry's energy law: k0 = 0, k1 = alpha x acceleration) and, with
the cached patterns, an increment's factors made with another mu are dropped; after it E grows by
``scale (-r_t . dx_t) / A`` (:func:`~dolfinx_fretting.friction.energy_density`'s terms, in its order). That is the
per-increment path's arithmetic step for step (``cycles.compiled_cycle`` with the user's function: one call per
increment), so the answers are the same to rounding.
"""

from __future__ import annotations

import math

import numba
import numpy as np

from .loading import FORCE_SWEEPS
from .local_solvers import (GROSS_SLIP_PREDICTOR, NEAR_MARGIN, _error, _force_scale, _lcp_kernel, _nothing_held,
                            _recompute_x, _restricted_core)
from .wear import ROW_FIELDS, commit_increment

__all__ = ["run_increments", "run_force_increments", "ActivePatternCache", "FrictionEvolution", "N_ROW",
           "HELD_BLOCK_ARGUMENTS", "warm_pattern_solve"]

#: The package's ``hold_block``, ``float32_sweeps`` for the loops below (the block held; float64 sweeps). The loops
#: take them without defaults: an argument left to a default makes numba's dispatcher fold the call in Python and
#: type every array argument there (~1.3 ms a call: 17 % of the main job's CPU, benchmarks/results/refactor.md,
#: session 12).
HELD_BLOCK_ARGUMENTS = (True, False)

#: Number of columns of the per-increment output (the :data:`~dolfinx_fretting.wear.ROW_FIELDS`, then
#: local iterations and local error).
N_ROW = len(ROW_FIELDS) + 2


class ActivePatternCache:
    """Per-increment contact patterns and LU factors of the previous cycle (2D), for ``run_increments``.

    Args:
        n: Increments per cycle.
        nc: Contacts.
        dim: Must be 2 for the cache to be used (an empty cache otherwise).
    """

    def __init__(self, n: int, nc: int, dim: int):
        m = nc * dim
        used = dim == 2
        self.enabled = used
        shape_n, shape_m = (n, nc) if used else (1, 1), (n, m, m) if used else (1, 1, 1)
        self.pattern = np.full(shape_n, -1, dtype=np.int8)     # -1: unknown
        self.lu = np.zeros(shape_m)
        self.piv = np.zeros((n, m) if used else (1, 1), dtype=np.int64)
        self.lu_ok = np.zeros(n if used else 1, dtype=np.bool_)
        #: Counts of the exact pattern solves accepted and rejected, of the factorisations, and of the local solves
        #: that swept the working set's block held from the solve before and of those that gathered one (any dim).
        self.counts = np.zeros(5, dtype=np.int64)
        #: The friction coefficients each increment's factors were made with (NaN: none yet): an evolving
        #: friction law changes mu between cycles, and a factor of another mu is dropped before the loop.
        self.factor_mu = np.full(shape_n, np.nan)


@numba.njit(cache=True)
def _lu_factor(A: np.ndarray, piv: np.ndarray) -> bool:
    """In-place LU with partial pivoting (A = P L U); False if a pivot is zero to rounding."""
    m = A.shape[0]
    scale = 0.0
    for i in range(m):
        for j in range(m):
            scale = max(scale, abs(A[i, j]))
    for k in range(m):
        p = k
        best = abs(A[k, k])
        for i in range(k + 1, m):
            if abs(A[i, k]) > best:
                best = abs(A[i, k])
                p = i
        piv[k] = p
        if best <= 1e-13 * scale:
            return False
        if p != k:
            for j in range(m):
                tmp = A[k, j]
                A[k, j] = A[p, j]
                A[p, j] = tmp
        inv = 1.0 / A[k, k]
        for i in range(k + 1, m):
            f = A[i, k] * inv
            if f != 0.0:
                A[i, k] = f
                for j in range(k + 1, m):
                    A[i, j] -= f * A[k, j]
            else:
                A[i, k] = 0.0
    return True


@numba.njit(cache=True)
def _lu_solve(LU: np.ndarray, piv: np.ndarray, b: np.ndarray) -> None:
    """Solve in place with the factors of :func:`_lu_factor`."""
    m = b.size
    for k in range(m):
        p = piv[k]
        if p != k:
            tmp = b[k]
            b[k] = b[p]
            b[p] = tmp
    for i in range(m):
        s = b[i]
        for j in range(i):
            s -= LU[i, j] * b[j]
        b[i] = s
    for i in range(m - 1, -1, -1):
        s = b[i]
        for j in range(i + 1, m):
            s -= LU[i, j] * b[j]
        b[i] = s / LU[i, i]


class FrictionEvolution:
    """Friction of the dissipated energy inside the compiled loop: the arrays the kernels read (see the module doc).

    Args:
        energy: (nc,) each contact's accumulated dissipated energy density (in/out: the loop adds each increment's).
        scale: The factor on each increment's energy (the wear law's acceleration in a cycle).
        table_of: (nc,) each contact's table (a row of ``abscissae``), -1 where mu is held over the cycle.
        abscissae, values: (tables, L) the tables' rows, padded past ``lengths``.
        lengths: (tables,) each table's rows.
        wear_base, wear_per_mu: (nc,) the wear rate's ``k0`` and ``k1`` (``k = k0 + k1 mu``).
    """

    def __init__(self, energy: np.ndarray, scale: float, table_of: np.ndarray, abscissae: np.ndarray,
                 values: np.ndarray, lengths: np.ndarray, wear_base: np.ndarray, wear_per_mu: np.ndarray):
        self.evolve = True
        self.energy = np.ascontiguousarray(energy, dtype=float)
        self.scale = float(scale)
        self.table_of = np.ascontiguousarray(table_of, dtype=np.int64)
        self.abscissae = np.ascontiguousarray(abscissae, dtype=float)
        self.values = np.ascontiguousarray(values, dtype=float)
        self.lengths = np.ascontiguousarray(lengths, dtype=np.int64)
        self.wear_base = np.ascontiguousarray(wear_base, dtype=float)
        self.wear_per_mu = np.ascontiguousarray(wear_per_mu, dtype=float)

    @classmethod
    def held(cls) -> "FrictionEvolution":
        """No evolution (mu held over the cycle): the kernels' arguments, unused."""
        out = cls(np.zeros(1), 0.0, np.full(1, -1), np.zeros((1, 1)), np.zeros((1, 1)), np.ones(1), np.zeros(1),
                  np.zeros(1))
        out.evolve = False
        return out

    def arguments(self) -> tuple:
        """The kernels' trailing arguments, in order."""
        return (self.evolve, self.energy, self.scale, self.table_of, self.abscissae, self.values, self.lengths,
                self.wear_base, self.wear_per_mu)


@numba.njit(cache=True)
def _interp(x: float, xp: np.ndarray, fp: np.ndarray, n: int) -> float:
    """``np.interp(x, xp[:n], fp[:n])`` for one x, NumPy's arithmetic: held at the end values outside, else
    ``slope (x - xp[j]) + fp[j]`` with ``xp[j] <= x < xp[j + 1]`` (x at a breakpoint: its value)."""
    if x < xp[0]:
        return fp[0]
    if x >= xp[n - 1]:
        return fp[n - 1]
    j = 0
    while xp[j + 1] <= x:
        j += 1
    if xp[j] == x:
        return fp[j]
    slope = (fp[j + 1] - fp[j]) / (xp[j + 1] - xp[j])
    return slope * (x - xp[j]) + fp[j]


@numba.njit(cache=True)
def _friction_before(j: int, mu: np.ndarray, k: np.ndarray, energy: np.ndarray, table_of: np.ndarray,
                     abscissae: np.ndarray, values: np.ndarray, lengths: np.ndarray, wear_base: np.ndarray,
                     wear_per_mu: np.ndarray, active: bool, factor_mu: np.ndarray, lu_ok: np.ndarray) -> None:
    """Increment ``j``'s mu (the tables at the energy), wear rate and stale factors (see the module doc)."""
    nc = mu.size
    for a in range(nc):
        t = table_of[a]
        if t >= 0:
            mu[a] = _interp(energy[a], abscissae[t], values[t], lengths[t])
        k[a] = wear_base[a] + wear_per_mu[a] * mu[a]
    if active:
        stale = False
        for a in range(nc):
            if factor_mu[j, a] != mu[a]:   # (NaN: no factor yet)
                stale = True
            factor_mu[j, a] = mu[a]
        if stale:
            lu_ok[j] = False


@numba.njit(cache=True)
def _friction_after(r: np.ndarray, x: np.ndarray, dim: int, tributary: np.ndarray, scale: float,
                    energy: np.ndarray) -> None:
    """Each contact's energy density after a converged increment: ``E += scale (-r_t . dx_t) / A`` (0 where A is 0),
    term by term as :func:`~dolfinx_fretting.friction.energy_density`."""
    for a in range(energy.size):
        work = 0.0
        for c in range(1, dim):
            work = r[a * dim + c] * x[a * dim + c] if c == 1 else work + r[a * dim + c] * x[a * dim + c]
        density = -work / tributary[a] if tributary[a] > 0 else 0.0
        energy[a] = energy[a] + scale * density


@numba.njit(cache=True)
def _all_zero(mu: np.ndarray) -> bool:
    for a in range(mu.size):
        if mu[a] != 0.0:
            return False
    return True


@numba.njit(cache=True)
def _pattern_matrix(W: np.ndarray, pattern: np.ndarray, mu: np.ndarray, A: np.ndarray) -> None:
    """The linear system of a 2D contact pattern (0 open, 1 stick, 2 slip with r_t > 0, 3 slip r_t < 0)."""
    nc = pattern.size
    m = 2 * nc
    for i in range(m):
        for j in range(m):
            A[i, j] = 0.0
    for a in range(nc):
        o = 2 * a
        code = pattern[a]
        if code == 0:
            A[o, o] = 1.0
            A[o + 1, o + 1] = 1.0
            continue
        for j in range(m):
            A[o, j] = W[o, j]           # x_n = 0
        if code == 1:
            for j in range(m):
                A[o + 1, j] = W[o + 1, j]   # x_t = 0
        else:
            sgn = 1.0 if code == 2 else -1.0
            A[o + 1, o + 1] = 1.0           # r_t - s mu r_n = 0
            A[o + 1, o] = -sgn * mu[a]


@numba.njit(cache=True)
def _pattern_rhs(q: np.ndarray, pattern: np.ndarray, b: np.ndarray) -> None:
    for a in range(pattern.size):
        o = 2 * a
        code = pattern[a]
        b[o] = 0.0 if code == 0 else -q[o]
        b[o + 1] = -q[o + 1] if code == 1 else 0.0


#: Attempts of :func:`warm_pattern_solve`: the warm start's pattern, then patterns corrected from each failed answer.
#: In gross slip the warm start's pattern holds at most trials; at a contact entering or leaving and at the stroke's
#: reversal (slip, stick, slip the other way, not all contacts at once) a few corrections find it. Measured on
#: McColl's first 100 cycles: 4 attempts leave 39 000 Uzawa sweeps (the reversals' trials), 8 leave 15 000 (against
#: 1.47 million with the sweeps alone); a failed attempt costs an LU of the closed contacts' unknowns (~20-40).
PATTERN_ATTEMPTS = 8

#: Relative margin under which a warm start's |r_t| counts as on the cone (slip): the sweeps leave a sliding contact's
#: force on the cone to rounding, and carrying it into a new pairing's frames rotates it by a few ulps.
ON_CONE = 1e-9


@numba.njit(cache=True)
def _pattern_of_forces(r: np.ndarray, mu: np.ndarray, pattern: np.ndarray) -> None:
    """Each 2D contact's pattern code (:func:`_pattern_matrix`'s) read from its forces: open where r_n <= 0, slip
    (with r_t's sign) where ``|r_t| >= mu r_n`` within :data:`ON_CONE`, else stick."""
    for a in range(pattern.size):
        rn, rt = r[2 * a], r[2 * a + 1]
        if not rn > 0.0:
            pattern[a] = 0
        elif abs(rt) >= mu[a] * rn * (1.0 - ON_CONE):
            pattern[a] = 3 if rt < 0.0 else 2
        else:
            pattern[a] = 1


@numba.njit(cache=True)
def _closed_pattern_solve(W: np.ndarray, q: np.ndarray, mu: np.ndarray, pattern: np.ndarray, r: np.ndarray) -> bool:
    """r (out) of a 2D contact pattern, :func:`_pattern_matrix`'s equations on the closed contacts only (r = 0 at the
    open ones): an LU of ``2 n_closed`` unknowns, not of all ``2 nc``. False if that matrix is singular to rounding."""
    nc = pattern.size
    closed = np.empty(nc, dtype=np.int64)
    n_closed = 0
    for a in range(nc):
        if pattern[a] != 0:
            closed[n_closed] = a
            n_closed += 1
    for i in range(r.size):
        r[i] = 0.0
    if n_closed == 0:
        return True
    size = 2 * n_closed
    A = np.zeros((size, size))
    b = np.zeros(size)
    for i in range(n_closed):
        a = closed[i]
        code = pattern[a]
        for k in range(n_closed):          # x_n = 0
            c = closed[k]
            A[2 * i, 2 * k] = W[2 * a, 2 * c]
            A[2 * i, 2 * k + 1] = W[2 * a, 2 * c + 1]
        b[2 * i] = -q[2 * a]
        if code == 1:                      # x_t = 0
            for k in range(n_closed):
                c = closed[k]
                A[2 * i + 1, 2 * k] = W[2 * a + 1, 2 * c]
                A[2 * i + 1, 2 * k + 1] = W[2 * a + 1, 2 * c + 1]
            b[2 * i + 1] = -q[2 * a + 1]
        else:                              # r_t - s mu r_n = 0
            A[2 * i + 1, 2 * i + 1] = 1.0
            A[2 * i + 1, 2 * i] = -(1.0 if code == 2 else -1.0) * mu[a]
    piv = np.empty(size, dtype=np.int64)
    if not _lu_factor(A, piv):
        return False
    _lu_solve(A, piv, b)
    for i in range(n_closed):
        r[2 * closed[i]] = b[2 * i]
        r[2 * closed[i] + 1] = b[2 * i + 1]
    return True


@numba.njit(cache=True)
def _corrected_pattern(r: np.ndarray, x: np.ndarray, mu: np.ndarray, pattern: np.ndarray) -> bool:
    """Correct a 2D pattern from its answer where it breaks Coulomb's law (a primal-dual active-set step): a closed
    contact pulling (r_n < 0) opens; an open one penetrating (x_n < 0) closes, sliding against its slip (stuck if
    x_t = 0); a stuck one beyond the cone slides with r_t's sign; a sliding one whose slip has r_t's sign sticks.
    False if nothing changed (the answer failed the tolerance on no sign: no better pattern to try)."""
    changed = False
    for a in range(pattern.size):
        rn, rt, xn, xt = r[2 * a], r[2 * a + 1], x[2 * a], x[2 * a + 1]
        code = pattern[a]
        new = code
        if code == 0:
            if xn < 0.0:
                new = 1 if xt == 0.0 else (3 if xt > 0.0 else 2)
        elif rn < 0.0:
            new = 0
        elif code == 1:
            if abs(rt) > mu[a] * rn:
                new = 3 if rt < 0.0 else 2
        elif (xt > 0.0 and code == 2) or (xt < 0.0 and code == 3):
            new = 1
        if new != code:
            pattern[a] = new
            changed = True
    return changed


@numba.njit(cache=True)
def warm_pattern_solve(W: np.ndarray, q: np.ndarray, mu: np.ndarray, rho: np.ndarray, tol: float, r: np.ndarray,
                       x: np.ndarray) -> tuple[bool, float, int]:
    """A 2D local problem solved exactly on the contact pattern of its warm start, before any sweep (finite sliding).

    The pattern (open, stick, slip with the sign of r_t) is read from the warm start ``r``
    (:func:`_pattern_of_forces`), its linear system solved on the closed contacts (:func:`_closed_pattern_solve`),
    and the answer accepted only if its natural-map error on ``x = W r + q`` recomputed is below ``tol``, the Uzawa
    sweeps' own criterion (so it is then a solution to rounding). A failed answer corrects the pattern where it
    breaks Coulomb's law (:func:`_corrected_pattern`), up to ``PATTERN_ATTEMPTS`` patterns in all.

    Args:
        W: The Delassus matrix (m, m), symmetric (read as W and as W^T).
        q: The free relative displacement (m,).
        mu, rho: Per contact: friction coefficient, Uzawa step (the error's scale, as the sweeps').
        tol: The local tolerance.
        r: (m,) in: the warm start; out: the answer if accepted, else the warm start unchanged.
        x: (m,) out: ``W r + q`` of the answer if accepted (else overwritten).

    Returns:
        (accepted, the last answer's error, patterns tried).
    """
    nc = mu.size
    m = q.size
    pattern = np.empty(nc, dtype=np.int8)
    _pattern_of_forces(r, mu, pattern)
    trial = np.empty(m)
    empty_i, empty_f = np.zeros(1, dtype=np.int64), np.zeros(1)
    scale = _force_scale(q, mu, rho, 2)
    err = np.inf
    for attempt in range(PATTERN_ATTEMPTS):
        if not _closed_pattern_solve(W, q, mu, pattern, trial):
            return False, err, attempt + 1
        _recompute_x(W, empty_i, empty_i, empty_f, False, q, trial, x)
        err = _error(trial, x, mu, rho, 2, scale)
        if err < tol:
            for i in range(m):
                r[i] = trial[i]
            return True, err, attempt + 1
        if not _corrected_pattern(trial, x, mu, pattern):
            return False, err, attempt + 1
    return False, err, PATTERN_ATTEMPTS


@numba.njit(cache=True)
def _normal_rows(Wc: np.ndarray, mu: np.ndarray, dim: int
                 ) -> tuple[bool, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """(frictionless?, W_nn, and the work arrays q_n, r_n, x_n of its size): without friction the Uzawa sweeps run
    on the normal rows alone (W_nn, transposed like Wc), the iterates being those of the full sweep with mu = 0
    (r_t stays 0; see local_solvers.solve)."""
    nc = mu.size
    normal_only = True
    for a in range(nc):
        if mu[a] != 0.0:
            normal_only = False
    nn = nc if normal_only else 1
    Wn = np.empty((nn, nn))
    if normal_only:
        for b in range(nc):
            for a in range(nc):
                Wn[b, a] = Wc[b * dim, a * dim]
    return normal_only, Wn, np.empty(nn), np.empty(nn), np.empty(nn)


@numba.njit(cache=True)
def _rhs(g0: np.ndarray, wear_gap: np.ndarray, G: np.ndarray, D: np.ndarray, Q: np.ndarray, S: np.ndarray,
         y: np.ndarray, dim: int, q_abs: np.ndarray, q: np.ndarray) -> None:
    """q_abs and q (out) of an increment with translation ``D`` (gdim,) and load factors ``S`` (L,)."""
    nc = g0.size
    gdim = G.shape[1]
    n_loads = Q.shape[0]
    # q_abs = g0 + g_w - G D + sum_l S_l Q_l, term by term in this order (so that a plane frame with
    # exact zeros gives g0 + g_w - d_n and -d_t exactly, as the Python path's increments do).
    for a in range(nc):
        o = a * dim
        for c in range(dim):
            v = g0[a] + wear_gap[a] if c == 0 else 0.0
            for comp in range(gdim):   # (not k: that is the wear coefficient)
                v += -G[o + c, comp] * D[comp]
            for load in range(n_loads):
                v += S[load] * Q[load, o + c]
            q_abs[o + c] = v
            q[o + c] = v if c == 0 else v - y[o + c]


@numba.njit(cache=True)
def _finish(j: int, r: np.ndarray, x: np.ndarray, q: np.ndarray, q_abs: np.ndarray, y: np.ndarray, mu: np.ndarray,
            dim: int, tributary: np.ndarray, abscissa: np.ndarray, k: np.ndarray, wear_gap: np.ndarray,
            states: np.ndarray, row: np.ndarray, its: int, err: float, rows: np.ndarray, r_warm: np.ndarray,
            r_last: np.ndarray, keep: bool, out_r: np.ndarray, out_x: np.ndarray, out_y: np.ndarray,
            out_wear: np.ndarray, out_states: np.ndarray, active: bool, pattern: np.ndarray, lu_ok: np.ndarray
            ) -> None:
    """Commit converged increment ``j`` (r, x of q; positions, wear, its row, the warm starts, the pattern)."""
    m = r.size
    nc = mu.size
    nfields = row.size
    # y = W r + q_abs = x + (q_abs - q)
    for i in range(m):
        y[i] = x[i] + q_abs[i] - q[i]
    commit_increment(r, x, y, mu, dim, tributary, abscissa, k, wear_gap, states, row)
    if active:
        same = pattern[j, 0] >= 0
        for a in range(nc):
            code = states[a]
            if code == 2 and r[a * dim + 1] < 0.0:
                code = 3
            if pattern[j, a] != code:
                same = False
                pattern[j, a] = code
        if not same:
            lu_ok[j] = False
    for i in range(nfields):
        rows[j, i] = row[i]
    rows[j, nfields] = its
    rows[j, nfields + 1] = err
    for i in range(m):
        r_warm[j, i] = r[i]
        r_last[i] = r[i]
    if keep:
        for i in range(m):
            out_r[j, i] = r[i]
            out_x[j, i] = x[i]
            out_y[j, i] = y[i]
        for a in range(nc):
            out_wear[j, a] = wear_gap[a]
            out_states[j, a] = states[a]


@numba.njit(cache=True)
def _solve_local(Wc: np.ndarray, Wn: np.ndarray, normal_only: bool, rho: np.ndarray, mu: np.ndarray, dim: int,
                 q: np.ndarray, r: np.ndarray, x: np.ndarray, tol: float, max_iter: int, refresh: int, active: bool,
                 j: int, pattern: np.ndarray, lu: np.ndarray, piv: np.ndarray, lu_ok: np.ndarray, counts: np.ndarray,
                 xs: np.ndarray, qn: np.ndarray, rn: np.ndarray, xn: np.ndarray,
                 held: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray], hold_block: bool,
                 float32_sweeps: bool, warm_pattern: bool, q_before: np.ndarray, x_known: np.ndarray
                 ) -> tuple[int, float, int, tuple[np.ndarray, ...]]:
    """One local solve of increment ``j`` from the warm start ``r`` (in/out; ``x`` out): the exact answer when no
    contact penetrates, else the cached contact pattern (``active``) or the warm start's (``warm_pattern``, 2D:
    :func:`warm_pattern_solve`, counted in ``counts[0]`` accepted and ``counts[1]`` not), else the Uzawa sweeps (on
    the normal rows alone when ``normal_only``; ``Wn`` their W; else on the working set, as ``local_solvers.solve``'s
    default: in 3D the gross-slip predictor first, ``local_solvers.GROSS_SLIP_PREDICTOR``). ``xs``, ``qn``, ``rn``,
    ``xn``: work arrays.

    ``held``: the working set, its ``(W_AA)^T`` and float32 copy, and the gross-slip predictor's loaded contacts,
    Cholesky factor and float32 loaded block, of an earlier solve of this call of the loop
    (``local_solvers._nothing_held`` at first): the sweeps use the block again while the set is the same, the
    predictor its factor and loaded block while the loaded contacts are, instead of gathering and factoring again
    (cost: ``benchmarks/results/loop_speed.md``). Sound because ``Wc`` is fixed within a call of the loop (no loop
    changes it; a new W is a new call, which starts with nothing held): the same values, so the same bits.
    ``hold_block`` False: nothing is held (the block gathered at every solve). ``counts`` of 5 entries (an
    :class:`ActivePatternCache`'s) gets the solves that swept the held block in ``counts[3]`` and those that
    gathered one in ``counts[4]`` (a shorter ``counts``, finite sliding's 3, gets neither). ``float32_sweeps``: the
    sweeps' updates of x read a float32 copy of the block (held beside it), as
    ``local_solvers.solve(..., float32_sweeps=True)``.

    ``x_known`` (bool, 1; in/out) True: ``x = W r + q_before`` on entry, ``q_before`` the right-hand side of the solve
    before (the caller vouches that ``r`` has not changed since): the sweeps' start ``W r + q`` is then ``x + q -
    q_before`` (O(m); forming it from ``W`` reads every loaded column, 7.1 ms at 2025 contacts, local_speed.md), the
    same up to rounding; an answer at that start is judged again on ``x`` formed exactly. On return ``x_known`` says
    whether ``x = W r + q`` exactly (a converged solve), and ``q_before`` holds ``q`` then.

    Returns (sweeps and predictor steps, error, local status: 1 converged, what is held for the next solve)."""
    m = q.size
    nc = mu.size
    empty_i = np.zeros(1, dtype=np.int64)
    empty_f = np.zeros(1)
    empty_blocks = np.zeros((1, dim, dim))
    working_stats = np.zeros(7, dtype=np.int64)
    its = 0
    err = 0.0
    known = x_known[0]
    x_known[0] = False   # until this solve's x is W r + q
    # No contact penetrates: r = 0 is an exact solution (x = q), as in local_solvers.solve.
    exact = True
    for a in range(nc):
        if q[a * dim] < 0.0:
            exact = False
            break
    if exact:
        for i in range(m):
            r[i] = 0.0
            x[i] = q[i]
        its = 0
        err = 0.0
    elif warm_pattern and dim == 2:
        known = False   # the tries leave r and x as they please
        accepted, err, _tried = warm_pattern_solve(Wc, q, mu, rho, tol, r, x)   # Wc = W^T = W
        if accepted:
            exact = True
            its = 0
            counts[0] += 1
        else:
            counts[1] += 1
    elif active and pattern[j, 0] >= 0:
        known = False   # the pattern's x replaces the warm start's
        if not lu_ok[j]:
            _pattern_matrix(Wc, pattern[j], mu, lu[j])   # Wc = W^T = W
            lu_ok[j] = _lu_factor(lu[j], piv[j])
            counts[2] += 1
        if lu_ok[j]:
            for i in range(m):
                xs[i] = r[i]
            _pattern_rhs(q, pattern[j], r)
            _lu_solve(lu[j], piv[j], r)
            _recompute_x(Wc, empty_i, empty_i, empty_f, False, q, r, x)
            err = _error(r, x, mu, rho, dim, _force_scale(q, mu, rho, dim))
            if err < tol:
                exact = True
                its = 0
                counts[0] += 1
            else:
                counts[1] += 1
                for i in range(m):     # back to the warm start: the pattern was wrong
                    r[i] = xs[i]
    if not exact and normal_only:
        for a in range(nc):
            qn[a] = q[a * dim]
            rn[a] = r[a * dim]
        _recompute_x(Wn, empty_i, empty_i, empty_f, False, qn, rn, xn)
        its, err, change, status = _lcp_kernel(Wn, empty_i, empty_i, empty_f, False, qn, rho, False, 1.0, rho,
                                               rn, xn, tol, max_iter, refresh)
        if status != 1:
            return its, err, status, held
        for a in range(nc):
            r[a * dim] = rn[a]
            for c in range(1, dim):
                r[a * dim + c] = 0.0
        _recompute_x(Wc, empty_i, empty_i, empty_f, False, q, r, x)  # the slip rows too
    elif not exact:
        # Sweeps on the closed and nearly closed contacts, then a check on all (local_solvers.solve's default). x on
        # every row by W^T's rows, before and at the check: contiguous, vectorised reads, faster here than the rows
        # the sweeps read by W's rows and the check's rows apart (measured: local_speed.md, its loop section).
        if known:
            for i in range(m):
                x[i] += q[i] - q_before[i]
        else:
            _recompute_x(Wc, empty_i, empty_i, empty_f, False, q, r, x)
        for _start in range(2):   # the start's own x, then (if it answered at once) x formed exactly
            its, err, change, status, member, block, block32, loaded, factor, loaded_block32 = _restricted_core(
                Wc, False, True, empty_blocks, q, mu, rho, rho, dim, r, x, tol, max_iter, refresh, False, 1.0,
                empty_f, empty_f, NEAR_MARGIN, float32_sweeps, working_stats, GROSS_SLIP_PREDICTOR, *held)
            if not (known and its == 0 and status == 1):
                break
            # Answered at the start, whose x came from the solve before's: judged again on x formed exactly (the
            # core checks x only after it has swept or stepped).
            _recompute_x(Wc, empty_i, empty_i, empty_f, False, q, r, x)
            known = False
        if counts.size >= 5:
            counts[3] += 1 if working_stats[3] > 0 else 0
            counts[4] += 1 if working_stats[3] < working_stats[0] else 0
        if hold_block and block.shape[0] > 0:
            held = (member, block, block32, loaded, factor, loaded_block32)
        if status != 1:
            return its, err, status, held
    for i in range(m):
        q_before[i] = q[i]
    x_known[0] = True
    return its, err, 1, held


@numba.njit(cache=True)
def run_increments(Wc: np.ndarray, rho: np.ndarray, mu: np.ndarray, dim: int, g0: np.ndarray,
                   wear_gap: np.ndarray, G: np.ndarray, D: np.ndarray, Q: np.ndarray, S: np.ndarray,
                   tributary: np.ndarray, abscissa: np.ndarray, y: np.ndarray, r_last: np.ndarray,
                   r_warm: np.ndarray, warm: int, k: np.ndarray, tol: float, max_iter: int, refresh: int,
                   keep: bool, out_r: np.ndarray, out_x: np.ndarray, out_y: np.ndarray, out_wear: np.ndarray,
                   out_states: np.ndarray, rows: np.ndarray, active: bool, pattern: np.ndarray,
                   lu: np.ndarray, piv: np.ndarray, lu_ok: np.ndarray, counts: np.ndarray, factor_mu: np.ndarray,
                   evolve: bool, energy: np.ndarray, energy_scale: float, table_of: np.ndarray,
                   abscissae: np.ndarray, values: np.ndarray, lengths: np.ndarray, wear_base: np.ndarray,
                   wear_per_mu: np.ndarray, hold_block: bool, float32_sweeps: bool,
                   warm_pattern: bool) -> tuple[int, int, float]:
    """Solve ``D.shape[0]`` increments in sequence, committing each converged one.

    Args:
        Wc: W transposed, C-contiguous (m, m) (W is symmetric: W itself).
        rho: Per-contact Uzawa step (``local_solvers.block_rho``).
        mu: Friction coefficient per contact.
        dim: 2 or 3.
        g0: Initial normal gap per contact.
        wear_gap: Wear gap per contact (in/out).
        G: (m, gdim) local relative displacement per unit rigid translation of the obstacle
            (``ContactSet.rigid_modes``).
        D: (n, gdim) obstacle translation per increment, global coordinates.
        Q: (L, m) local displacement per unit factor of each load (``H K^-1 f_l``).
        S: (n, L) load factors per increment.
        tributary, abscissa: Per contact (see :func:`~dolfinx_fretting.wear.commit_increment`).
        y: Total relative position of the last converged increment (m,) (in/out).
        r_last: Forces of the last converged increment (m,) (in/out).
        r_warm: (n, m) forces of the same increments of the previous cycle (in/out: overwritten with
            this cycle's).
        warm: 1: start increment j from ``r_warm[j]``; 0: from ``r_last``.
        k: Wear coefficient applied per contact (1/MPa).
        tol, max_iter, refresh: Local solver settings.
        keep: Store every increment's r, x, y, wear_gap and states in the ``out_*`` arrays ((n, ...) each).
        rows: (n, N_ROW) output rows.
        active: Try the previous cycle's contact pattern first (2D only); ``pattern``, ``lu``, ``piv``,
            ``lu_ok``, ``counts`` and ``factor_mu`` are the arrays of an :class:`ActivePatternCache` (in/out).
        evolve: mu follows the dissipated energy (``mu`` and ``k`` are then updated in place before each
            increment); ``energy`` to ``wear_per_mu``: :meth:`FrictionEvolution.arguments` (unused otherwise).
        hold_block: Keep the working set's block ``W_AA`` from one local solve to the next while the set is the
            same (see :func:`_solve_local`; the same bits either way). False: gathered at every solve.
        float32_sweeps: The sweeps' incremental updates of x in float32 (the stopping criterion still on x
            recomputed in float64: answers within the tolerance of the float64 ones, not the same bits).
        warm_pattern: 2D: each local solve first tries its warm start's contact pattern as an exact linear solve
            (:func:`warm_pattern_solve`; finite sliding's loop, whose W changes with every pairing, so that no
            pattern can be cached per increment), ``counts[0]`` / ``counts[1]`` its accepted and rejected tries.

    Returns:
        (converged increments, local status of the first failure (1 if none), its error).
    """
    n = D.shape[0]
    m = G.shape[0]
    nc = mu.size
    q, q_abs, x, r, xs = np.empty(m), np.empty(m), np.empty(m), np.empty(m), np.empty(m)
    states = np.empty(nc, dtype=np.int8)
    row = np.empty(N_ROW - 2)
    normal_only, Wn, qn, rn, xn = _normal_rows(Wc, mu, dim)
    held = _nothing_held()   # the working set's block, held from one local solve to the next (Wc is fixed here)
    q_before = np.empty(m)   # the last solve's q, and whether x = W r + q_before (_solve_local)
    x_known = np.zeros(1, dtype=np.bool_)
    for j in range(n):
        if evolve:
            _friction_before(j, mu, k, energy, table_of, abscissae, values, lengths, wear_base, wear_per_mu,
                             active, factor_mu, lu_ok)
            if _all_zero(mu) != normal_only:
                normal_only, Wn, qn, rn, xn = _normal_rows(Wc, mu, dim)
        _rhs(g0, wear_gap, G, D[j], Q, S[j], y, dim, q_abs, q)
        if warm == 1:
            x_known[0] = False   # another start than the last answer, whose x is known
            for i in range(m):
                r[i] = r_warm[j, i]
        else:
            for i in range(m):   # the last answer itself (_finish wrote it to r_last): x stays known
                r[i] = r_last[i]
        its, err, status, held = _solve_local(Wc, Wn, normal_only, rho, mu, dim, q, r, x, tol, max_iter, refresh,
                                              active, j, pattern, lu, piv, lu_ok, counts, xs, qn, rn, xn, held,
                                              hold_block, float32_sweeps, warm_pattern, q_before, x_known)
        if status != 1:
            return j, status, err
        _finish(j, r, x, q, q_abs, y, mu, dim, tributary, abscissa, k, wear_gap, states, row, its, err, rows,
                r_warm, r_last, keep, out_r, out_x, out_y, out_wear, out_states, active, pattern, lu_ok)
        if evolve:
            _friction_after(r, x, dim, tributary, energy_scale, energy)
    return n, 1, 0.0


#: Outcome codes of :func:`run_force_increments` beyond the local solver's (0: max_iter, 2: non-finite values):
#: a trial obstacle displacement not finite, a force that saturates, one not bracketed or not reached by the root
#: finder, forces not reached after ``FORCE_SWEEPS`` sweeps over the controlled components (the messages are
#: :mod:`dolfinx_fretting.loading`'s, as the stepwise path raises them).
TRIAL_NOT_FINITE, SATURATED, NOT_BRACKETED, NOT_REACHED, SWEEPS_EXHAUSTED = 3, 4, 5, 6, 7


@numba.njit(cache=True)
def _force_trial(trial: np.ndarray, T: np.ndarray, A: np.ndarray, Dj: np.ndarray, F: np.ndarray, Wc: np.ndarray,
                 Wn: np.ndarray, normal_only: bool, rho: np.ndarray, mu: np.ndarray, dim: int, g0: np.ndarray,
                 wear_gap: np.ndarray, G: np.ndarray, Q: np.ndarray, Sj: np.ndarray, y: np.ndarray,
                 q_abs: np.ndarray, q: np.ndarray, r: np.ndarray, x: np.ndarray, tol: float, max_iter: int,
                 refresh: int, active: bool, j: int, pattern: np.ndarray, lu: np.ndarray, piv: np.ndarray,
                 lu_ok: np.ndarray, counts: np.ndarray, xs: np.ndarray, qn: np.ndarray, rn: np.ndarray,
                 xn: np.ndarray, tally: np.ndarray, held: tuple[np.ndarray, ...], hold_block: bool,
                 float32_sweeps: bool, warm_pattern: bool, q_before: np.ndarray, x_known: np.ndarray
                 ) -> tuple[int, float, int, tuple[np.ndarray, ...]]:
    """One trial of the load control: the local problem with the obstacle at ``trial`` (its components), warm
    started from ``r`` (the previous trial's forces, as the stepwise path), then ``F = A r`` (the total force along
    each component). ``tally``: (solves, sweeps) so far, in/out; ``held``, ``hold_block``, ``float32_sweeps``,
    ``q_before``, ``x_known``: as :func:`_solve_local` (``r`` and ``x`` go from trial to trial).
    Returns (the first non-finite component or -1, error, local status, what is held for the next solve)."""
    for c in range(trial.size):
        if not math.isfinite(trial[c]):
            return c, 0.0, 1, held
    for g in range(Dj.size):   # D = T d, component by component (as ContactZone.translations)
        v = 0.0
        for c in range(trial.size):
            v = v + trial[c] * T[g, c] if c > 0 else trial[c] * T[g, c]
        Dj[g] = v
    _rhs(g0, wear_gap, G, Dj, Q, Sj, y, dim, q_abs, q)
    its, err, status, held = _solve_local(Wc, Wn, normal_only, rho, mu, dim, q, r, x, tol, max_iter, refresh, active,
                                          j, pattern, lu, piv, lu_ok, counts, xs, qn, rn, xn, held, hold_block,
                                          float32_sweeps, warm_pattern, q_before, x_known)
    tally[0] += 1
    tally[1] += its
    for c in range(F.size):
        v = 0.0
        for i in range(r.size):
            v += A[c, i] * r[i]
        F[c] = v
    return -1, err, status, held


@numba.njit(cache=True, error_model="numpy")
def run_force_increments(Wc: np.ndarray, rho: np.ndarray, mu: np.ndarray, dim: int, g0: np.ndarray,
                         wear_gap: np.ndarray, G: np.ndarray, T: np.ndarray, A: np.ndarray, targets: np.ndarray,
                         controlled: np.ndarray, d: np.ndarray, stiffness: np.ndarray, force_tol: float,
                         max_eval: int, Q: np.ndarray, S: np.ndarray, tributary: np.ndarray, abscissa: np.ndarray,
                         y: np.ndarray, r_last: np.ndarray, r_warm: np.ndarray, k: np.ndarray, tol: float,
                         max_iter: int, refresh: int, keep: bool, out_r: np.ndarray, out_x: np.ndarray,
                         out_y: np.ndarray, out_wear: np.ndarray, out_states: np.ndarray, rows: np.ndarray,
                         out_d: np.ndarray, solves: np.ndarray, active: bool, pattern: np.ndarray, lu: np.ndarray,
                         piv: np.ndarray, lu_ok: np.ndarray, counts: np.ndarray, failure: np.ndarray, F: np.ndarray,
                         factor_mu: np.ndarray, evolve: bool, energy: np.ndarray, energy_scale: float,
                         table_of: np.ndarray, abscissae: np.ndarray, values: np.ndarray, lengths: np.ndarray,
                         wear_base: np.ndarray, wear_per_mu: np.ndarray, hold_block: bool,
                         float32_sweeps: bool, warm_pattern: bool) -> tuple[int, int, float]:
    """:func:`run_increments` with force-controlled obstacle components: each increment finds the obstacle
    displacement whose total contact force meets the targets, by the stepwise path's load control
    (``increments._local_with_control``: sweeps over the controlled components, each closed by
    :func:`~dolfinx_fretting.loading.find_displacement`'s iteration, the same tolerance ``force_tol`` times the
    largest target or first trial's force, every trial warm started from the previous one, the slope estimate
    ``stiffness`` updated after each root find), then commits it. The obstacle of the cycle's increment ``j`` is
    ``out_d[j]``.

    Args:
        T: (gdim, components) the obstacle translation per unit component (``translations`` of the unit vectors).
        A: (components, m) the total force along each component per contact force (``obstacle_forces``).
        targets: (n, components) the prescribed values (forces where ``controlled``, else displacements).
        d: (components,) the obstacle of the last converged increment (in/out).
        stiffness: (components,) the slope estimates of ``ContactOperators.stiffness`` (in/out).
        max_eval: The root finder's bound on trials per component.
        solves: (n,) out: local solves per increment.
        failure: (4,) out on failure: the component, then the numbers of the message (see the codes above).
        F: (components,) out: the total force of the last trial.
        Others: as :func:`run_increments` (no cycle warm start: the stepwise path's warm starts; ``evolve`` and
            the arrays after it: mu of the dissipated energy, updated before each increment).

    Returns:
        (converged increments, status of the first failure (1 if none: the local solver's, or a code above), the
        local error).
    """
    n = targets.shape[0]
    m = G.shape[0]
    nc = mu.size
    ncomp = d.size
    q, q_abs, x, r, xs = np.empty(m), np.empty(m), np.empty(m), np.empty(m), np.empty(m)
    states = np.empty(nc, dtype=np.int8)
    row = np.empty(N_ROW - 2)
    normal_only, Wn, qn, rn, xn = _normal_rows(Wc, mu, dim)
    Dj = np.empty(G.shape[1])
    trial = np.empty(ncomp)
    tally = np.zeros(2, dtype=np.int64)
    held = _nothing_held()   # the working set's block, held from one local solve to the next (Wc is fixed here)
    q_before = np.empty(m)   # the last trial's q, and whether x = W r + q_before (_solve_local)
    x_known = np.zeros(1, dtype=np.bool_)
    for i in range(m):
        r[i] = r_last[i]
    for j in range(n):
        if evolve:
            _friction_before(j, mu, k, energy, table_of, abscissae, values, lengths, wear_base, wear_per_mu,
                             active, factor_mu, lu_ok)
            if _all_zero(mu) != normal_only:
                normal_only, Wn, qn, rn, xn = _normal_rows(Wc, mu, dim)
        tally[0] = 0
        tally[1] = 0
        for c in range(ncomp):
            if not controlled[c]:
                d[c] = targets[j, c]
            trial[c] = d[c]
        bad, err, status, held = _force_trial(trial, T, A, Dj, F, Wc, Wn, normal_only, rho, mu, dim, g0, wear_gap, G,
                                              Q, S[j], y, q_abs, q, r, x, tol, max_iter, refresh, active, j, pattern,
                                              lu, piv, lu_ok, counts, xs, qn, rn, xn, tally, held, hold_block,
                                              float32_sweeps, warm_pattern, q_before, x_known)
        if bad >= 0:
            failure[0] = bad
            return j, TRIAL_NOT_FINITE, 0.0
        if status != 1:
            return j, status, err
        # Tolerance relative to the loads in play (as the stepwise path).
        scale = 1e-300
        for c in range(ncomp):
            if controlled[c]:
                scale = max(scale, abs(targets[j, c]))
            scale = max(scale, abs(F[c]))
        ftol = force_tol * scale
        reached = False
        for _sweep in range(FORCE_SWEEPS):
            reached = True
            for c in range(ncomp):
                if controlled[c] and not abs(F[c] - targets[j, c]) <= ftol:
                    reached = False
            if reached:
                break
            for kc in range(ncomp):
                if not controlled[kc]:
                    continue
                d_old, F_old = d[kc], F[kc]
                target = targets[j, kc]
                # find_displacement (loading.py), step by step: each force(v) is a trial with d[kc] = v.
                for c in range(ncomp):
                    trial[c] = d[c]
                a = b = fa = fb = 0.0
                found = False
                evals = 0
                while True:   # a block to break out of: the bracketing, then the Illinois regula falsi
                    trial[kc] = d[kc]
                    bad, err, status, held = _force_trial(trial, T, A, Dj, F, Wc, Wn, normal_only, rho, mu, dim, g0,
                                                          wear_gap, G, Q, S[j], y, q_abs, q, r, x, tol, max_iter,
                                                          refresh, active, j, pattern, lu, piv, lu_ok, counts, xs, qn,
                                                          rn, xn, tally, held, hold_block, float32_sweeps,
                                                          warm_pattern, q_before, x_known)
                    if bad >= 0 or status != 1:
                        break
                    f0 = F[kc] - target
                    evals = 1
                    if abs(f0) <= ftol:
                        b = d[kc]
                        found = True
                        break
                    step = -f0 / max(stiffness[kc], 1e-300)
                    a, fa = d[kc], f0
                    b = d[kc] + step
                    trial[kc] = b
                    bad, err, status, held = _force_trial(trial, T, A, Dj, F, Wc, Wn, normal_only, rho, mu, dim, g0,
                                                          wear_gap, G, Q, S[j], y, q_abs, q, r, x, tol, max_iter,
                                                          refresh, active, j, pattern, lu, piv, lu_ok, counts, xs, qn,
                                                          rn, xn, tally, held, hold_block, float32_sweeps,
                                                          warm_pattern, q_before, x_known)
                    if bad >= 0 or status != 1:
                        break
                    fb = F[kc] - target
                    evals += 1
                    flat_steps = 0
                    while fa * fb > 0:
                        flat = abs(fb - fa) <= ftol and abs(fb + target) > ftol
                        flat_steps = flat_steps + 1 if flat else 0
                        if flat_steps >= 5:
                            failure[0], failure[1], failure[2] = kc, target, fb + target
                            return j, SATURATED, 0.0
                        if evals >= max_eval:
                            failure[0], failure[1], failure[2], failure[3] = kc, target, f0 + target, fb + target
                            return j, NOT_BRACKETED, 0.0
                        step *= 2.0
                        a, fa = b, fb
                        b = b + step
                        trial[kc] = b
                        bad, err, status, held = _force_trial(trial, T, A, Dj, F, Wc, Wn, normal_only, rho, mu, dim,
                                                              g0, wear_gap, G, Q, S[j], y, q_abs, q, r, x, tol,
                                                              max_iter, refresh, active, j, pattern, lu, piv, lu_ok,
                                                              counts, xs, qn, rn, xn, tally, held, hold_block,
                                                              float32_sweeps, warm_pattern, q_before, x_known)
                        if bad >= 0 or status != 1:
                            break
                        fb = F[kc] - target
                        evals += 1
                    if bad >= 0 or status != 1:
                        break
                    if abs(fb) <= ftol:
                        found = True
                        break
                    while evals < max_eval:
                        c_new = b - fb * (b - a) / (fb - fa)
                        trial[kc] = c_new
                        bad, err, status, held = _force_trial(trial, T, A, Dj, F, Wc, Wn, normal_only, rho, mu, dim,
                                                              g0, wear_gap, G, Q, S[j], y, q_abs, q, r, x, tol,
                                                              max_iter, refresh, active, j, pattern, lu, piv, lu_ok,
                                                              counts, xs, qn, rn, xn, tally, held, hold_block,
                                                              float32_sweeps, warm_pattern, q_before, x_known)
                        if bad >= 0 or status != 1:
                            break
                        fc = F[kc] - target
                        evals += 1
                        if abs(fc) <= ftol:
                            b = c_new
                            found = True
                            break
                        if fc * fb < 0:
                            a, fa = b, fb
                        else:
                            fa = fa / 2.0   # the far end kept again: halve its value (Illinois)
                        b, fb = c_new, fc
                    break
                if bad >= 0:
                    failure[0] = bad
                    return j, TRIAL_NOT_FINITE, 0.0
                if status != 1:
                    return j, status, err
                if not found:
                    failure[0], failure[1], failure[2], failure[3] = kc, target, fb, ftol
                    return j, NOT_REACHED, 0.0
                d[kc] = b
                if d[kc] != d_old and F[kc] != F_old:
                    stiffness[kc] = abs((F[kc] - F_old) / (d[kc] - d_old))
        if not reached:
            failure[0], failure[1] = -1, ftol
            return j, SWEEPS_EXHAUSTED, 0.0
        for c in range(ncomp):
            out_d[j, c] = trial[c]
        solves[j] = tally[0]
        _finish(j, r, x, q, q_abs, y, mu, dim, tributary, abscissa, k, wear_gap, states, row, tally[1], err, rows,
                r_warm, r_last, keep, out_r, out_x, out_y, out_wear, out_states, active, pattern, lu_ok)
        if evolve:
            _friction_after(r, x, dim, tributary, energy_scale, energy)
    return n, 1, 0.0
