"""DOLFINx glue of J2 plasticity: quadrature-point state, residual, consistent tangent, commit and rollback.

The constitutive update itself is :func:`dolfinx_fretting.materials.return_mapping` (numba, on arrays);
this module only moves data between DOLFINx and it:

1. the total strain of the current displacement is evaluated at the quadrature points with a
   ``fem.Expression`` (DOLFINx 0.5.2 cannot interpolate into quadrature spaces; 0.11 uses the same path);
2. the return mapping runs from the *committed* state (plastic strain, cumulative plastic strain) and
   writes the trial stress and consistent tangent into quadrature functions;
3. the residual ``F(u) = int sigma : eps(v) dx - f_ext`` and the tangent ``int eps(du) : C : eps(v) dx``
   are assembled with the same quadrature rule (forms compiled once);
4. :meth:`PlasticState.commit` copies the trial state into history only after an increment converged;
   nothing needs undoing after a failed or cut increment.

Tensors are Mandel vectors ``[xx, yy, zz, sqrt2 yz, sqrt2 xz, sqrt2 xy]``; in 2D (plane strain) the
strain has ``eps_zz = eps_yz = eps_xz = 0`` and the forms use the in-plane part ``[xx, yy, sqrt2 xy]``,
while the out-of-plane stress ``sigma_zz`` is kept in the state (it enters von Mises).
"""

from __future__ import annotations

import math

import numpy as np
import ufl
from petsc4py import PETSc

from . import _dolfinx as dfx
from ._dolfinx import fem
from .materials import J2Plasticity, return_mapping

__all__ = ["PlasticState", "mandel_strain"]

_SQ2 = math.sqrt(2.0)


def _in_plane(gdim: int) -> list[int]:
    """Mandel components used by the forms: in 2D (xx, yy, sqrt2 xy); in 3D all six."""
    return [0, 1, 5] if gdim == 2 else [0, 1, 2, 3, 4, 5]


def mandel_strain(u, gdim: int):
    """UFL Mandel vector of the small strain of ``u`` restricted to the form components."""
    e = ufl.sym(ufl.grad(u))
    if gdim == 2:
        return ufl.as_vector([e[0, 0], e[1, 1], _SQ2 * e[0, 1]])
    return ufl.as_vector([e[0, 0], e[1, 1], e[2, 2], _SQ2 * e[1, 2], _SQ2 * e[0, 2], _SQ2 * e[0, 1]])


class PlasticState:
    """Quadrature-point state of a J2 body and the forms that use it. Collective to build.

    Args:
        V: Displacement space (vector Lagrange).
        law: The material.
        quadrature_degree: Degree of the quadrature rule (2: 2 x 2 Gauss on quadrilaterals).

    Attributes:
        sigma, eps_p, p: Committed state per quadrature point (numpy, (n, 6), (n, 6), (n,)), owned cells.
        trial_*: State of the last :meth:`update` (becomes the committed one at :meth:`commit`).
        yielded: Points that yielded in the last update.
    """

    def __init__(self, V: fem.FunctionSpace, law: J2Plasticity, quadrature_degree: int = 2,
                 elastic_cells: np.ndarray | None = None):
        import basix

        self.V = V
        self.law = law
        msh = V.mesh
        self.mesh = msh
        self.gdim = gdim = msh.geometry.dim
        self.comps = _in_plane(gdim)
        k = len(self.comps)
        points, _ = basix.make_quadrature(dfx.basix_cell(msh), quadrature_degree)
        self.nq = points.shape[0]
        tdim = msh.topology.dim
        self.cells = np.arange(msh.topology.index_map(tdim).size_local, dtype=np.int32)
        n = self.cells.size * self.nq
        self.n_points = n
        # Cells of a body that stays elastic (two bodies, one of them plastic): their points use the same
        # elastic constants and a yield stress that is never reached.
        self.elastic_points = np.zeros(n, dtype=bool)
        if elastic_cells is not None and len(elastic_cells):
            in_elastic = np.isin(self.cells, elastic_cells)
            self.elastic_points = np.repeat(in_elastic, self.nq)
        self._elastic_law = J2Plasticity(law.E, law.nu, np.inf, 0.0)

        md = {"quadrature_degree": quadrature_degree, "quadrature_scheme": "default"}
        self.dx = ufl.dx(domain=msh, metadata=md)
        S = dfx.quadrature_space(msh, quadrature_degree, (k,))
        T = dfx.quadrature_space(msh, quadrature_degree, (k, k))
        self._stress = fem.Function(S)      # trial stress, form components
        self._tangent = fem.Function(T)     # consistent tangent, form components
        # Quadrature dofs of the owned cells, in (cell, point) order: where point j of cell c lives.
        self._blocks = dfx.cell_dofmap(S)[self.cells].ravel()

        u_, v = ufl.TrialFunction(V), ufl.TestFunction(V)
        self._u = fem.Function(V)
        self._strain_expr = dfx.expression(mandel_strain(self._u, gdim), points)
        self.residual_form = fem.form(ufl.inner(self._stress, mandel_strain(v, gdim)) * self.dx)
        self.tangent_form = fem.form(ufl.inner(ufl.dot(self._tangent, mandel_strain(u_, gdim)),
                                               mandel_strain(v, gdim)) * self.dx)

        self.sigma = np.zeros((n, 6))
        self.eps_p = np.zeros((n, 6))
        self.p = np.zeros(n)
        self.trial_sigma = self.sigma.copy()
        self.trial_eps_p = self.eps_p.copy()
        self.trial_p = self.p.copy()
        self.yielded = np.zeros(n, dtype=bool)
        self.update_count = 0

    # ------------------------------------------------------------------------------------------------
    def strain(self, u: fem.Function) -> np.ndarray:
        """Total strain (n, 6) Mandel at the quadrature points of the owned cells."""
        self._u.x.array[:] = u.x.array
        vals = dfx.eval_expression(self._strain_expr, self.mesh, self.cells).reshape(-1, len(self.comps))
        eps = np.zeros((vals.shape[0], 6))
        eps[:, self.comps] = vals
        return eps

    def update(self, u: fem.Function) -> None:
        """Return mapping from the committed state at the strain of ``u``; fills the stress and tangent
        functions used by the forms (collective only through the ghost update)."""
        eps = self.strain(u)
        # The law's own update (the constitutive hook of problem.Plasticity; J2Plasticity.update is the radial
        # return); points of a body that stays elastic use a J2 law that never yields.
        sigma, eps_p, p, C, yielded = self.law.update(eps, self.eps_p, self.p)
        if self.elastic_points.any():
            e = self.elastic_points
            sigma[e], eps_p[e], p[e], C[e], yielded[e] = return_mapping(self._elastic_law, eps[e], self.eps_p[e],
                                                                        self.p[e], tangent=True)
        self.trial_sigma, self.trial_eps_p, self.trial_p, self.yielded = sigma, eps_p, p, yielded
        k = len(self.comps)
        stress = self._stress.x.array.reshape(-1, k)
        stress[self._blocks] = sigma[:, self.comps]
        tangent = self._tangent.x.array.reshape(-1, k * k)
        tangent[self._blocks] = C[:, self.comps][:, :, self.comps].reshape(-1, k * k)
        self._stress.x.scatter_forward()
        self._tangent.x.scatter_forward()
        self.update_count += 1

    def commit(self) -> None:
        """Make the last update the history (call only after a converged increment)."""
        self.sigma, self.eps_p, self.p = self.trial_sigma.copy(), self.trial_eps_p.copy(), self.trial_p.copy()

    def assemble_residual(self, b: PETSc.Vec, bcs: list) -> None:
        """b <- internal forces of the last update (Dirichlet rows zeroed). Collective."""
        with b.localForm() as loc:
            loc.set(0.0)
        fem.petsc.assemble_vector(b, self.residual_form)
        b.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
        dfx.set_bc(b, bcs, scale=0.0)

    def assemble_tangent(self, A: PETSc.Mat, bcs: list) -> None:
        """A <- consistent tangent of the last update (identity on Dirichlet rows). Collective."""
        A.zeroEntries()
        fem.petsc.assemble_matrix(A, self.tangent_form, bcs=bcs)
        A.assemble()

    def create_tangent(self, bcs: list) -> PETSc.Mat:
        A = fem.petsc.assemble_matrix(self.tangent_form, bcs=bcs)
        A.assemble()
        return A

    # Output -------------------------------------------------------------------------------------------
    def cell_average(self, values: np.ndarray) -> np.ndarray:
        """Average of per-point values over each owned cell."""
        return values.reshape(self.cells.size, self.nq).mean(axis=1)

    def von_mises(self, sigma: np.ndarray | None = None) -> np.ndarray:
        from .materials import von_mises

        return von_mises(self.sigma if sigma is None else sigma)


class NewtonError(RuntimeError):
    """A Newton loop did not converge; the message gives the iteration norms."""


class ElastoplasticBody:
    """Newton-Raphson on the equilibrium of a J2 body with the contact solve inside each iteration
    (paper Fig. 4). Collective.

    Iteration i from the displacement u_i (residual R_i = F_int(u_i) - s f, f the unit face load):

        u_pred = u_i - K^-1 R_i,   local problem on W = H K^-1 H^T with q_body = H u_pred -> r,
        u_{i+1} = u_pred + K^-1 H^T r,

    converged when the out-of-balance force ||F_int - s f - H^T r|| <= delta_1 * (force scale) and the
    last correction ||u_{i+1} - u_i|| <= delta_2 * ||u_{i+1} - u_start|| (the first iteration of an
    increment that stays elastic is exact: only delta_1 is asked of it). ``K`` is the elastic stiffness
    with its one factorisation and W (``tangent = "elastic"``, the initial-stiffness method: no
    refactorisation), or the consistent tangent refactorised with W rebuilt every iteration
    (``"consistent"``, full Newton), or the last factorised matrix kept while it contracts the residual
by 10x an iteration and the consistent tangent refactorised when it does not (``"adaptive"``: in shaken-down
cycles most increments need no refactorisation). The wear gap is held fixed during the loop (the caller updates it
    after convergence), and the plastic state is committed by the caller only after convergence.

    Args:
        problem: The elastic problem (space, K, Dirichlet conditions, its factorisation and W).
        law: The J2 material.
        H: Contact operator (replicated, global dofs).
        W: Delassus matrix of the elastic K.
        face_load: Load vector of a unit face pressure, or None.
        tangent: ``"elastic"`` or ``"consistent"``.
        max_iter, delta_1, delta_2: Newton settings.
    """

    def __init__(self, problem, law: J2Plasticity, H, W: np.ndarray, face_load: PETSc.Vec | None,
                 tangent: str = "elastic", max_iter: int = 50, delta_1: float = 1e-8, delta_2: float = 1e-8,
                 quadrature_degree: int = 2, elastic_cells: np.ndarray | None = None):
        from mpi4py import MPI

        self.MPI = MPI
        self.problem = problem
        self.comm = problem.comm
        self.H = H.tocsr()
        self.HT = self.H.T.tocsr()
        self.W_elastic = W
        self.face_load = face_load
        self.tangent = tangent
        self.max_iter = max_iter
        self.delta_1 = delta_1
        self.delta_2 = delta_2
        self.state = PlasticState(problem.V, law, quadrature_degree, elastic_cells)
        V = problem.V
        self.u = fem.Function(V, name="displacement")        # committed
        self._trial = fem.Function(V)
        self._work = (fem.Function(V), fem.Function(V))  # u_pred and the contact correction, reused
        self._rhs = problem.K.createVecRight()
        self._z = problem.K.createVecRight()
        self._fint = dfx.vector_for_form(self.state.residual_form)
        self.rstart, self.rend = self._rhs.getOwnershipRange()
        self._HS = self.H[:, self.rstart:self.rend].tocsr()
        self._tangent_op = None
        self._KT = None
        self._W_tangent = None
        #: Adaptive tangent: refactorise when an iteration reduces delta_1 by less than this factor.
        self.contraction = 0.1
        self.refactorizations = 0
        self.last_info: dict = {}

    # Linear algebra helpers ---------------------------------------------------------------------------
    def _H_dot(self, u: fem.Function) -> np.ndarray:
        n = self.rend - self.rstart
        return self.comm.allreduce(self._HS @ u.x.array[:n], op=self.MPI.SUM)

    def _solve_into(self, op, b: PETSc.Vec, out: fem.Function) -> None:
        op.solve(b, dfx.petsc_vec(out))
        out.x.scatter_forward()

    def _residual(self, u: fem.Function, pressure: float) -> PETSc.Vec:
        """R = F_int(u) - s f into self._rhs (non-ghosted, Dirichlet rows 0); updates the trial state."""
        self.state.update(u)
        self.state.assemble_residual(self._fint, self.problem.bcs)
        n = self.rend - self.rstart
        self._rhs.getArray()[:] = self._fint.getArray(readonly=True)[:n]
        if self.face_load is not None and pressure != 0.0:
            self._rhs.axpy(-pressure, self.face_load)
        return self._rhs

    def _contact_force(self, r: np.ndarray) -> np.ndarray:
        return (self.HT @ r)[self.rstart:self.rend]

    @property
    def tangent(self) -> str:
        return self._tangent_mode

    @tangent.setter
    def tangent(self, mode: str) -> None:
        if mode not in ("elastic", "consistent", "adaptive"):
            raise ValueError(f"solver.newton_tangent = {mode!r}: allowed 'elastic', 'consistent', 'adaptive'")
        self._tangent_mode = mode

    def _operator(self, refresh: bool):
        """(factorised operator, W) of the iteration matrix; ``refresh``: refactorise the current tangent."""
        if self.tangent == "elastic" or ((self._KT is None or self._W_tangent is None) and not refresh):
            return self.problem.delassus, self.W_elastic
        if self.tangent == "consistent" and not refresh:
            return self.problem.delassus, self.W_elastic
        if not refresh:
            return self._tangent_op, self._W_tangent
        from .compliance import DelassusOperator

        if self._KT is None:
            self._KT = self.state.create_tangent(self.problem.bcs)
            self._tangent_op = DelassusOperator(self._KT, self.comm, method="auto",
                                                options_prefix="dolfinx_fretting_tangent_")
            self._tangent_op.factorize()
        else:
            self.state.assemble_tangent(self._KT, self.problem.bcs)
            self._tangent_op.refactorize()
        W = self._tangent_op.build(self.H)
        self._W_tangent = self.comm.bcast(W if self.comm.rank == 0 else None, root=0)
        self.refactorizations += 1
        return self._tangent_op, self._W_tangent

    # The increment ------------------------------------------------------------------------------------
    def increment(self, local_solve, pressure: float) -> tuple:
        """Newton loop of one increment from the committed state.

        Args:
            local_solve: ``local_solve(q_body, W) -> IncrementResult`` (the contact solve with its load control;
                its ``forces`` enter the equilibrium; called on every rank with identical input; must raise on
                failure).
            pressure: Face pressure of the increment.

        Returns:
            (the contact solution of the last iteration, info with iterations and norms).

        Raises:
            NewtonError: no convergence within ``max_iter`` or non-finite norms (nothing committed).
        """
        u_i = self._trial
        u_i.x.array[:] = self.u.x.array
        history = []
        solved = None
        R = self._residual(u_i, pressure)
        n = self.rend - self.rstart
        # The first iteration is the elastic predictor (the exact tangent of an increment that stays
        # elastic: one iteration, no refactorisation); "consistent" refactorises from the second on.
        refresh = False
        refreshed_at = -1
        for it in range(self.max_iter):
            op, W = self._operator(refresh)
            if refresh:
                refreshed_at = it
            # u_pred = u_i - K^-1 R
            z = self._work[0]
            self._solve_into(op, R, z)
            u_pred = z
            u_pred.x.array[:] = u_i.x.array - z.x.array
            solved = local_solve(self._H_dot(u_pred), W)
            # u_new = u_pred + K^-1 H^T r
            self._z.getArray()[:] = self._contact_force(solved.forces)
            dfx.set_bc(self._z, self.problem.bcs, scale=0.0)
            c = self._work[1]
            self._solve_into(op, self._z, c)
            u_new = c
            u_new.x.array[:] = u_pred.x.array + c.x.array
            du = u_new.x.array[:n] - u_i.x.array[:n]
            R = self._residual(u_new, pressure)
            out_of_balance = R.getArray(readonly=True) - self._contact_force(solved.forces)
            sums = np.array([out_of_balance @ out_of_balance, du @ du,
                             np.sum((u_new.x.array[:n] - self.u.x.array[:n]) ** 2),
                             self._z.getArray(readonly=True) @ self._z.getArray(readonly=True),
                             float(self.state.yielded.sum()),
                             R.getArray(readonly=True) @ R.getArray(readonly=True)])
            sums = self.comm.allreduce(sums, op=self.MPI.SUM)
            res, dun, incn, fc = np.sqrt(sums[:4])
            # Force scale: contact forces, face load, or the internal forces (R ~ F_int when both vanish).
            fscale = max(fc, abs(pressure) * self._face_norm(), math.sqrt(sums[5]), 1e-300)
            d1 = res / fscale
            d2 = dun / max(incn, 1e-300)
            history.append((it + 1, d1, d2, int(sums[4])))
            u_i.x.array[:] = u_new.x.array
            if not (np.isfinite(d1) and np.isfinite(d2)):
                break
            if d1 <= self.delta_1 and (it == 0 or d2 <= self.delta_2):
                self.last_info = {"newton_iterations": it + 1, "delta_1": d1, "delta_2": d2,
                                  "yielded_points": int(sums[4])}
                return solved, self.last_info
            # Which matrix next: "consistent" refactorises every iteration; "adaptive" keeps the last
            # factorised matrix (elastic K at first) while it contracts the residual fast enough, and
            # refactorises the consistent tangent when it does not (at most once per iteration).
            if self.tangent == "consistent":
                refresh = True
            elif self.tangent == "adaptive":
                slow = len(history) >= 2 and history[-1][1] > self.contraction * history[-2][1]
                refresh = (slow or (it == 0 and d1 > 1e3 * self.delta_1)) and refreshed_at != it
            else:
                refresh = False
        self._W_tangent = None  # a failed try's tangent is no start for the next one: back to elastic K
        table = "; ".join(f"it {i}: delta_1 = {a:.2e}, delta_2 = {b:.2e}, {y} yielded points"
                          for i, a, b, y in history[-5:])
        raise NewtonError(f"Newton did not converge in {len(history)} iterations (tolerances delta_1 = "
                          f"{self.delta_1:g}, delta_2 = {self.delta_2:g}); last: {table}")

    def _face_norm(self) -> float:
        if self.face_load is None:
            return 0.0
        if not hasattr(self, "_fnorm"):
            self._fnorm = self.face_load.norm()
        return self._fnorm

    def commit(self) -> None:
        """The last increment converged: its displacement and plastic state become history."""
        self.u.x.array[:] = self._trial.x.array
        self.state.commit()

    def destroy(self) -> None:
        for obj in (self._rhs, self._z, self._fint):
            obj.destroy()
        if self._tangent_op is not None:
            self._tangent_op.destroy()
        if self._KT is not None:
            self._KT.destroy()
