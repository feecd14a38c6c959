"""The Delassus matrix W = H K^-1 H^T: the MUMPS routes against an independent SciPy solve.

Reference: K is copied out of PETSc into SciPy and factorised by SuperLU (a different direct solver),
and W_ref = H K^-1 H^T is formed from its solves. W must be symmetric positive definite (K is SPD once the
fixed face removes the rigid modes, and H has full row rank: distinct nodes, orthonormal frames).
"""

from dataclasses import replace

import numpy as np
import pytest
import scipy.sparse as sp
import scipy.sparse.linalg as spla
from mpi4py import MPI

from dolfinx_fretting import compliance, delassus_routes
from dolfinx_fretting.compliance import DelassusOperator, check_no_constrained_dofs
from dolfinx_fretting.delassus_routes import auto_route
from dolfinx_fretting.scenes import load_scene
from dolfinx_fretting.simulation import ContactModel

from support.sphere import sphere_model

serial_only = pytest.mark.skipif(MPI.COMM_WORLD.size > 1, reason="SciPy reference needs the whole K")


@pytest.fixture(scope="module", params=["half_cylinder", "rectangle"])
def model(request):
    if request.param == "half_cylinder":
        scene = load_scene("hertz", ["geometry.contact_mesh_size=0.02"])
    else:
        scene = load_scene({"geometry": {"kind": "rectangle", "width": 10.0, "height": 4.0, "nx": 20, "ny": 8},
                            "contact": {"surface": "bottom"}, "loading": {"normal_displacement": 1e-4}})
    m = ContactModel(scene, MPI.COMM_WORLD)
    yield m
    m.problem.destroy()


def _scipy_K(K) -> sp.csr_matrix:
    ai, aj, av = K.getValuesCSR()
    n = K.getSize()[0]
    return sp.csr_matrix((av, aj, ai), shape=(n, n))


@serial_only
def test_routes_match_independent_solve(model):
    H = model.contact.H
    Kd = _scipy_K(model.problem.operators.K).tocsc()
    Y = spla.splu(Kd).solve(H.T.toarray())
    W_ref = H @ Y
    scale = np.abs(W_ref).max()
    for route in ("columns", "block", "selected_inverse", "owned", "schur"):
        W = model.problem.operators.delassus.build(H, method=route)
        # Two direct solvers on a K with condition number ~1e5-1e7: agreement to ~1e-10 of max|W|.
        assert np.abs(W - W_ref).max() <= 1e-9 * scale, route
    # The model's W (route "auto") is the same matrix.
    assert np.abs(model.W - W_ref).max() <= 1e-9 * scale


def test_W_symmetric_positive_definite(model):
    W = model.W
    # build() symmetrises; the raw asymmetry of the route is recorded and must be at rounding level.
    assert np.array_equal(W, W.T)
    assert model.problem.operators.delassus.stats["asymmetry"] < 1e-10
    eig = np.linalg.eigvalsh(W)
    assert eig.min() > 0, eig.min()
    # Finite conditioning (compliances of distinct nodes): well away from numerical singularity.
    assert eig.max() / eig.min() < 1e10


def test_contact_response_reproduces_W(model):
    """u = K^-1 H^T r then H u = W r: the field solve and W agree (same factor, same H)."""
    H = model.contact.H
    rng = np.random.default_rng(0)
    r = rng.standard_normal(H.shape[0])
    u = model.problem.displacement(replace(model.problem.initial_state(), forces=r))
    imap = model.problem.V.dofmap.index_map
    bs = model.problem.V.dofmap.index_map_bs
    n_owned = imap.size_local * bs
    rstart = imap.local_range[0] * bs
    full = np.zeros(H.shape[1])
    full[rstart:rstart + n_owned] = u.x.array[:n_owned]
    full = model.comm.allreduce(full, op=MPI.SUM)
    Wr = model.W @ r
    assert np.abs(H @ full - Wr).max() <= 1e-9 * np.abs(Wr).max()


def test_constrained_dofs_are_rejected():
    H = sp.csr_matrix(([1.0, 1.0], ([0, 1], [3, 8])), shape=(2, 10))
    check_no_constrained_dofs(H, np.array([0, 1, 2]))
    with pytest.raises(ValueError, match=r"Dirichlet-constrained dof.*global dofs 8"):
        check_no_constrained_dofs(H, np.array([8, 9]))


def test_bad_method_and_missing_factor(model):
    with pytest.raises(ValueError, match="unknown Delassus method 'lu'"):
        DelassusOperator(model.problem.operators.K, method="lu")
    op = DelassusOperator(model.problem.operators.K)
    with pytest.raises(RuntimeError, match="not factorised"):
        op.build(model.contact.H)


def test_refactorize_follows_new_values(model):
    """After K's values change (same pattern), refactorize() makes solves use the new K: x(2K) = x(K)/2."""
    p = model.problem
    op = DelassusOperator(p.operators.K, method="columns")
    op.factorize()
    b, x1 = p.operators.K.createVecs()
    x2 = b.duplicate()
    b.setRandom()
    fem_bc_dofs = np.flatnonzero(np.isclose(p.operators.K.getDiagonal().getArray(), 1.0))
    op.solve(b, x1)
    p.operators.K.scale(2.0)
    try:
        op.refactorize()
        op.solve(b, x2)
        free = np.setdiff1d(np.arange(x1.getLocalSize()), fem_bc_dofs)
        # Dirichlet rows scale too (their diagonal 1 becomes 2); compare the free dofs to rounding.
        assert np.allclose(x2.getArray()[free], 0.5 * x1.getArray()[free], rtol=1e-10, atol=1e-14)
        assert op.stats["refactorizations"] == 1
    finally:
        p.operators.K.scale(0.5)
        op.destroy()
        for v in (b, x1, x2):
            v.destroy()


@serial_only
def test_schur_route_reuses_its_factor_and_follows_refactorize(model):
    """The "schur" route's own factorisation: freed after each build while K has never been refactorised (an
    elastic body builds W once per H: the factor, 1.2-2.9x K's, is not held through the cycles); kept from K's
    first refactorisation on and refreshed numerically after K's values change: W(2K) = W(K)/2 to rounding (the
    factor is refactorised, not rebuilt)."""
    p = model.problem
    H = model.contact.H
    op = DelassusOperator(p.operators.K, method="schur")
    op.factorize()
    doubled = False
    try:
        W1 = op.build(H)
        assert op._schur is None  # freed: nothing would reuse it
        assert op.stats["schur_size"] == H.shape[0]  # the Schur complement is W's own size
        assert np.abs(op.build(H) - W1).max() == 0.0  # made anew: the same bits
        p.operators.K.scale(2.0)
        doubled = True
        op.refactorize()
        W2 = op.build(H)
        own = op._schur
        assert own is not None and own.stats["factorizations"] == 1 and own.stats["refactorizations"] == 0
        # Two factorisations of the same K up to a factor 2: agreement to rounding of max|W|.
        assert np.abs(W2 - 0.5 * W1).max() <= 1e-12 * np.abs(W1).max()
        assert np.abs(op.build(H) - W2).max() == 0.0 and op._schur is own  # kept and reused, not refactorised
        p.operators.K.scale(0.5)
        doubled = False
        op.refactorize()
        W3 = op.build(H)
        assert op._schur is own and own.stats["refactorizations"] == 1  # refreshed numerically
        assert np.abs(W3 - W1).max() <= 1e-12 * np.abs(W1).max()
    finally:
        if doubled:
            p.operators.K.scale(0.5)
        op.destroy()


@serial_only
def test_schur_route_on_two_bodies_in_3d(monkeypatch):
    """Two bodies in 3D (sphere on an identical flat, half model: a/h = 2, extent 4, 6 x 11 contacts): each row of
    H touches the dofs of both surfaces' nodes, so the Schur complement of [[K, H^T], [H, 0]] on H's rows is
    -W itself. W by the Schur route, by the selected inverse and by SciPy's SuperLU agree; ``auto`` takes the
    Schur route from AUTO_SCHUR_ROWS rows of H up on a K of at most AUTO_SCHUR_DOFS_PER_ROW dofs per row, else the
    selected inverse."""
    _, problem, *_ = sphere_model(2, 4.0, 1.6, flat=True, mu=0.5)
    try:
        d, H = problem.operators.delassus, problem.contact.H_free
        assert np.unique(H.indices).size > H.shape[0]  # several dofs per row: not a selection of dofs
        Kd = _scipy_K(problem.operators.K).tocsc()
        W_ref = H @ spla.splu(Kd).solve(H.T.toarray())
        scale = np.abs(W_ref).max()
        W_schur = d.build(H, method="schur")
        assert d.stats["schur_size"] == H.shape[0]
        # Two direct solvers (MUMPS, SuperLU) on a K of condition ~1e6: 1e-10 of max|W| (measured 1e-15).
        assert np.abs(W_schur - W_ref).max() <= 1e-10 * scale
        W_si = d.build(H, method="selected_inverse")
        assert np.abs(W_schur - W_si).max() <= 1e-10 * scale
        assert d.method == "auto"  # serially "auto" stays, resolved for each H
        dofs = problem.operators.K.getSize()[0]
        monkeypatch.setattr(delassus_routes, "AUTO_SCHUR_ROWS", H.shape[0])
        monkeypatch.setattr(delassus_routes, "AUTO_SCHUR_DOFS_PER_ROW", dofs / H.shape[0])
        d.build(H)
        assert d.stats["last_build_route"] == "schur"
        monkeypatch.setattr(delassus_routes, "AUTO_SCHUR_ROWS", H.shape[0] + 1)
        d.build(H)
        assert d.stats["last_build_route"] == "selected_inverse"  # too few rows
        monkeypatch.setattr(delassus_routes, "AUTO_SCHUR_ROWS", H.shape[0])
        monkeypatch.setattr(delassus_routes, "AUTO_SCHUR_DOFS_PER_ROW", 0.99 * dofs / H.shape[0])
        d.build(H)
        assert d.stats["last_build_route"] == "selected_inverse"  # too many dofs per row
        # The size rule says Schur, but its second factor (3x K's INFOG(22)) would not fit: the selected inverse.
        monkeypatch.setattr(delassus_routes, "AUTO_SCHUR_DOFS_PER_ROW", dofs / H.shape[0])
        need = delassus_routes.SCHUR_FACTOR_RATIO * d.stats["mumps_memory_mb"] * 2**20
        monkeypatch.setattr(compliance, "available_memory", lambda: (int(0.99 * need), "test"))
        d.build(H)
        assert d.stats["last_build_route"] == "selected_inverse" and d.stats["auto_schur_skipped_for_memory"]
        monkeypatch.setattr(compliance, "available_memory", lambda: (int(1.01 * need), "test"))
        d.build(H)
        assert d.stats["last_build_route"] == "schur" and not d.stats["auto_schur_skipped_for_memory"]
    finally:
        problem.destroy()


def test_auto_route():
    """``auto``: the Schur route from AUTO_SCHUR_ROWS rows on a K of at most AUTO_SCHUR_DOFS_PER_ROW dofs per row, else
    the selected inverse (serial); the owned route under MPI at any size (the Schur route is serial only)."""
    rows, per_row = delassus_routes.AUTO_SCHUR_ROWS, delassus_routes.AUTO_SCHUR_DOFS_PER_ROW
    assert auto_route(1, rows - 1, per_row * rows) == "selected_inverse"
    assert auto_route(1, rows, per_row * rows) == "schur"
    assert auto_route(1, rows, per_row * rows + 1) == "selected_inverse"
    assert auto_route(2, 10 * rows, rows) == "owned" and auto_route(3, 1, 1) == "owned"
    # where the Schur route's second factor does not fit in memory: the selected inverse (serial), as before (MPI)
    assert auto_route(1, rows, per_row * rows, schur_fits=False) == "selected_inverse"
    assert auto_route(2, 10 * rows, rows, schur_fits=False) == "owned"
