"""The algebra of the condensed elastic-plastic Newton iteration (plastic_zone, PlasticState.point_matrices)
against independent references: dense linear algebra, and DOLFINx's own assembly of the same forms."""

import numpy as np
import pytest
from mpi4py import MPI  # before dolfinx: on the DOLFINx wheel it loads the MPI library DOLFINx needs

from dolfinx import fem, mesh  # noqa: E402

from dolfinx_fretting import _dolfinx as dfx
from dolfinx_fretting.materials import J2Plasticity, elastic_stiffness
from dolfinx_fretting.plastic_zone import LowRankTangent, zone_tangent_matrix, zone_update
from dolfinx_fretting.plasticity import PlasticState

E, NU = 115e3, 0.342


def test_low_rank_tangent_is_the_updated_inverse():
    """K_T = K + E_P D E_P^T: the Woodbury form from Z = (K^-1)_XX alone gives W_T = H K_T^-1 H^T and
    K_T^-1 on X as dense inverses do. Random SPD K (n = 80, condition ~1e3) and a negative semi-definite D
    of rank 5 that keeps K_T SPD (as a hardening J2 tangent does): both sides are O(1) and computed to
    ~1e-13; 1e-10 relative leaves margin for the conditioning and catches any wrong term (O(1))."""
    rng = np.random.default_rng(5)
    n, m = 80, 12
    A = rng.standard_normal((n, n))
    K = A @ A.T + 0.05 * n * np.eye(n)
    Kinv = np.linalg.inv(K)
    S = np.sort(rng.choice(n, 10, replace=False))            # dofs touched by H
    P_dofs = np.sort(rng.choice(np.setdiff1d(np.arange(n), S), 15, replace=False))
    X = np.union1d(np.union1d(S, P_dofs), rng.choice(n, 10, replace=False))
    H = np.zeros((m, n))
    H[:, S] = rng.standard_normal((m, S.size))
    L = rng.standard_normal((P_dofs.size, 5))
    Kpp = K[np.ix_(P_dofs, P_dofs)]
    # D = -L L^T scaled so that K + E_P D E_P^T stays positive definite.
    D = -0.5 * L @ L.T * np.linalg.eigvalsh(Kpp).min() / np.linalg.eigvalsh(L @ L.T).max()
    KT = K.copy()
    KT[np.ix_(P_dofs, P_dofs)] += D
    assert np.linalg.eigvalsh(KT).min() > 0
    Z = Kinv[np.ix_(X, X)]
    HZ = H[:, X] @ Z
    P = np.searchsorted(X, P_dofs)
    T = LowRankTangent(P, D, Z, HZ, H @ Kinv @ H.T)
    W_ref = H @ np.linalg.solve(KT, H.T)
    assert np.abs(T.W - W_ref).max() <= 1e-10 * np.abs(W_ref).max()
    # K_T^-1 b on X from K^-1 b on X: y - Z[:, P] M y_P.
    b = rng.standard_normal(n)
    y = Kinv @ b
    xT = y[X] - T.Z_P.T @ T.apply(y[X][P])
    ref = np.linalg.solve(KT, b)[X]
    assert np.abs(xT - ref).max() <= 1e-10 * np.abs(ref).max()


def _state(cell_type, degree, law, family="Lagrange"):
    msh = mesh.create_unit_square(MPI.COMM_SELF, 3, 4, cell_type)
    x = msh.geometry.x  # a distorted mesh: non-constant Jacobians
    x[:, 0] += 0.08 * np.sin(3.0 * x[:, 1])
    x[:, 1] += 0.05 * np.cos(2.0 * x[:, 0]) * x[:, 0]
    V = dfx.vector_space(msh, degree, family)
    return PlasticState(V, law, quadrature_degree=2 if degree == 1 else 2 * degree)


def _cell_dofs(state):
    V = state.V
    nodes = dfx.cell_dofmap(V)[: state.cells.size]
    return (2 * nodes[:, :, None] + np.arange(2)).reshape(nodes.shape[0], -1)


@pytest.mark.parametrize("cell_type, degree", [(mesh.CellType.quadrilateral, 1), (mesh.CellType.triangle, 2),
                                               (mesh.CellType.triangle, 3), (mesh.CellType.quadrilateral, 3)])
def test_point_matrices_reproduce_dolfinx(cell_type, degree):
    """B u_cell is the strain DOLFINx evaluates, sum w B^T C_e B is the stiffness DOLFINx assembles, and the
    zone kernel's plastic forces are DOLFINx's F_int(u) - K u. All three are the same quadrature sums in
    another order: agreement to ~1e-13 relative; 1e-11 is asserted (a wrong weight, node order or factor
    sqrt2 is an O(1) error). Degree 3 has two dofs on an edge, whose order DOLFINx permutes per cell: the
    basis gradients come from DOLFINx's own tabulation, so they follow it."""
    law = J2Plasticity(E, NU, 1e12, 0.0)  # never yields: sigma = C_e (eps - eps_p) at every point
    st = _state(cell_type, degree, law)
    rng = np.random.default_rng(2)
    u = fem.Function(st.V)
    u.x.array[:] = rng.uniform(-1e-3, 1e-3, u.x.array.size)
    B, w = st.point_matrices(st.cells)
    dofs = _cell_dofs(st)
    cell_of = np.repeat(np.arange(st.cells.size), st.nq)
    eps = np.einsum("pkd,pd->pk", B, u.x.array[dofs[cell_of]])
    ref = st.strain(u)[:, st.comps]
    assert np.abs(eps - ref).max() <= 1e-11 * np.abs(ref).max()
    # Stiffness: the tangent form at an elastic state is K.
    st.update(fem.Function(st.V))
    Kd = st.create_tangent([]).convert("dense").getDenseArray()
    comps = np.asarray(st.comps)
    Ce = elastic_stiffness(E, NU)[np.ix_(comps, comps)]
    K = np.zeros_like(Kd)
    for i, c in enumerate(cell_of):
        np.add.at(K, np.ix_(dofs[c], dofs[c]), w[i] * B[i].T @ Ce @ B[i])
    assert np.abs(K - Kd).max() <= 1e-11 * np.abs(Kd).max()
    # Plastic forces g = F_int(u) - K u = -sum w B^T (C_e eps_p) of a committed plastic strain.
    st.eps_p = np.zeros((st.n_points, 6))
    st.eps_p[:, [0, 1, 2, 5]] = rng.normal(scale=2e-3, size=(st.n_points, 4))
    st.eps_p[:, :3] -= st.eps_p[:, :3].mean(axis=1, keepdims=True)
    st.update(u, tangent=False)
    b = dfx.vector_for_form(st.residual_form)
    st.assemble_residual(b, [])
    g_ref = b.getArray() - Kd @ u.x.array
    n = st.n_points
    out = {"eps": np.zeros((n, 6)), "sigma": np.zeros((n, 6)), "eps_p": np.zeros((n, 6)), "p": np.zeros(n),
           "dC": np.zeros((n, 6, 6)), "yielded": np.zeros(n, bool), "g": np.zeros(u.x.array.size)}
    zone_update(law, np.ascontiguousarray(B), w, dofs[cell_of].astype(np.int64), comps.astype(np.int64),
                u.x.array.copy(), st.eps_p, st.p, out)
    assert not out["yielded"].any()
    assert np.abs(out["g"] - g_ref).max() <= 1e-11 * np.abs(g_ref).max()
    assert np.abs(out["sigma"] - st.trial_sigma).max() <= 1e-11 * np.abs(st.trial_sigma).max()


def test_tangent_matrix_is_dolfinx_tangent_minus_stiffness():
    """D from the zone kernel (sum over the yielded points of w B^T (C_T - C_e) B) is K_T - K as DOLFINx
    assembles both, on the dofs of the yielded cells (1e-11 relative, as above)."""
    law = J2Plasticity(E, NU, 300.0, 5e3)
    st = _state(mesh.CellType.quadrilateral, 1, law)
    u = fem.Function(st.V)
    st.update(u)
    K = st.create_tangent([]).convert("dense").getDenseArray()
    # A bump at a corner: strains ~1e-2 there (yield), ~0 far from it.
    u.interpolate(lambda x: np.stack([4e-3 * np.exp(-(x[0] ** 2 + x[1] ** 2) / 0.1), 0.0 * x[1]]))
    st.update(u)
    KT = st.create_tangent([]).convert("dense").getDenseArray()
    B, w = st.point_matrices(st.cells)
    dofs = _cell_dofs(st)
    cell_of = np.repeat(np.arange(st.cells.size), st.nq)
    n = st.n_points
    out = {"eps": np.zeros((n, 6)), "sigma": np.zeros((n, 6)), "eps_p": np.zeros((n, 6)), "p": np.zeros(n),
           "dC": np.zeros((n, 6, 6)), "yielded": np.zeros(n, bool), "g": np.zeros(u.x.array.size)}
    comps = np.asarray(st.comps, dtype=np.int64)
    dofpos = dofs[cell_of].astype(np.int64)
    zone_update(law, np.ascontiguousarray(B), w, dofpos, comps, u.x.array.copy(), st.eps_p, st.p, out)
    assert np.array_equal(out["yielded"], st.yielded) and 0 < out["yielded"].sum() < n
    P = np.unique(dofpos[out["yielded"]])
    D = zone_tangent_matrix(np.ascontiguousarray(B), w, dofpos, comps, out["dC"], out["yielded"], P, u.x.array.size)
    diff = KT - K
    assert np.abs(diff[np.ix_(P, P)] - D).max() <= 1e-11 * np.abs(K).max()
    rest = np.setdiff1d(np.arange(K.shape[0]), P)
    assert np.abs(diff[rest]).max() <= 1e-11 * np.abs(K).max()  # K_T = K off the yielded cells' dofs


def test_point_matrices_refuse_a_discontinuous_space():
    """The points' strains come from a continuous Lagrange basis: another element is refused by name (the
    condensed Newton then refactorises instead, see plasticity.condensation_unavailable)."""
    from dolfinx_fretting.plasticity import condensation_unavailable

    law = J2Plasticity(E, NU, 300.0, 5e3)
    st = _state(mesh.CellType.quadrilateral, 1, law, family="DG")
    with pytest.raises(ValueError, match="point_matrices: the displacement space's element is 'D"):
        st.point_matrices(st.cells)
    assert "continuous Lagrange" in condensation_unavailable(law, st.V)
    assert condensation_unavailable(law, _state(mesh.CellType.quadrilateral, 1, law).V) is None
