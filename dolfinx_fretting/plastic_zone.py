"""The plastic zone's algebra for the condensed Newton iteration (pure NumPy/numba: no mesh, no DOLFINx).

The consistent tangent of a J2 body differs from the elastic stiffness K only on the dofs P of the cells
where a point yields::

    K_T = K + E_P D E_P^T,   D = sum over yielded points of  w B^T (C_T - C_e) B   (p x p),

with B the strain-displacement matrix of a point, w its weight (quadrature weight x ``|det J|``) and E_P the
injection of P into all dofs. Given the entries Z = (K^-1)_XX of the elastic inverse on a set X of dofs
that contains P and the contact dofs (one MUMPS selected inverse, once), the Woodbury identity gives the
tangent's inverse and its Delassus matrix without a refactorisation::

    K_T^-1 = K^-1 - K^-1 E_P M E_P^T K^-1,        M = (I + D Z_PP)^-1 D,
    W_T    = H K_T^-1 H^T = W - G M G^T,          G = H K^-1 E_P = (H Z)[:, P].

Likewise the plastic part of the internal forces, g(u) = F_int(u) - K u = -sum w B^T (C_e eps_p), lives on
the dofs of the cells with plastic strain, so one Newton iteration of the whole body can run on the zone's
dofs X alone (:class:`~dolfinx_fretting.plasticity.ElastoplasticBody` does the DOLFINx side). The kernels
here work on the points of the zone, each with its (k, nd) matrix B, its weight and the positions in X of
its cell's dofs (-1 for a constrained dof, whose value is zero).

Tensors are Mandel vectors (see :mod:`dolfinx_fretting.materials`); ``comps`` are the k components the
forms use (2D plane strain: xx, yy, sqrt2 xy).
"""

from __future__ import annotations

import numba
import numpy as np
import scipy.linalg
import scipy.sparse

from .materials import radial_return_kernel

__all__ = ["LowRankTangent", "point_strains", "rows_axpy", "zone_update", "zone_tangent_matrix", "MAX_ZONE_DOFS",
           "ZONE_MARGIN"]

#: Largest plastic zone (dofs of X) kept condensed: Z = (K^-1)_XX is dense, ``|X|^2`` doubles, and its
#: selected inverse costs ~1.3 s at 2600 dofs here (benchmarks/results/plastic.md); past it the body
#: refactorises K_T (``ElastoplasticBody.max_zone_dofs``; ``sizes`` counts the zone's memory with it).
MAX_ZONE_DOFS = 6000
#: Layers of neighbour cells added around the cells that yield when the zone grows.
ZONE_MARGIN = 2


@numba.njit(cache=True)
def _zone_update(E, nu, sy0, H, B, w, dofpos, comps, uX, eps_p_old, p_old, eps, sigma, eps_p, p, dC, yielded, g):
    """Strains, return mapping (with C_T - C_e) and plastic forces at the zone's points (see zone_update)."""
    npt, k, nd = B.shape
    for i in range(npt):
        for a in range(6):
            eps[i, a] = 0.0
        for a in range(k):
            v = 0.0
            for j in range(nd):
                d = dofpos[i, j]
                if d >= 0:
                    v += B[i, a, j] * uX[d]
            eps[i, comps[a]] = v
    radial_return_kernel(E, nu, sy0, H, eps, eps_p_old, p_old, sigma, eps_p, p, dC, yielded, 2)
    # g = -sum w B^T (C_e eps_p)[comps]: sigma - C_e eps = -C_e eps_p exactly, without the cancellation of
    # subtracting two stresses; a point without plastic strain contributes exactly nothing.
    G = E / (2.0 * (1.0 + nu))
    lam = E * nu / ((1.0 + nu) * (1.0 - 2.0 * nu))
    t = np.empty(6)
    for d in range(g.size):
        g[d] = 0.0
    for i in range(npt):
        nonzero = False
        for a in range(6):
            if eps_p[i, a] != 0.0:
                nonzero = True
        if not nonzero:
            continue
        tr = eps_p[i, 0] + eps_p[i, 1] + eps_p[i, 2]
        for a in range(6):
            t[a] = 2.0 * G * eps_p[i, a]
        for a in range(3):
            t[a] += lam * tr
        for j in range(nd):
            d = dofpos[i, j]
            if d < 0:
                continue
            acc = 0.0
            for a in range(k):
                acc += B[i, a, j] * t[comps[a]]
            g[d] -= w[i] * acc


@numba.njit(cache=True)
def point_strains(B, dofs, u, comps, eps):
    """eps[i, comps] = B[i] @ u[dofs[i]] (the other Mandel components 0): the strain at points from their
    (k, nd) matrices and cell dofs (indices into ``u``)."""
    npt, k, nd = B.shape
    for i in range(npt):
        for a in range(6):
            eps[i, a] = 0.0
        for a in range(k):
            v = 0.0
            for j in range(nd):
                v += B[i, a, j] * u[dofs[i, j]]
            eps[i, comps[a]] = v


@numba.njit(cache=True)
def rows_axpy(y, Z, rows, coefficients):
    """y += sum_k coefficients[k] * Z[rows[k]] in place (no copy of the rows)."""
    m = y.size
    for k in range(rows.size):
        a = coefficients[k]
        r = rows[k]
        for j in range(m):
            y[j] += a * Z[r, j]


def zone_update(law, B: np.ndarray, w: np.ndarray, dofpos: np.ndarray, comps: np.ndarray, uX: np.ndarray,
                eps_p_old: np.ndarray, p_old: np.ndarray, out: dict) -> None:
    """Return mapping at the zone's points for the displacement ``uX`` on the dofs X.

    Args:
        law: :class:`~dolfinx_fretting.materials.J2Plasticity`.
        B: (n, k, nd) strain-displacement matrices of the points (form components).
        w: (n,) weights (quadrature weight x ``|det J|``).
        dofpos: (n, nd) positions in X of the dofs of each point's cell (-1: constrained, value 0).
        comps: (k,) Mandel components of the form components.
        uX: ``(|X|,)`` displacement on X.
        eps_p_old, p_old: (n, 6), (n,) committed plastic state of the points.
        out: Preallocated outputs, updated in place: ``eps``, ``sigma``, ``eps_p`` (n, 6), ``p`` (n,),
            ``dC`` (n, 6, 6): C_T - C_e (0 where elastic), ``yielded`` (n,) bool, ``g`` ``(|X|,)``: the
            plastic forces F_int - K u of these points.
    """
    _zone_update(float(law.E), float(law.nu), float(law.sigma_y0), float(law.H), B, w, dofpos, comps, uX,
                 eps_p_old, p_old, out["eps"], out["sigma"], out["eps_p"], out["p"], out["dC"], out["yielded"],
                 out["g"])


@numba.njit(cache=True)
def _zone_tangent(B, w, dofpos, comps, dC, yielded, ppos, D):
    npt, k, nd = B.shape
    tmp = np.empty((k, nd))
    for i in range(npt):
        if not yielded[i]:
            continue
        for a in range(k):
            for j in range(nd):
                v = 0.0
                for b in range(k):
                    v += dC[i, comps[a], comps[b]] * B[i, b, j]
                tmp[a, j] = w[i] * v
        for j1 in range(nd):
            d1 = dofpos[i, j1]
            if d1 < 0:
                continue
            p1 = ppos[d1]
            for j2 in range(nd):
                d2 = dofpos[i, j2]
                if d2 < 0:
                    continue
                v = 0.0
                for a in range(k):
                    v += B[i, a, j1] * tmp[a, j2]
                D[p1, ppos[d2]] += v


def zone_tangent_matrix(B: np.ndarray, w: np.ndarray, dofpos: np.ndarray, comps: np.ndarray, dC: np.ndarray,
                        yielded: np.ndarray, P: np.ndarray, nX: int) -> np.ndarray:
    """D = sum over the yielded points of w B^T (C_T - C_e) B on the dofs P (positions in X), dense (p, p).

    Args:
        B, w, dofpos, comps: As in :func:`zone_update`.
        dC: (n, 6, 6) C_T - C_e of the points.
        yielded: (n,) the points that contribute.
        P: (p,) sorted positions in X; must contain every unconstrained dof of a yielded point's cell.
        nX: ``|X|``.
    """
    ppos = np.full(nX, -1, dtype=np.int64)
    ppos[P] = np.arange(P.size)
    D = np.zeros((P.size, P.size))
    _zone_tangent(B, w, dofpos, comps, dC, yielded, ppos, D)
    return D


@numba.njit(cache=True)
def _sparse_times_dense_plus_identity(indptr, indices, data, Zpp):
    """I + D Zpp for a CSR D (a few dozen entries a row) and a dense Zpp: row axpys, O(nnz p)."""
    p = Zpp.shape[0]
    out = np.zeros((p, p))
    for i in range(p):
        out[i, i] = 1.0
        for k in range(indptr[i], indptr[i + 1]):
            a = data[k]
            row = Zpp[indices[k]]
            for j in range(p):
                out[i, j] += a * row[j]
    return out


class LowRankTangent:
    """The consistent tangent K_T = K + E_P D E_P^T as a correction of the elastic inverse (Woodbury).

    Args:
        P: (p,) positions in X of the dofs where K_T differs from K.
        D: (p, p) the difference (symmetric).
        Z: ``(|X|, |X|)`` entries of K^-1 on X.
        HZ: ``(m, |X|)`` = H[:, X] Z, i.e. H K^-1 on the columns X.
        W: (m, m) elastic Delassus matrix H K^-1 H^T.

    Attributes:
        P: The dofs (positions in X).
        G: (m, p) = H K^-1 E_P.
        W: (m, m) Delassus matrix of K_T (symmetrised).
    """

    def __init__(self, P: np.ndarray, D: np.ndarray, Z: np.ndarray, HZ: np.ndarray, W: np.ndarray,
                 ZH: np.ndarray | None = None):
        self.P = P
        self.D = scipy.sparse.csr_matrix(D)  # element-sparse: a few dozen entries a row
        self.Z_P = Z[P]  # rows P of Z = its columns (Z is symmetric): K^-1 E_P on X
        A = np.ascontiguousarray(self.Z_P[:, P])
        A = _sparse_times_dense_plus_identity(self.D.indptr, self.D.indices, self.D.data, A)
        self._lu = scipy.linalg.lu_factor(A, overwrite_a=True, check_finite=False)
        self.G = HZ[:, P] if ZH is None else ZH[P].T  # ZH = HZ^T: contiguous rows
        WT = W - self.G @ self.apply(self.G.T)
        self.W = 0.5 * (WT + WT.T)

    def apply(self, v: np.ndarray) -> np.ndarray:
        """M v = (I + D Z_PP)^-1 D v for a vector or the columns of a matrix on P."""
        return scipy.linalg.lu_solve(self._lu, self.D @ v, check_finite=False)
